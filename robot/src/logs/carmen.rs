//! CARMEN logs: `FLASER` (old front laser), `ROBOTLASER1`, `ODOM`; comments and other records
//! are skipped and counted.
//!
//! ```text
//! FLASER n r_1 … r_n x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
//! ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode
//!             n r_1 … r_n m v_1 … v_m laser_x laser_y laser_theta robot_x robot_y robot_theta
//!             tv rv forward_safety side_safety turn_axis ipc_timestamp ipc_hostname logger_timestamp
//! ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
//! ```
//!
//! Ranges are metres; a reading at or beyond the maximum (81.91 m for a SICK in centimetre mode)
//! is a no-return. A log that declares `PARAM robot_front_laser_max` (the logger's usable
//! range) may write its no-returns as another value beyond that: the corrected Edmonton log
//! declares 10 m and writes 51.15 m (51.09–51.16) for no return, while 29 % of its readings lie
//! between 10 and 50 m, walls and pillars on which its scans and its corrected poses agree. So
//! the readings beyond the declared range are kept when the log's no-return value can be told
//! apart ([`no_return_from`]), and only when it cannot does the declared range end the scans
//! (as MRPT's CARMEN reader always does).
//!
//! An `FLASER` states neither its first bearing nor its beam step: like CARMEN's own reader it
//! takes the step from the SICK mode its count of readings betrays ([`flaser_increment`]) and
//! starts at −90° ([`flaser_start`]). A SICK sweeping 180° gives 181 or 361 readings (1° or
//! 0.5° apart); loggers that drop the last one write 180 or 360, whose beams are still 1° or
//! 0.5° apart.
//!
//! An `FLASER`'s `x y theta` is the laser's pose as the logger knew it, its `odom_*` fields the
//! base's odometry. They are equal in a raw log; a SLAM-corrected log states its corrected pose
//! in `x y theta` (and may keep the raw odometry in the others). The odometry becomes the log's
//! odometry samples, and the stated pose is kept beside each scan
//! ([`RecordedLog::line_poses`](super::RecordedLog::line_poses)).

use super::{Cursor, LogError, LogEvent, LogFormat, RecordedLog};
use crate::geometry::Pose2;
use crate::localization::RangeScan;
use crate::time::Stamp;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};

/// An FLASER reading at or beyond this is a no-return, metres.
pub const FLASER_RANGE_MAX_M: f64 = 81.9;

/// The bearing step of an `FLASER` of `n` readings, radians: CARMEN's
/// `carmen_laser_guess_angle_increment`. 180 or 181 readings are 1° apart, 360 or 361 are 0.5°,
/// 400 or 401 are 0.25°; any other count spreads over 180°. Spreading 180 readings over 180°
/// instead would stretch every bearing by 1/179: half a degree at the scan's ends, 9 cm sideways
/// on a wall 10 m away.
fn flaser_increment(n: usize) -> f64 {
    match n {
        180 | 181 => PI / 180.0,
        360 | 361 => PI / 360.0,
        400 | 401 => PI / 720.0,
        0 | 1 => 0.0,
        _ => PI / (n - 1) as f64,
    }
}

/// The bearing of an `FLASER`'s first reading, radians: −90°, as CARMEN's reader takes it, but
/// for the SICK's 100° sweeps (400 or 401 readings 0.25° apart), which span −50° to +50° ahead
/// of the laser. (CARMEN's reader starts those at −90° too, which turns them 40° to the right.)
fn flaser_start(n: usize) -> f64 {
    match n {
        400 | 401 => -50f64.to_radians(),
        _ => -FRAC_PI_2,
    }
}

