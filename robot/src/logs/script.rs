//! 002 App. C.1 `.script`: chronological `POS` and `LASER-RANGE` lines.
//!
//! ```text
//! POS sec usec: X Y Θ
//! LASER-RANGE sec usec start_angle n end_angle: d_1 … d_n
//! ```
//!
//! Distances are millimetres. The appendix's prose says radians, but its own example reads
//! `0 180 180.0` for a half-turn laser and headings such as `-214.577450`: angles are degrees,
//! and that is how they are read. The beams span `start..end` evenly and are centred on the
//! laser's x axis (as the appendix's Matlab `calc_pol2cart` does): `0 … 180` is −90° … +90°.

use super::{Cursor, LogError, LogEvent, LogFormat, RecordedLog};
use crate::geometry::Pose2;
use crate::localization::RangeScan;
use crate::time::Stamp;

/// A `.script` range at or beyond this is a no-return, metres (the SICK's 8 m/32 m modes both fit).
pub const SCRIPT_RANGE_MAX_M: f64 = 32.0;

pub(super) fn parse(text: &str, file: &str) -> Result<RecordedLog, LogError> {
    let mut log = RecordedLog::new(LogFormat::Script);
    for (index, line) in text.lines().enumerate() {
        let at = Cursor {
            file,
            line: index + 1,
        };
        let Some((head, body)) = line.split_once(':') else {
            match line.split_whitespace().next() {
                None => {}
                Some(kind @ ("POS" | "LASER-RANGE")) => {
                    return Err(at.error(format!("{kind} without the `:` before its values")));
                }
                Some(other) => log.skip(other),
            }
            continue;
        };
        let mut head_fields = head.split_whitespace();
        let kind = head_fields.next().unwrap_or_default();
        match kind {
            "POS" => {
                let stamp = stamp(&at, &mut head_fields)?;
                let mut values = body.split_whitespace();
                let x = at.number(values.next(), "X (mm)")?;
                let y = at.number(values.next(), "Y (mm)")?;
                let theta = at.number(values.next(), "Θ (degrees)")?;
                log.events.push(LogEvent::Odometry {
                    stamp,
                    pose: Pose2::new(
                        x * 1e-3,
                        y * 1e-3,
                        crate::geometry::wrap_angle(theta.to_radians()),
                    ),
                });
            }
            "LASER-RANGE" => {
                let stamp = stamp(&at, &mut head_fields)?;
                let start = at.number(head_fields.next(), "start_angle (degrees)")?;
                let n = at.number(head_fields.next(), "number of points")?;
                let end = at.number(head_fields.next(), "end_angle (degrees)")?;
                if n < 1.0 || n.fract() != 0.0 || n > 100_000.0 {
                    return Err(at.error(format!("number of points `{n}` is not a count")));
                }
                let n = n as usize;
                let ranges: Vec<f64> = body
                    .split_whitespace()
                    .enumerate()
                    .map(|(i, d)| {
                        Ok(at.number_named(Some(d), || format!("distance {}", i + 1))? * 1e-3)
                    })
                    .collect::<Result<_, LogError>>()?;
                if ranges.len() != n {
                    return Err(at.error(format!(
                        "LASER-RANGE announces {n} distances but has {}",
                        ranges.len()
                    )));
                }
                let increment = if n > 1 {
                    (end - start) / (n - 1) as f64
                } else {
                    0.0
                };
                let angle_min = -(end - start) / 2.0;
                log.events.push(LogEvent::Scan(
                    RangeScan::new(
                        angle_min.to_radians(),
                        increment.to_radians(),
                        SCRIPT_RANGE_MAX_M,
                        ranges,
                    )
                    .stamped(stamp),
                ));
            }
            other => log.skip(other),
        }
    }
    Ok(log)
}

fn stamp<'a>(
    at: &Cursor<'_>,
    fields: &mut impl Iterator<Item = &'a str>,
) -> Result<Stamp, LogError> {
    let secs = at.number(fields.next(), "seconds")?;
    let micros = at.number(fields.next(), "microseconds")?;
    if secs < 0.0 || !(0.0..1e6).contains(&micros) {
        return Err(at.error(format!(
            "time `{secs} {micros}` is not seconds and microseconds"
        )));
    }
    Ok(Stamp::from_secs_f64(secs) + std::time::Duration::from_micros(micros as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_appendix_example() {
        let text = "POS 976052857 337284: 0.000000 0.000000 -0.140850\n\
                    LASER-RANGE 976052857 337530 0 3 180.0: 1070.0 2000.0 1050.0\n\
                    POS 976055548 522255: -5088.399900 -3582.500000 -214.577450\n";
        let log = parse(text, "a.script").unwrap();
        assert_eq!((log.scans(), log.odometry_samples()), (1, 2));
        let LogEvent::Scan(scan) = &log.events[1] else {
            panic!()
        };
        assert!((scan.angle_min + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let p = scan.points();
        assert!(
            (p.xy[1][0] - 2.0).abs() < 1e-12,
            "the middle beam looks ahead: {p:?}"
        );
        let LogEvent::Odometry { pose, .. } = log.events[2] else {
            panic!()
        };
        assert!((pose.x + 5.0883999).abs() < 1e-9);
        assert!((pose.theta.to_degrees() - 145.42255).abs() < 1e-6);
    }

    #[test]
    fn wrong_counts_are_named() {
        let err = parse("LASER-RANGE 1 0 0 3 180: 1 2\n", "b.script")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("b.script:1:") && err.contains("announces 3"),
            "{err}"
        );
        let err = parse("POS 1 2 3 4\n", "b.script").unwrap_err().to_string();
        assert!(err.contains("`:`"), "{err}");
    }
}
