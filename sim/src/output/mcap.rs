//! `run.mcap`: a run or a drive as ROS 2 messages (CDR, `ros2msg` schemas), which `ros2 bag
//! play`, Foxglove and the Python `mcap-ros2-support` reader open.
//!
//! | topic | type | when | frame |
//! |---|---|---|---|
//! | `/tf_static` | `tf2_msgs/TFMessage` | at 0 | `base_link` → `laser` (fixed mount) or `tilt_link` → `laser`; `base_link` → `sonar_N` |
//! | `/scan` | `sensor_msgs/LaserScan` | each scan, at its measurement | `laser` (no return: +inf, REP-117) |
//! | `/odom` | `nav_msgs/Odometry` | each scan | `odom` → `base_link` |
//! | `/tf` | `tf2_msgs/TFMessage` | each scan | `odom` → `base_link`; `map` → `odom` (the twin's truth); `base_link` → `pan_link` → `tilt_link` (the head's angles) |
//! | `/ground_truth` | `geometry_msgs/PoseStamped` | each scan (twin) | `map` |
//! | `/estimate` | `geometry_msgs/PoseStamped` | each placed scan | `map` |
//! | `/sonar/N` | `sensor_msgs/Range` | the ring's reading | `sonar_N` (no echo: +inf) |
//! | `/points` | `sensor_msgs/PointCloud2` | at the end, when the run built a 3D model | `map` (or `odom` when placed by odometry) |
//! | `/clock` | `rosgraph_msgs/Clock` | each scan | |
//! | `/rosout` | `rcl_interfaces/Log` | each serial link event (a drive) | |
//! | `/hardware/tape` | `std_msgs/String` | every call through the hardware contract and its answer, as JSON | |
//!
//! Frames follow REP-105: `odom` starts at the start pose, so the twin's odometry (world frame,
//! starting at the start pose) is `odom` → `base_link` as it is, and the truth enters only as
//! `map` → `odom`. Every stamp is the robot's time (simulated in the twin).

use crate::record::{Placement, SonarRecord};
use robot::hardware::{HeadAngles, LaserScan, SPEED_OF_SOUND, echo_distance_m};
use robot::logs::mcap::Recorder;
use robot::logs::ros2::{
    ClockMsg, Encoded, Header, LaserScanMsg, LogMsg, OdometryMsg, PointCloudMsg, PoseStampedMsg,
    RangeMsg, TfMessage, Transform, TransformStamped,
};
use robot::mount::LaserMount;
use robot::{Pose2, Stamp};
use std::path::Path;

/// One scan with the poses beside it.
#[derive(Copy, Clone, Debug)]
pub struct RecordedScan<'a> {
    /// The scan as the robot received it.
    pub scan: &'a LaserScan,
    /// The odometry at its stamp (the `odom` frame).
    pub odometry: Pose2,
    /// The true pose at its stamp, in the twin.
    pub truth: Option<Pose2>,
}