pub(super) fn parse(text: &str, file: &str) -> Result<RecordedLog, LogError> {
    let mut log = RecordedLog::new(LogFormat::Carmen);
    let mut mount_known = false;
    // The logger's own usable range for the front laser, when it declares one.
    let mut front_max = FLASER_RANGE_MAX_M;
    // The readings at or beyond a declared range (centimetres, counted), every FLASER reading
    // counted, and the events of the FLASER scans read under a declared range.
    let mut beyond: BTreeMap<i64, usize> = BTreeMap::new();
    let mut readings = 0usize;
    let mut declared_scans = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let at = Cursor {
            file,
            line: index + 1,
        };
        let mut fields = line.split_whitespace();
        let Some(kind) = fields.next() else { continue };
        match kind {
            "FLASER" => {
                let n = count(&at, fields.next(), "number of readings")?;
                let ranges = numbers(&at, &mut fields, n, "range")?;
                let stated = pose(&at, &mut fields, "x y theta")?;
                let odom = pose(&at, &mut fields, "odom_x odom_y odom_theta")?;
                let Some(stamp) = stamp(&at, fields.next())? else {
                    log.skip(&format!("{kind} with a negative stamp"));
                    continue;
                };
                let increment = flaser_increment(n);
                readings += n;
                if front_max < FLASER_RANGE_MAX_M {
                    for &r in ranges.iter().filter(|&&r| r >= front_max && r.is_finite()) {
                        *beyond.entry((r * 100.0).round() as i64).or_default() += 1;
                    }
                    declared_scans.push(log.events.len() + 1);
                }
                log.events.push(LogEvent::Odometry { stamp, pose: odom });
                log.events.push(LogEvent::Scan(
                    RangeScan::new(flaser_start(n), increment, front_max, ranges).stamped(stamp),
                ));
                log.line_poses.insert(log.events.len() - 1, stated);
            }
            "ROBOTLASER1" => {
                let _type = at.number(fields.next(), "laser_type")?;
                let start = at.number(fields.next(), "start_angle")?;
                let _fov = at.number(fields.next(), "field_of_view")?;
                let resolution = at.number(fields.next(), "angular_resolution")?;
                let max_range = at.number(fields.next(), "maximum_range")?;
                let _accuracy = at.number(fields.next(), "accuracy")?;
                let _remission = at.number(fields.next(), "remission_mode")?;
                let n = count(&at, fields.next(), "number of readings")?;
                let ranges = numbers(&at, &mut fields, n, "range")?;
                let m = count(&at, fields.next(), "number of remissions")?;
                numbers(&at, &mut fields, m, "remission")?;
                let laser = pose(
                    &at,
                    &mut fields,
                    "laser_pose_x laser_pose_y laser_pose_theta",
                )?;
                let robot = pose(
                    &at,
                    &mut fields,
                    "robot_pose_x robot_pose_y robot_pose_theta",
                )?;
                for what in [
                    "tv",
                    "rv",
                    "forward_safety_dist",
                    "side_safety_dist",
                    "turn_axis",
                ] {
                    at.number(fields.next(), what)?;
                }
                let Some(stamp) = stamp(&at, fields.next())? else {
                    log.skip(&format!("{kind} with a negative stamp"));
                    continue;
                };
                if !mount_known {
                    log.mount = robot.relative(&laser);
                    mount_known = true;
                }
                log.events.push(LogEvent::Odometry { stamp, pose: robot });
                log.events.push(LogEvent::Scan(
                    RangeScan::new(start, resolution, max_range, ranges).stamped(stamp),
                ));
                log.line_poses.insert(log.events.len() - 1, laser);
            }
            "ODOM" => {
                let odom = pose(&at, &mut fields, "x y theta")?;
                for what in ["tv", "rv", "accel"] {
                    at.number(fields.next(), what)?;
                }
                let Some(stamp) = stamp(&at, fields.next())? else {
                    log.skip(&format!("{kind} with a negative stamp"));
                    continue;
                };
                log.events.push(LogEvent::Odometry { stamp, pose: odom });
            }
            "PARAM" if line.split_whitespace().nth(1) == Some("robot_front_laser_max") => {
                fields.next();
                let max = at.number(fields.next(), "robot_front_laser_max")?;
                if max > 0.0 {
                    front_max = max.min(FLASER_RANGE_MAX_M);
                }
                log.skip("PARAM");
            }
            _ if kind.starts_with('#') => log.skip("#"),
            other => log.skip(other),
        }
    }
    if let Some(no_return) = no_return_from(&beyond, readings) {
        for &k in &declared_scans {
            if let Some(LogEvent::Scan(scan)) = log.events.get_mut(k) {
                scan.range_max = no_return;
            }
        }
    }
    Ok(log)
}

/// The range from which a log that declares a usable range writes its no-returns, told from
/// the readings at or beyond that range (`beyond`: centimetres, counted) among all `readings`:
/// 10 cm short of the value most of them share, when it stands out as a logger's no-return
/// value written on every beam that saw nothing — at least 1 % of all readings, and ten times
/// as many as any value beyond the declared range more than 10 cm from it (Edmonton: 51.15 m on
/// 2,991 readings, 51.09–51.16 m on 3,367, no value between 10 and 50 m on more than 139).
/// `None` when no value stands out so, or when it is the SICK's own 81.91 m (already a
/// no-return): the declared range then ends the scans.
fn no_return_from(beyond: &BTreeMap<i64, usize>, readings: usize) -> Option<f64> {
    let (&code, &count) = beyond
        .iter()
        .max_by_key(|&(value, count)| (*count, *value))?;
    let others = beyond
        .iter()
        .filter(|&(value, _)| value.abs_diff(code) > 10)
        .map(|(_, &n)| n)
        .max()
        .unwrap_or(0);
    let value = code as f64 / 100.0;
    (count * 100 >= readings && count >= 10 * others && value < FLASER_RANGE_MAX_M)
        .then_some(value - 0.1)
}

