//! 002 App. C.2 RobotLogger `.log`: groups of `odometry:`, `laser-scan:` and `laser-geometry:`
//! lines, with asynchronous `odometry-result:` lines (a previous run's answers, skipped).
//!
//! ```text
//! odometry: 2011 05 19 22 22 50.728448:X,Y,θ,Vx,Vy,ω[,…]
//! laser-scan: 2011 05 19 22 22 50.728448:[n:]x1,y1,x2,y2,…
//! laser-geometry: X,Y,θ,α,β,γ
//! ```
//!
//! Metres and radians; the scan is Cartesian points in the laser frame; the geometry is the
//! laser's pose on the base. The time is a calendar date and time of day (UTC).

use super::{Cursor, LogError, LogEvent, LogFormat, RecordedLog};
use crate::geometry::Pose2;
use crate::localization::ScanPoints;
use crate::time::Stamp;

pub(super) fn parse(text: &str, file: &str) -> Result<RecordedLog, LogError> {
    let mut log = RecordedLog::new(LogFormat::RobotLogger);
    let mut geometry_known = false;
    for (index, line) in text.lines().enumerate() {
        let at = Cursor {
            file,
            line: index + 1,
        };
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let Some((kind, rest)) = line.split_once(':') else {
            log.skip(line.split_whitespace().next().unwrap_or(line));
            continue;
        };
        match kind.trim() {
            "odometry" => {
                let (stamp, values) = stamped(&at, rest)?;
                let v = csv(&at, values, "odometry value")?;
                if v.len() < 3 {
                    return Err(
                        at.error(format!("odometry needs X,Y,θ,…; found {} values", v.len()))
                    );
                }
                log.events.push(LogEvent::Odometry {
                    stamp,
                    pose: Pose2::new(v[0], v[1], crate::geometry::wrap_angle(v[2])),
                });
            }
            "laser-scan" => {
                let (stamp, values) = stamped(&at, rest)?;
                // An optional `n:` before the coordinates.
                let (announced, values) = match values.split_once(':') {
                    Some((n, tail)) => (Some(at.number(Some(n), "number of elements")?), tail),
                    None => (None, values),
                };
                let v = csv(&at, values, "laser-scan coordinate")?;
                if v.len() % 2 != 0 {
                    return Err(at.error(format!(
                        "laser-scan needs x,y pairs; found {} numbers",
                        v.len()
                    )));
                }
                if let Some(n) = announced
                    && n as usize != v.len() / 2
                    && n as usize != v.len()
                {
                    return Err(at.error(format!(
                        "laser-scan announces {n} elements but has {} points",
                        v.len() / 2
                    )));
                }
                let xy: Vec<[f64; 2]> = v.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
                let beam = (0..xy.len()).collect();
                log.events.push(LogEvent::Points {
                    stamp,
                    points: ScanPoints { xy, beam },
                });
            }
            "laser-geometry" => {
                let v = csv(&at, rest, "laser-geometry value")?;
                if v.len() < 3 {
                    return Err(at.error("laser-geometry needs X,Y,θ,α,β,γ"));
                }
                if !geometry_known {
                    log.mount = Pose2::new(v[0], v[1], v[2]);
                    geometry_known = true;
                }
            }
            other => log.skip(other),
        }
    }
    Ok(log)
}

/// Splits `YYYY MM DD hh mm ss.ssssss:rest`.
fn stamped<'t>(at: &Cursor<'_>, text: &'t str) -> Result<(Stamp, &'t str), LogError> {
    let (time, rest) = text
        .split_once(':')
        .ok_or_else(|| at.error("expected `YYYY MM DD hh mm ss.ssssss:` before the values"))?;
    let mut f = time.split_whitespace();
    let mut next = |what| at.number(f.next(), what);
    let (y, mo, d) = (next("year")?, next("month")?, next("day")?);
    let (h, mi, s) = (next("hour")?, next("minute")?, next("seconds")?);
    let valid = (1970.0..=9999.0).contains(&y)
        && (1.0..=12.0).contains(&mo)
        && (1.0..=31.0).contains(&d)
        && (0.0..24.0).contains(&h)
        && (0.0..60.0).contains(&mi)
        && (0.0..61.0).contains(&s);
    if !valid {
        return Err(at.error(format!("`{}` is not a date and time", time.trim())));
    }
    let days = days_from_civil(y as i64, mo as i64, d as i64);
    let secs = days as f64 * 86_400.0 + h * 3600.0 + mi * 60.0 + s;
    Ok((Stamp::from_secs_f64(secs), rest))
}

fn csv(at: &Cursor<'_>, text: &str, what: &str) -> Result<Vec<f64>, LogError> {
    text.split(',')
        .filter(|t| !t.trim().is_empty())
        .enumerate()
        .map(|(i, t)| at.number_named(Some(t), || format!("{what} {}", i + 1)))
        .collect()
}

/// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's algorithm).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let doy = (153 * (m + if m > 2 { -3 } else { 9 }) + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_appendix_example() {
        let text = "odometry:      2011 05 19 22 22 50.728448:0,0,0,-1.96721e-44,0,0,0\n\
                    laser-scan:    2011 05 19 22 22 50.728448:-4.7457e-08,-1.08569,6.36921e-08,0.935997\n\
                    laser-geometry: 0.03,0,0,1,1,1\n\
                    odometry-result: 2011 05 19 22 23 38.339990:0,0,-0.0348944,-4.22795e-143,0,0,-0.349066\n";
        let log = parse(text, "r.log").unwrap();
        assert_eq!((log.scans(), log.odometry_samples()), (1, 1));
        assert_eq!(log.skipped["odometry-result"], 1);
        assert_eq!(log.mount, Pose2::new(0.03, 0.0, 0.0));
        let LogEvent::Points { stamp, points } = &log.events[1] else {
            panic!()
        };
        assert_eq!(points.len(), 2);
        // 2011-05-19 22:22:50.728448 UTC.
        assert!(
            (stamp.secs_f64() - 1_305_843_770.728448).abs() < 1e-5,
            "{stamp}"
        );
    }

    #[test]
    fn malformed_lines_are_named() {
        let err = parse("laser-scan: 2011 05 19 22 22 50:1,2,3\n", "r.log")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("r.log:1:") && err.contains("pairs"),
            "{err}"
        );
        let err = parse("odometry: 2011 13 19 22 22 50:1,2,3\n", "r.log")
            .unwrap_err()
            .to_string();
        assert!(err.contains("date"), "{err}");
    }
}
