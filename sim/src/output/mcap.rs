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
//! The messages come in the order the run's events happened: `/tf_static` first; then each
//! exchange of the tape, and each kept scan's topics after the exchanges noted before the tour
//! handed it over ([`RecordedScan::after`]; a scan not placed among them comes before the
//! tape); then `/estimate`, the sonar, `/points` and `/rosout`. A run writes the file this way
//! as it goes ([`super::ScanStream`]), the same bytes as from its record afterwards.
//!
//! Frames follow REP-105: `odom` starts at the start pose, so the twin's odometry (world frame,
//! starting at the start pose) is `odom` → `base_link` as it is, and the truth enters only as
//! `map` → `odom`. Every stamp is the robot's time (simulated in the twin).

use crate::record::{Placement, SonarRecord};
use robot::hardware::{HeadAngles, LaserScan, SPEED_OF_SOUND, echo_distance_m};
use robot::logs::mcap::{RecordError, Recorder};
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
    /// How many of the tape's exchanges were noted before the tour handed the scan over: its
    /// topics are written after them (`None`: before the tape).
    pub after: Option<usize>,
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
    let m = ScanMessages::of(s, mount, scan_time_s);
    let mut out = vec![
        ("/clock", Encoded::of(&m.clock)),
        ("/tf", Encoded::of(&m.tf)),
        ("/odom", Encoded::of(&m.odom)),
    ];
    if let Some(truth) = &m.truth {
        out.push(("/ground_truth", Encoded::of(truth)));
    }
    out.push(("/scan", Encoded::of(&m.scan)));
    out
}

/// One scan's messages (see [`scan_topics`]), not yet encoded.
struct ScanMessages {
    clock: ClockMsg,
    tf: TfMessage,
    odom: OdometryMsg,
    truth: Option<PoseStampedMsg>,
    scan: LaserScanMsg,
}

impl ScanMessages {
    fn of(s: &RecordedScan, mount: &LaserMount, scan_time_s: f64) -> Self {
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
        ScanMessages {
            clock: ClockMsg(t),
            tf: TfMessage(tf),
            odom: OdometryMsg {
                header: Header::new(t, "odom"),
                child_frame_id: "base_link".into(),
                pose: Transform::planar(s.odometry),
                pose_covariance: [0.0; 36],
                linear: [0.0; 3],
                angular: [0.0; 3],
                twist_covariance: [0.0; 36],
            },
            truth: s.truth.map(|truth| pose_msg(t, "map", truth)),
            scan: scan_msg(s.scan, scan_time_s),
        }
    }
}

fn write(path: &Path, r: &Recording) -> Result<u32, RecordError> {
    let transducers = r.sonar.map_or(&[][..], |(s, _)| s.transducers.as_slice());
    let mut m = McapStream::start(Recorder::create(path)?, r.mount, r.scan_time_s, transducers)?;
    let mut scans = r.scans.iter().peekable();
    for (i, exchange) in r.tape.iter().enumerate() {
        while let Some(s) = scans.next_if(|s| s.after.is_none_or(|n| n <= i)) {
            m.scan(s)?;
        }
        m.exchange(exchange)?;
    }
    for s in scans {
        m.scan(s)?;
    }
    m.end(r)?;
    let n = m.rec.messages();
    m.rec.finish()?;
    Ok(n)
}

/// `run.mcap` being written in its order (see the module's documentation), into `W`.
pub(crate) struct McapStream<W: std::io::Write + std::io::Seek> {
    rec: Recorder<W>,
    mount: LaserMount,
    scan_time_s: f64,
    /// The stamp of the last exchange written (one without a stamp of its own is written at it).
    tape_at: Stamp,
    /// Scans and exchanges written.
    scans: usize,
    exchanges: usize,
    /// The last stamp of a scan written.
    last: Stamp,
    /// The last exchange's JSON.
    json: Vec<u8>,
}

impl<W: std::io::Write + std::io::Seek> std::fmt::Debug for McapStream<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "McapStream({} scans, {} exchanges, {} messages)",
            self.scans,
            self.exchanges,
            self.rec.messages()
        )
    }
}

impl<W: std::io::Write + std::io::Seek> McapStream<W> {
    /// Starts the recording with `/tf_static`: the laser on `mount`, the sonar `transducers`.
    pub(crate) fn start(
        mut rec: Recorder<W>,
        mount: LaserMount,
        scan_time_s: f64,
        transducers: &[Pose2],
    ) -> Result<Self, RecordError> {
        rec.write(
            "/tf_static",
            Stamp::ZERO,
            &static_transforms(&mount, transducers),
        )?;
        Ok(McapStream {
            rec,
            mount,
            scan_time_s,
            tape_at: Stamp::ZERO,
            scans: 0,
            exchanges: 0,
            last: Stamp::ZERO,
            json: Vec::new(),
        })
    }

    /// A kept scan's topics, at its stamp (each message encoded into the recorder's one buffer,
    /// the bytes [`scan_topics`] gives).
    pub(crate) fn scan(&mut self, s: &RecordedScan) -> Result<(), RecordError> {
        let t = s.scan.stamp;
        let m = ScanMessages::of(s, &self.mount, self.scan_time_s);
        let rec = &mut self.rec;
        rec.write("/clock", t, &m.clock)?;
        rec.write("/tf", t, &m.tf)?;
        rec.write("/odom", t, &m.odom)?;
        if let Some(truth) = &m.truth {
            rec.write("/ground_truth", t, truth)?;
        }
        rec.write("/scan", t, &m.scan)?;
        self.last = self.last.max(t);
        self.scans += 1;
        Ok(())
    }

    /// An exchange of the tape, as JSON (`std_msgs/String`), at its answer's stamp (or the last
    /// stamp before it). The JSON is written through one buffer the stream keeps: no allocation
    /// an exchange once it has grown (on the stream's thread, beside the simulation's, every
    /// allocation can wait on the allocator's lock the two share).
    pub(crate) fn exchange(
        &mut self,
        exchange: &robot::replay::Exchange,
    ) -> Result<(), RecordError> {
        self.tape_at = exchange
            .stamp()
            .map_or(self.tape_at, |s| s.max(self.tape_at));
        self.exchanges += 1;
        self.json.clear();
        serde_json::to_writer(&mut self.json, exchange).expect("an exchange serialises");
        let json = std::str::from_utf8(&self.json).expect("serde_json writes UTF-8");
        self.rec
            .write(robot::logs::mcap::TAPE_TOPIC, self.tape_at, json)
    }

    /// Scans and exchanges written so far.
    pub(crate) fn written(&self) -> (usize, usize) {
        (self.scans, self.exchanges)
    }

    /// What comes after the run's events: the estimate, the sonar ring's reading, the 3D
    /// model's points and the serial link's events, from `r` (whose scans and tape were
    /// written).
    fn end(&mut self, r: &Recording) -> Result<(), RecordError> {
        let rec = &mut self.rec;
        let mut last = self.last;
        for (at, pose) in &r.estimate {
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
        Ok(())
    }

    /// Ends the recording with the rest of `r` (its scans and tape written already): the
    /// writer, the file complete.
    pub(crate) fn finish(mut self, r: &Recording) -> Result<W, RecordError> {
        self.end(r)?;
        self.rec.finish_into()
    }
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