/// Everything a recording holds.
#[derive(Clone, Debug)]
pub struct Recording<'a> {
    /// Where the laser sits on the base.
    pub mount: LaserMount,
    /// Time between scans, seconds (the LaserScan's `scan_time`).
    pub scan_time_s: f64,
    /// The scans, in order.
    pub scans: Vec<RecordedScan<'a>>,
    /// The scan-matching estimate (map frame).
    pub estimate: Vec<(Stamp, Pose2)>,
    /// The sonar ring's reading, with its transducers' range limits, metres.
    pub sonar: Option<(&'a SonarRecord, [f64; 2])>,
    /// The 3D model's points and how they were placed, at the end.
    pub points: Option<(Placement, &'a [[f32; 3]])>,
    /// Serial link events: stamp, device, what happened.
    pub link_events: Vec<(Stamp, String, String)>,
    /// The controller's calls through the hardware contract and their answers, for a replay.
    pub tape: &'a [robot::replay::Exchange],
    /// The same as JSON, one string per exchange, when already written (else written here).
    pub tape_json: Option<&'a [String]>,
}

/// Writes `recording` to `path`; returns the number of messages written.
pub fn write_mcap(path: &Path, recording: &Recording) -> std::io::Result<u32> {
    write(path, recording).map_err(std::io::Error::other)
}

fn stamped(stamp: Stamp, parent: &str, child: &str, transform: Transform) -> TransformStamped {
    TransformStamped {
        header: Header::new(stamp, parent),
        child_frame_id: child.to_string(),
        transform,
    }
}

/// The head's joints as two transforms: the pan about z at the pan axis, the tilt about y.
pub fn head_transforms(
    mount: &LaserMount,
    stamp: Stamp,
    head: HeadAngles,
) -> Vec<TransformStamped> {
    let LaserMount::Head(g) = mount else {
        return Vec::new();
    };
    let (sp, cp) = (head.pan / 2.0).sin_cos();
    let pan = Transform {
        translation: g.axis,
        rotation: [0.0, 0.0, sp, cp],
    };
    // REP-103 pitch is positive nose-down: a tilt up turns about y by −tilt.
    let (st, ct) = (-head.tilt / 2.0).sin_cos();
    let tilt = Transform {
        translation: [0.0; 3],
        rotation: [0.0, st, 0.0, ct],
    };
    vec![
        stamped(stamp, "base_link", "pan_link", pan),
        stamped(stamp, "pan_link", "tilt_link", tilt),
    ]
}

fn pose_msg(stamp: Stamp, frame: &str, pose: Pose2) -> PoseStampedMsg {
    PoseStampedMsg {
        header: Header::new(stamp, frame),
        pose: Transform::planar(pose),
    }
}

/// `/tf_static`: the laser on the base (fixed) or on the head's tilting plate, and the sonar
/// transducers on the base.
pub fn static_transforms(mount: &LaserMount, transducers: &[Pose2]) -> TfMessage {
    let mut statics = match *mount {
        LaserMount::Fixed { pose, z } => vec![stamped(
            Stamp::ZERO,
            "base_link",
            "laser",
            Transform {
                translation: [pose.x, pose.y, z],
                rotation: pose.quaternion(),
            },
        )],
        LaserMount::Head(g) => vec![stamped(
            Stamp::ZERO,
            "tilt_link",
            "laser",
            Transform {
                translation: [g.laser_forward, 0.0, g.laser_up],
                rotation: [0.0, 0.0, 0.0, 1.0],
            },
        )],
    };
    for (n, p) in transducers.iter().enumerate() {
        statics.push(stamped(
            Stamp::ZERO,
            "base_link",
            &format!("sonar_{n}"),
            Transform::planar(*p),
        ));
    }
    TfMessage(statics)
}

/// `/estimate`: the scan-matching pose in the map.
pub fn estimate_msg(at: Stamp, pose: Pose2) -> PoseStampedMsg {
    pose_msg(at, "map", pose)
}

/// What one scan puts on the topics, all stamped at its measurement: `/clock`, `/tf`, `/odom`,
/// `/ground_truth` (when known) and `/scan`.
pub fn scan_topics(
    s: &RecordedScan,
    mount: &LaserMount,
    scan_time_s: f64,
) -> Vec<(&'static str, Encoded)> {
    let t = s.scan.stamp;
    let mut tf = vec![stamped(
        t,
        "odom",
        "base_link",
        Transform::planar(s.odometry),
    )];
    if let Some(truth) = s.truth {
        tf.push(stamped(
            t,
            "map",
            "odom",
            Transform::planar(truth.compose(&s.odometry.inverse())),
        ));
    }
    if let Some(head) = s.scan.head {
        tf.extend(head_transforms(mount, t, head));
    }
    let mut out = vec![
        ("/clock", Encoded::of(&ClockMsg(t))),
        ("/tf", Encoded::of(&TfMessage(tf))),
        (
            "/odom",
            Encoded::of(&OdometryMsg {
                header: Header::new(t, "odom"),
                child_frame_id: "base_link".into(),
                pose: Transform::planar(s.odometry),
                pose_covariance: [0.0; 36],
                linear: [0.0; 3],
                angular: [0.0; 3],
                twist_covariance: [0.0; 36],
            }),
        ),
    ];
    if let Some(truth) = s.truth {
        out.push(("/ground_truth", Encoded::of(&pose_msg(t, "map", truth))));
    }
    out.push(("/scan", Encoded::of(&scan_msg(s.scan, scan_time_s))));
    out
}

fn write(path: &Path, r: &Recording) -> Result<u32, robot::logs::mcap::RecordError> {
    let mut rec = Recorder::create(path)?;
    let transducers = r.sonar.map_or(&[][..], |(s, _)| s.transducers.as_slice());
    rec.write(
        "/tf_static",
        Stamp::ZERO,
        &static_transforms(&r.mount, transducers),
    )?;
    // Scans with the poses at their stamps, and the estimate, in time order.
    let mut estimate = r.estimate.iter().peekable();
    let mut last = Stamp::ZERO;
    for s in &r.scans {
        let t = s.scan.stamp;
        while let Some((at, pose)) = estimate.next_if(|(at, _)| *at < t) {
            rec.write("/estimate", *at, &estimate_msg(*at, *pose))?;
        }
        for (topic, msg) in scan_topics(s, &r.mount, r.scan_time_s) {
            rec.write_encoded(topic, t, &msg)?;
        }
        last = last.max(t);
    }
    for (at, pose) in estimate {
        rec.write("/estimate", *at, &estimate_msg(*at, *pose))?;
        last = last.max(*at);
    }
    if let Some((sonar, [min, max])) = r.sonar {
        let e = &sonar.echoes;
        for i in 0..e.times.len() {
            let n = e.sequence[i];
            let at = e.measured[i].unwrap_or(e.stamp);
            let range =
                echo_distance_m(e.times[i], SPEED_OF_SOUND).map_or(f32::INFINITY, |d| d as f32);
            rec.write(
                &format!("/sonar/{n}"),
                at,
                &RangeMsg {
                    header: Header::new(at, &format!("sonar_{n}")),
                    radiation_type: RangeMsg::ULTRASOUND,
                    field_of_view: sonar.cone as f32,
                    min_range: min as f32,
                    max_range: max as f32,
                    range,
                    variance: 0.0,
                },
            )?;
        }
    }
    if let Some((placement, points)) = r.points {
        let frame = if placement == Placement::Odometry {
            "odom"
        } else {
            "map"
        };
        rec.write(
            "/points",
            last,
            &PointCloudMsg {
                header: Header::new(last, frame),
                points: points.to_vec(),
            },
        )?;
    }
    for (at, device, what) in &r.link_events {
        rec.write(
            "/rosout",
            *at,
            &LogMsg {
                stamp: *at,
                level: LogMsg::WARN,
                name: device.clone(),
                msg: what.clone(),
            },
        )?;
    }
    // The tape, each exchange at its answer's stamp (or the last stamp before it).
    let mut at = Stamp::ZERO;
    let written = r.tape_json.filter(|json| json.len() == r.tape.len());
    for (i, exchange) in r.tape.iter().enumerate() {
        at = exchange.stamp().map_or(at, |s| s.max(at));
        // The JSON built during the run, borrowed; built here when the run did not.
        let json: std::borrow::Cow<'_, str> = match written {
            Some(json) => json[i].as_str().into(),
            None => tape_json(exchange).into(),
        };
        rec.write(robot::logs::mcap::TAPE_TOPIC, at, &*json)?;
    }
    let n = rec.messages();
    rec.finish()?;
    Ok(n)
}

