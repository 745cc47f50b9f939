//! The rows' pairs as plain text, for a matcher outside this project to read: the race
//! against CSM's own C code (`studies/csm-race/`, `cargo run --release --example csm_pairs`).
//!
//! One pair a line, fields separated by single spaces:
//!
//! `row pair tolerance_m tolerance_rad guess_x guess_y guess_theta truth_x truth_y truth_theta
//! angle_min angle_increment range_max n reference_ranges… current_ranges…`
//!
//! - `row` is the row's name with each whitespace character written as `_`;
//! - poses are the current laser frame in the reference laser frame (metres, radians);
//! - both scans have the same `n` beams from `angle_min`, `angle_increment` apart;
//! - a beam that returned nothing is written as `range_max` (the smaller of the two scans'),
//!   so a reader takes a range at or beyond it as no return.
//!
//! Every number is written as Rust's shortest form that reads back to the same `f64`.

use super::CaseSet;
use robot::localization::RangeScan;
use std::fmt::Write as _;
use std::io::{self, Write};

/// Writes every pair of `sets` to `out`, one a line. A pair whose two scans have different
/// beams (count, first angle or step) cannot be written in this form: the error names its row
/// and pair.
pub fn write_pairs(sets: &[CaseSet], mut out: impl Write) -> io::Result<()> {
    let mut line = String::new();
    for set in sets {
        let row = set.name.replace(char::is_whitespace, "_");
        for (pair, case) in set.cases.iter().enumerate() {
            let (reference, current) = (&case.reference, &case.current);
            if reference.ranges.len() != current.ranges.len()
                || reference.angle_min != current.angle_min
                || reference.angle_increment != current.angle_increment
            {
                return Err(io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!(
                        "row {:?}, pair {pair}: its two scans' beams differ ({} from {} rad by {} rad, and {} from {} by {}); \
                         the plain form needs one set of beams a pair",
                        set.name,
                        reference.ranges.len(),
                        reference.angle_min,
                        reference.angle_increment,
                        current.ranges.len(),
                        current.angle_min,
                        current.angle_increment
                    ),
                ));
            }
            let range_max = reference.range_max.min(current.range_max);
            line.clear();
            let (g, t) = (case.guess, case.truth);
            let _ = write!(
                line,
                "{row} {pair} {} {} {} {} {} {} {} {} {} {} {range_max} {}",
                set.tolerance_m,
                set.tolerance_rad,
                g.x,
                g.y,
                g.theta,
                t.x,
                t.y,
                t.theta,
                reference.angle_min,
                reference.angle_increment,
                reference.ranges.len()
            );
            for scan in [reference, current] {
                write_ranges(&mut line, scan, range_max);
            }
            writeln!(out, "{line}")?;
        }
    }
    out.flush()
}

/// Each of `scan`'s ranges after a space; a beam that returned nothing as `range_max`.
fn write_ranges(line: &mut String, scan: &RangeScan, range_max: f64) {
    for (i, &range) in scan.ranges.iter().enumerate() {
        let range = if scan.returned(i) && range < range_max {
            range
        } else {
            range_max
        };
        let _ = write!(line, " {range}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::matchers::{Case, standard_sets};
    use robot::Pose2;
    use std::path::Path;

    fn root() -> &'static Path {
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
    }

    /// Each line reads back to its pair: the names, the poses and every range to the bit, the
    /// no-returns as the range limit.
    #[test]
    fn the_plain_pairs_read_back_to_the_pairs() {
        let sets = standard_sets(root(), 4, 7).expect("the bundled worlds and logs load");
        let mut text = Vec::new();
        write_pairs(&sets, &mut text).expect("every standard pair has one set of beams");
        let text = String::from_utf8(text).expect("the plain form is UTF-8");
        let cases: Vec<(&CaseSet, usize, &Case)> = sets
            .iter()
            .flat_map(|s| s.cases.iter().enumerate().map(move |(k, c)| (s, k, c)))
            .collect();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), cases.len());
        let mut no_returns = 0;
        for (line, (set, pair, case)) in lines.iter().zip(&cases) {
            let fields: Vec<&str> = line.split(' ').collect();
            assert_eq!(fields[0], set.name.replace(' ', "_"));
            assert!(!fields[0].contains(' '));
            assert_eq!(fields[1].parse::<usize>().unwrap(), *pair);
            let num = |k: usize| fields[k].parse::<f64>().unwrap();
            assert_eq!((num(2), num(3)), (set.tolerance_m, set.tolerance_rad));
            assert_eq!(Pose2::new(num(4), num(5), num(6)), case.guess);
            assert_eq!(Pose2::new(num(7), num(8), num(9)), case.truth);
            assert_eq!(num(10), case.reference.angle_min);
            assert_eq!(num(11), case.reference.angle_increment);
            let range_max = num(12);
            let n: usize = fields[13].parse().unwrap();
            assert_eq!(fields.len(), 14 + 2 * n);
            for (s, scan) in [&case.reference, &case.current].into_iter().enumerate() {
                assert_eq!(scan.ranges.len(), n);
                for i in 0..n {
                    let written = num(14 + s * n + i);
                    if scan.returned(i) && scan.ranges[i] < range_max {
                        assert_eq!(written, scan.ranges[i]);
                    } else {
                        assert_eq!(written, range_max);
                        no_returns += 1;
                    }
                }
            }
        }
        // The twin's scans reach past the rooms' doors and the logs hold no-returns.
        assert!(no_returns > 0);
    }

    /// A pair whose scans were taken with different beams is refused, named by row and pair,
    /// and nothing of it is written.
    #[test]
    fn a_pair_with_two_kinds_of_beams_is_refused_by_name() {
        let mut sets = standard_sets(root(), 2, 7).expect("the bundled worlds and logs load");
        let set = &mut sets[0];
        set.cases[1].current.ranges.pop();
        let mut text = Vec::new();
        let error = write_pairs(&sets[..1], &mut text).unwrap_err();
        assert_eq!(error.kind(), io::ErrorKind::InvalidData);
        let message = error.to_string();
        assert!(
            message.contains(&format!("{:?}", sets[0].name)),
            "{message}"
        );
        assert!(message.contains("pair 1"), "{message}");
        assert_eq!(String::from_utf8(text).unwrap().lines().count(), 1);
    }
}