fn count(at: &Cursor<'_>, text: Option<&str>, what: &str) -> Result<usize, LogError> {
    let v = at.number(text, what)?;
    if v < 0.0 || v.fract() != 0.0 || v > 100_000.0 {
        return Err(at.error(format!("{what} `{v}` is not a count of readings")));
    }
    Ok(v as usize)
}

fn numbers<'a>(
    at: &Cursor<'_>,
    fields: &mut impl Iterator<Item = &'a str>,
    n: usize,
    what: &str,
) -> Result<Vec<f64>, LogError> {
    (0..n)
        .map(|i| at.number_named(fields.next(), || format!("{what} {} of {n}", i + 1)))
        .collect()
}

fn pose<'a>(
    at: &Cursor<'_>,
    fields: &mut impl Iterator<Item = &'a str>,
    what: &str,
) -> Result<Pose2, LogError> {
    let mut names = what.split(' ');
    let mut next = || at.number(fields.next(), names.next().unwrap_or(what));
    Ok(Pose2::new(next()?, next()?, next()?))
}

/// The record's stamp, `None` when it is negative: a glitch of the logger (one `ODOM` of the
/// corrected Freiburg 101 log is stamped −2.88 s between 1077.35 s and 1077.46 s), so the record
/// is skipped and counted rather than the whole log refused.
fn stamp(at: &Cursor<'_>, text: Option<&str>) -> Result<Option<Stamp>, LogError> {
    let secs = at.number(text, "ipc_timestamp")?;
    Ok((secs >= 0.0).then(|| Stamp::from_secs_f64(secs)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flaser_odom_and_unknown_lines() {
        let text = "# a comment\nPARAM robot_x 1\nFLASER 3 1.0 81.91 2.0 0.1 0.2 0.3 0.1 0.2 0.3 1000.5 host 0.1\n\
                    ODOM 1 2 0.5 0 0 0 1001.25 host 0.2\nSYNC x\n";
        let log = parse(text, "t.clf").unwrap();
        assert_eq!(log.scans(), 1);
        assert_eq!(log.odometry_samples(), 2);
        assert_eq!(log.skipped_lines(), 3);
        let LogEvent::Scan(scan) = &log.events[1] else {
            panic!("{:?}", log.events)
        };
        assert_eq!(scan.points().len(), 2, "81.91 is a no-return");
        assert!((scan.angle_min + FRAC_PI_2).abs() < 1e-12);
        assert!((scan.angle_increment - FRAC_PI_2).abs() < 1e-12);
        assert_eq!(scan.stamp, Stamp::from_secs_f64(1000.5));
    }

    /// The first bearing and the step of an `FLASER` of `n` readings, in degrees.
    fn geometry(n: usize) -> (f64, f64) {
        let ranges = vec!["1.0"; n].join(" ");
        let log = parse(
            &format!("FLASER {n} {ranges} 0 0 0 0 0 0 1.5 host 0\n"),
            "t.clf",
        )
        .unwrap();
        let LogEvent::Scan(scan) = &log.events[1] else {
            panic!("{:?}", log.events)
        };
        (
            scan.angle_min.to_degrees(),
            scan.angle_increment.to_degrees(),
        )
    }

    #[test]
    fn an_flaser_takes_its_beam_step_from_its_count_of_readings() {
        let near =
            |(a, b): (f64, f64), (c, d): (f64, f64)| (a - c).abs() < 1e-9 && (b - d).abs() < 1e-9;
        // A SICK's 180° sweeps, with and without the last reading.
        for (n, step) in [(181, 1.0), (180, 1.0), (361, 0.5), (360, 0.5)] {
            assert!(near(geometry(n), (-90.0, step)), "{n}: {:?}", geometry(n));
        }
        // Its 100° sweeps, ahead of the laser.
        assert!(near(geometry(401), (-50.0, 0.25)), "{:?}", geometry(401));
        assert!(near(geometry(400), (-50.0, 0.25)), "{:?}", geometry(400));
        // Any other count spans 180°.
        assert!(near(geometry(91), (-90.0, 2.0)), "{:?}", geometry(91));
        assert!(near(geometry(1), (-90.0, 0.0)), "{:?}", geometry(1));
    }

    #[test]
    fn a_corrected_pose_is_kept_beside_the_raw_odometry() {
        // x y theta (corrected) differ from odom_x odom_y odom_theta (raw).
        let text = "FLASER 2 1.0 2.0 5.0 6.0 0.5 1.0 2.0 0.1 1.5 host 0\n\
                    FLASER 2 1.0 2.0 5.5 6.0 0.5 1.4 2.0 0.1 2.5 host 0\n\
                    ODOM 1.6 2.0 0.1 0 0 0 3.0 host 0\n";
        let log = parse(text, "t.clf").unwrap();
        let odometry: Vec<Pose2> = log
            .events
            .iter()
            .filter_map(|e| match e {
                LogEvent::Odometry { pose, .. } => Some(*pose),
                _ => None,
            })
            .collect();
        assert_eq!(odometry[0], Pose2::new(1.0, 2.0, 0.1), "the raw odometry");
        let stated: Vec<Pose2> = log.scans_with_logged_pose().iter().map(|s| s.1).collect();
        assert_eq!(
            stated,
            [Pose2::new(5.0, 6.0, 0.5), Pose2::new(5.5, 6.0, 0.5)]
        );
    }

    /// The scans of a log that declares `max` as its usable range, one scan a line of 10
    /// readings.
    fn declared(scans: &[[f64; 10]], max: &str) -> Vec<RangeScan> {
        let mut text = format!("PARAM robot_front_laser_max {max} nohost 0\n");
        for (k, ranges) in scans.iter().enumerate() {
            let ranges: Vec<String> = ranges.iter().map(|r| r.to_string()).collect();
            text += &format!("FLASER 10 {} 0 0 0 0 0 0 {k}.5 host 0\n", ranges.join(" "));
        }
        let log = parse(&text, "t.log").unwrap();
        log.events
            .into_iter()
            .filter_map(|e| match e {
                LogEvent::Scan(scan) => Some(scan),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn readings_beyond_a_declared_range_are_kept_when_its_no_return_stands_out() {
        // Edmonton's way: 10 m declared, no-returns written as 51.15 m (and 51.1 m), ten
        // times as often as any other value beyond 10 m.
        let nothing = 51.15;
        let scans = declared(
            &[
                [
                    2.0, 15.0, nothing, nothing, 30.5, 3.0, 51.1, nothing, nothing, 5.0,
                ],
                [
                    2.0, nothing, nothing, 49.0, 3.0, 3.5, nothing, nothing, nothing, 7.0,
                ],
                [
                    nothing, nothing, 12.0, 2.5, nothing, 3.0, nothing, nothing, 4.0, 6.0,
                ],
            ],
            "10",
        );
        let kept: Vec<usize> = scans.iter().map(|s| s.points().len()).collect();
        assert_eq!(kept, [5, 5, 5], "the far readings kept, 51.1–51.15 m not");
        assert!(scans.iter().all(|s| (s.range_max - 51.05).abs() < 1e-9));
        // No value beyond 10 m repeats: the declared range ends the scans, as before.
        let scans = declared(
            &[[2.0, 15.0, 51.15, 20.0, 30.5, 3.0, 44.0, 4.0, 12.0, 5.0]],
            "10",
        );
        assert_eq!(scans[0].points().len(), 4);
        assert_eq!(scans[0].range_max, 10.0);
        // Freiburg's way: 80.99 m declared, no-returns at the SICK's own 81.91 m.
        let scans = declared(
            &[[2.0, 81.91, 81.91, 70.0, 3.0, 3.5, 4.0, 81.91, 6.0, 7.0]],
            "80.99",
        );
        assert_eq!(scans[0].range_max, 80.99);
        assert_eq!(scans[0].points().len(), 7);
    }

    #[test]
    fn malformed_lines_are_named() {
        let err = parse("FLASER 3 1.0 2.0\n", "t.clf")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("t.clf:1:") && err.contains("range 3 of 3"),
            "{err}"
        );
        let err = parse("\n\nODOM 1 x 0 0 0 0 5 h 1\n", "t.clf")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("t.clf:3:") && err.contains("`x`"), "{err}");
        // A garbled reading is named by its place, and what was found quoted.
        let err = parse("FLASER 3 1.0 zz 2.0 0 0 0 0 0 0 5 h 1\n", "t.clf")
            .unwrap_err()
            .to_string();
        assert!(err.contains("range 2 of 3 `zz` is not a number"), "{err}");
        let err = parse("FLASER -2\n", "t.clf").unwrap_err().to_string();
        assert!(err.contains("count"), "{err}");
    }
}