/// An exchange of the tape as `/hardware/tape` carries it.
pub(super) fn tape_json(exchange: &robot::replay::Exchange) -> String {
    serde_json::to_string(exchange).expect("an exchange serialises")
}

/// A scan of no beams: the example a live view announces `/scan` with before the first one.
pub fn no_scan() -> LaserScan {
    LaserScan {
        stamp: Stamp::ZERO,
        angle_min: 0.0,
        angle_increment: 0.0,
        range_max_mm: 0,
        ranges_mm: Vec::new(),
        head: None,
    }
}

/// A scan as `sensor_msgs/LaserScan`: metres, no return as +inf.
pub fn scan_msg(s: &LaserScan, scan_time_s: f64) -> LaserScanMsg {
    let n = s.ranges_mm.len();
    LaserScanMsg {
        header: Header::new(s.stamp, "laser"),
        angle_min: s.angle_min as f32,
        angle_max: (s.angle_min + s.angle_increment * n.saturating_sub(1) as f64) as f32,
        angle_increment: s.angle_increment as f32,
        time_increment: 0.0,
        scan_time: scan_time_s as f32,
        range_min: 0.0,
        range_max: s.range_max_m() as f32,
        ranges: s
            .ranges_mm
            .iter()
            .map(|&mm| {
                if mm >= s.range_max_mm {
                    f32::INFINITY
                } else {
                    // Rounded once, from the exact millimetres.
                    (f64::from(mm) * 1e-3) as f32
                }
            })
            .collect(),
        intensities: Vec::new(),
    }
}
