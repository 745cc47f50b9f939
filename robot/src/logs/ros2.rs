//! ROS 2 messages as they travel: CDR (little-endian, with its 4-byte encapsulation header) and
//! the `ros2msg` definitions MCAP files carry as schemas, so that `ros2 bag`, Foxglove and the
//! Python `mcap-ros2-support` reader decode what the twin and the robot record.
//!
//! Only the messages the project records are here, in the definitions of ROS 2 Jazzy (its
//! `sensor_msgs/Range` has `variance`). Each is written field by field in definition order with
//! CDR's alignment (every primitive aligned to its size, counted from after the encapsulation
//! header); sequences are a `u32` length then the elements, strings a `u32` length counting a
//! closing NUL. [`CdrReader`] reads the three kinds `twin map` needs from other robots' bags
//! (`LaserScan`, `Odometry`, `TFMessage`), refusing what does not fit with the field it was at.

use crate::geometry::Pose2;
use crate::time::Stamp;

/// The six-by-six covariance of a pose or a twist, row-major (x, y, z, roll, pitch, yaw).
pub type Covariance = [f64; 36];

/// A message the recorder can write: its type name, its full definition and its bytes.
pub trait Ros2Message {
    /// The type's name, `package/Name` (MCAP's schema name for `ros2msg`).
    const NAME: &'static str;
    /// The definition with every type it uses, as `ros2msg` schemas give it.
    fn definition() -> String;
    /// Writes the fields (after the encapsulation header) into `w`.
    fn encode(&self, w: &mut CdrWriter);

    /// About how many bytes the message takes in CDR: room reserved at once, so that encoding
    /// copies the fields once instead of growing the buffer as it goes.
    fn size_hint(&self) -> usize {
        256
    }

    /// The message in CDR, encapsulation header first.
    fn to_cdr(&self) -> Vec<u8> {
        let mut bytes = Vec::new();
        self.write_cdr(&mut bytes);
        bytes
    }

    /// The message in CDR into `bytes`, replacing what it held (its room is kept: a writer of
    /// many messages encodes them all into one buffer).
    fn write_cdr(&self, bytes: &mut Vec<u8>) {
        bytes.clear();
        bytes.reserve(self.size_hint());
        bytes.extend_from_slice(&ENCAPSULATION_LE);
        let mut w = CdrWriter {
            buf: std::mem::take(bytes),
        };
        self.encode(&mut w);
        *bytes = w.buf;
    }
}

/// A message already encoded, with what a channel needs to announce it: for recorders and live
/// publishers that take messages of any type.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// The type's name ([`Ros2Message::NAME`]).
    pub name: &'static str,
    /// Its definition ([`Ros2Message::definition`]).
    pub definition: fn() -> String,
    /// The message in CDR.
    pub cdr: Vec<u8>,
}

impl Encoded {
    /// `msg`, encoded.
    pub fn of<M: Ros2Message + ?Sized>(msg: &M) -> Self {
        Encoded {
            name: M::NAME,
            definition: M::definition,
            cdr: msg.to_cdr(),
        }
    }
}

/// Builds a CDR little-endian message.
#[derive(Debug)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

/// CDR_LE, no options.
const ENCAPSULATION_LE: [u8; 4] = [0, 1, 0, 0];

impl CdrWriter {
    fn align(&mut self, n: usize) {
        while !(self.buf.len() - 4).is_multiple_of(n) {
            self.buf.push(0);
        }
    }

    fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    fn len(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }

    fn string(&mut self, s: &str) {
        self.len(s.len() + 1);
        self.buf.reserve(s.len() + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    fn time(&mut self, t: Stamp) {
        let ns = t.0;
        self.i32(i32::try_from(ns / 1_000_000_000).unwrap_or(i32::MAX));
        self.u32((ns % 1_000_000_000) as u32);
    }

    fn header(&mut self, h: &Header) {
        self.time(h.stamp);
        self.string(&h.frame_id);
    }

    /// A run of doubles: aligned once, since each keeps the next aligned.
    fn f64s(&mut self, values: &[f64]) {
        self.align(8);
        self.buf.reserve(values.len() * 8);
        values
            .iter()
            .for_each(|v| self.buf.extend_from_slice(&v.to_le_bytes()));
    }

    /// A run of floats: aligned once, since each keeps the next aligned.
    fn f32s(&mut self, values: &[f32]) {
        self.align(4);
        self.buf.reserve(values.len() * 4);
        values
            .iter()
            .for_each(|v| self.buf.extend_from_slice(&v.to_le_bytes()));
    }
}

/// `std_msgs/Header`: when and in which frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// When the data were measured.
    pub stamp: Stamp,
    /// The frame they are expressed in.
    pub frame_id: String,
}

impl Header {
    /// A header at `stamp` in `frame`.
    pub fn new(stamp: Stamp, frame: &str) -> Self {
        Header {
            stamp,
            frame_id: frame.to_string(),
        }
    }
}

/// A rigid transform or a pose: translation and unit quaternion `[x, y, z, w]`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Transform {
    /// Translation, metres.
    pub translation: [f64; 3],
    /// Rotation as a unit quaternion `[x, y, z, w]`.
    pub rotation: [f64; 4],
}

impl Transform {
    /// No translation, no rotation.
    pub const IDENTITY: Transform = Transform {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };

    /// A planar pose at height zero.
    pub fn planar(p: Pose2) -> Self {
        Transform {
            translation: [p.x, p.y, 0.0],
            rotation: p.quaternion(),
        }
    }

    /// An isometry.
    pub fn from_isometry(iso: &nalgebra::Isometry3<f64>) -> Self {
        let t = iso.translation.vector;
        let q = iso.rotation.quaternion();
        Transform {
            translation: [t.x, t.y, t.z],
            rotation: [q.i, q.j, q.k, q.w],
        }
    }

    /// The planar part: position and heading about z (for a transform with no roll or pitch).
    pub fn to_planar(&self) -> Pose2 {
        let [x, y, z, w] = self.rotation;
        let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
        Pose2::new(self.translation[0], self.translation[1], yaw)
    }

    fn encode(&self, w: &mut CdrWriter) {
        w.f64s(&self.translation);
        w.f64s(&self.rotation);
    }
}

/// `sensor_msgs/LaserScan`.
#[derive(Clone, Debug, PartialEq)]
pub struct LaserScanMsg {
    /// Stamp of the first beam and the laser's frame.
    pub header: Header,
    /// Angle of the first beam, radians.
    pub angle_min: f32,
    /// Angle of the last beam, radians.
    pub angle_max: f32,
    /// Angle between beams, radians.
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest valid range, metres.
    pub range_min: f32,
    /// Longest valid range, metres.
    pub range_max: f32,
    /// Ranges, metres (REP-117: +inf when nothing came back).
    pub ranges: Vec<f32>,
    /// Intensities (none recorded).
    pub intensities: Vec<f32>,
}

impl Ros2Message for LaserScanMsg {
    const NAME: &'static str = "sensor_msgs/msg/LaserScan";
    fn definition() -> String {
        definition(
            "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n\
             float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\n\
             float32[] ranges\nfloat32[] intensities\n",
            &[HEADER, TIME],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.header(&self.header);
        for v in [
            self.angle_min,
            self.angle_max,
            self.angle_increment,
            self.time_increment,
            self.scan_time,
            self.range_min,
            self.range_max,
        ] {
            w.f32(v);
        }
        for seq in [&self.ranges, &self.intensities] {
            w.len(seq.len());
            w.f32s(seq);
        }
    }
    fn size_hint(&self) -> usize {
        96 + self.header.frame_id.len() + 4 * (self.ranges.len() + self.intensities.len())
    }
}

/// `nav_msgs/Odometry`: a pose in `header.frame_id` and a twist in `child_frame_id`.
#[derive(Clone, Debug, PartialEq)]
pub struct OdometryMsg {
    /// Stamp and the odometry frame.
    pub header: Header,
    /// The base's frame.
    pub child_frame_id: String,
    /// The base's pose.
    pub pose: Transform,
    /// Its covariance.
    pub pose_covariance: Covariance,
    /// Linear velocity in the base frame, m/s.
    pub linear: [f64; 3],
    /// Angular velocity, rad/s.
    pub angular: [f64; 3],
    /// Their covariance.
    pub twist_covariance: Covariance,
}

impl Ros2Message for OdometryMsg {
    const NAME: &'static str = "nav_msgs/msg/Odometry";
    fn definition() -> String {
        definition(
            "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n\
             geometry_msgs/TwistWithCovariance twist\n",
            &[
                HEADER,
                TIME,
                POSE_WITH_COVARIANCE,
                POSE,
                POINT,
                QUATERNION,
                TWIST_WITH_COVARIANCE,
                TWIST,
                VECTOR3,
            ],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.header(&self.header);
        w.string(&self.child_frame_id);
        self.pose.encode(w);
        w.f64s(&self.pose_covariance);
        w.f64s(&self.linear);
        w.f64s(&self.angular);
        w.f64s(&self.twist_covariance);
    }
}

/// `geometry_msgs/TransformStamped`: `child_frame_id` in `header.frame_id`.
#[derive(Clone, Debug, PartialEq)]
pub struct TransformStamped {
    /// Stamp and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// The child's pose in the parent.
    pub transform: Transform,
}

/// `tf2_msgs/TFMessage`, as `/tf` and `/tf_static` carry it.
#[derive(Clone, Debug, PartialEq)]
pub struct TfMessage(pub Vec<TransformStamped>);

impl Ros2Message for TfMessage {
    const NAME: &'static str = "tf2_msgs/msg/TFMessage";
    fn definition() -> String {
        definition(
            "geometry_msgs/TransformStamped[] transforms\n",
            &[
                TRANSFORM_STAMPED,
                HEADER,
                TIME,
                TRANSFORM,
                VECTOR3,
                QUATERNION,
            ],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.len(self.0.len());
        for t in &self.0 {
            w.header(&t.header);
            w.string(&t.child_frame_id);
            t.transform.encode(w);
        }
    }
}

/// `geometry_msgs/PoseStamped`.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseStampedMsg {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Transform,
}

impl Ros2Message for PoseStampedMsg {
    const NAME: &'static str = "geometry_msgs/msg/PoseStamped";
    fn definition() -> String {
        definition(
            "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
            &[HEADER, TIME, POSE, POINT, QUATERNION],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.header(&self.header);
        self.pose.encode(w);
    }
}

/// `sensor_msgs/Range` (Jazzy: with `variance`).
#[derive(Clone, Debug, PartialEq)]
pub struct RangeMsg {
    /// Stamp and the transducer's frame.
    pub header: Header,
    /// 0 ultrasound, 1 infrared.
    pub radiation_type: u8,
    /// Full width of the cone, radians.
    pub field_of_view: f32,
    /// Shortest valid range, metres.
    pub min_range: f32,
    /// Longest valid range, metres.
    pub max_range: f32,
    /// The range, metres (+inf: no echo).
    pub range: f32,
    /// Variance of the range, m² (0: unknown).
    pub variance: f32,
}

impl RangeMsg {
    /// `radiation_type` of a sonar.
    pub const ULTRASOUND: u8 = 0;
}

impl Ros2Message for RangeMsg {
    const NAME: &'static str = "sensor_msgs/msg/Range";
    fn definition() -> String {
        definition(
            "uint8 ULTRASOUND=0\nuint8 INFRARED=1\nstd_msgs/Header header\nuint8 radiation_type\n\
             float32 field_of_view\nfloat32 min_range\nfloat32 max_range\nfloat32 range\n\
             float32 variance\n",
            &[HEADER, TIME],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.header(&self.header);
        w.u8(self.radiation_type);
        for v in [
            self.field_of_view,
            self.min_range,
            self.max_range,
            self.range,
            self.variance,
        ] {
            w.f32(v);
        }
    }
}

/// `sensor_msgs/PointCloud2` of `x, y, z` float32 points, unordered (height 1).
#[derive(Clone, Debug, PartialEq)]
pub struct PointCloudMsg {
    /// Stamp and frame.
    pub header: Header,
    /// The points, metres.
    pub points: Vec<[f32; 3]>,
}

impl Ros2Message for PointCloudMsg {
    const NAME: &'static str = "sensor_msgs/msg/PointCloud2";
    fn definition() -> String {
        definition(
            "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\n\
             bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
            &[HEADER, TIME, POINT_FIELD],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        const FLOAT32: u8 = 7;
        w.header(&self.header);
        w.u32(1);
        w.len(self.points.len());
        w.len(3);
        for (i, name) in ["x", "y", "z"].into_iter().enumerate() {
            w.string(name);
            w.u32(4 * i as u32);
            w.u8(FLOAT32);
            w.u32(1);
        }
        w.u8(0); // little-endian
        w.u32(12);
        w.len(12 * self.points.len());
        w.len(12 * self.points.len());
        w.buf.reserve(12 * self.points.len() + 8);
        for p in &self.points {
            for v in p {
                w.buf.extend_from_slice(&v.to_le_bytes());
            }
        }
        w.u8(1); // dense: no invalid points
    }
}

/// `rosgraph_msgs/Clock`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ClockMsg(pub Stamp);

impl Ros2Message for ClockMsg {
    const NAME: &'static str = "rosgraph_msgs/msg/Clock";
    fn definition() -> String {
        definition("builtin_interfaces/Time clock\n", &[TIME])
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.time(self.0);
    }
}

/// `std_msgs/String`.
#[derive(Clone, Debug, PartialEq)]
pub struct StringMsg(pub String);

impl Ros2Message for StringMsg {
    const NAME: &'static str = "std_msgs/msg/String";
    fn definition() -> String {
        "string data\n".to_string()
    }
    fn encode(&self, w: &mut CdrWriter) {
        self.0.as_str().encode(w);
    }
    fn size_hint(&self) -> usize {
        self.0.as_str().size_hint()
    }
}

/// Borrowed text as `std_msgs/String`: the same bytes as [`StringMsg`], without a copy of the
/// text to own.
impl Ros2Message for str {
    const NAME: &'static str = StringMsg::NAME;
    fn definition() -> String {
        StringMsg::definition()
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.string(self);
    }
    fn size_hint(&self) -> usize {
        16 + self.len()
    }
}

/// `rcl_interfaces/Log`, as `/rosout` carries it: what a serial link reported.
#[derive(Clone, Debug, PartialEq)]
pub struct LogMsg {
    /// When.
    pub stamp: Stamp,
    /// Severity: 10 debug, 20 info, 30 warning, 40 error, 50 fatal.
    pub level: u8,
    /// Who reported it.
    pub name: String,
    /// What.
    pub msg: String,
}

impl LogMsg {
    /// `level` of a warning.
    pub const WARN: u8 = 30;
}

impl Ros2Message for LogMsg {
    const NAME: &'static str = "rcl_interfaces/msg/Log";
    fn definition() -> String {
        definition(
            "uint8 DEBUG=10\nuint8 INFO=20\nuint8 WARN=30\nuint8 ERROR=40\nuint8 FATAL=50\n\
             builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\n\
             string function\nuint32 line\n",
            &[TIME],
        )
    }
    fn encode(&self, w: &mut CdrWriter) {
        w.time(self.stamp);
        w.u8(self.level);
        w.string(&self.name);
        w.string(&self.msg);
        w.string("");
        w.string("");
        w.u32(0);
    }
}

// The definitions messages use, each with the name `ros2msg` schemas give it after `MSG:`.
const TIME: (&str, &str) = ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n");
const HEADER: (&str, &str) = (
    "std_msgs/Header",
    "builtin_interfaces/Time stamp\nstring frame_id\n",
);
const VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n");
const POINT: (&str, &str) = ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n");
const QUATERNION: (&str, &str) = (
    "geometry_msgs/Quaternion",
    "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
);
const POSE: (&str, &str) = (
    "geometry_msgs/Pose",
    "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
);
const POSE_WITH_COVARIANCE: (&str, &str) = (
    "geometry_msgs/PoseWithCovariance",
    "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
);
const TWIST: (&str, &str) = (
    "geometry_msgs/Twist",
    "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
);
const TWIST_WITH_COVARIANCE: (&str, &str) = (
    "geometry_msgs/TwistWithCovariance",
    "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
);
const TRANSFORM: (&str, &str) = (
    "geometry_msgs/Transform",
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
);
const TRANSFORM_STAMPED: (&str, &str) = (
    "geometry_msgs/TransformStamped",
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
);
const POINT_FIELD: (&str, &str) = (
    "sensor_msgs/PointField",
    "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\n\
     uint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n",
);

/// A message's definition followed by those of the types it uses.
fn definition(main: &str, uses: &[(&str, &str)]) -> String {
    let mut text = main.to_string();
    for (name, body) in uses {
        text.push_str(&"=".repeat(80));
        text.push_str(&format!("\nMSG: {name}\n{body}"));
    }
    text
}

/// Why a CDR message cannot be read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CdrError {
    /// The message ends inside a field.
    #[error("ends at byte {at} inside `{field}` (expected {need} more bytes)")]
    Truncated {
        /// The field being read.
        field: &'static str,
        /// Where, from the start of the message.
        at: usize,
        /// Bytes it needed.
        need: usize,
    },
    /// The encapsulation header is not CDR little-endian.
    #[error(
        "encapsulation {0:02x?}: expected CDR little-endian (00 01) — other encodings are not read"
    )]
    Encapsulation([u8; 2]),
    /// A value is not what the field allows.
    #[error("`{field}`: {message}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// What was wrong.
        message: String,
    },
}

/// Reads a CDR little-endian message field by field.
#[derive(Debug)]
pub struct CdrReader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl<'a> CdrReader<'a> {
    /// A reader of `buf`, encapsulation header first.
    pub fn new(buf: &'a [u8]) -> Result<Self, CdrError> {
        if buf.len() < 4 {
            return Err(CdrError::Truncated {
                field: "encapsulation",
                at: 0,
                need: 4 - buf.len(),
            });
        }
        if buf[0..2] != ENCAPSULATION_LE[0..2] {
            return Err(CdrError::Encapsulation([buf[0], buf[1]]));
        }
        Ok(CdrReader { buf, at: 4 })
    }

    fn take(&mut self, field: &'static str, align: usize, n: usize) -> Result<&'a [u8], CdrError> {
        while !(self.at - 4).is_multiple_of(align) {
            self.at += 1;
        }
        let end = self.at.saturating_add(n);
        if end > self.buf.len() {
            return Err(CdrError::Truncated {
                field,
                at: self.at.min(self.buf.len()),
                need: end - self.buf.len(),
            });
        }
        let bytes = &self.buf[self.at..end];
        self.at = end;
        Ok(bytes)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        let b = self.take(field, 4, 4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn f32(&mut self, field: &'static str) -> Result<f32, CdrError> {
        Ok(f32::from_bits(self.u32(field)?))
    }

    fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        let b = self.take(field, 8, 8)?;
        Ok(f64::from_le_bytes(b.try_into().expect("eight bytes")))
    }

    fn f64s<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], CdrError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(field)?;
        }
        Ok(out)
    }

    /// A sequence's length, refused when it could not fit in what is left at `size` bytes each.
    fn len(&mut self, field: &'static str, size: usize) -> Result<usize, CdrError> {
        let n = self.u32(field)? as usize;
        let left = self.buf.len() - self.at;
        if n.saturating_mul(size) > left {
            return Err(CdrError::Truncated {
                field,
                at: self.at,
                need: n.saturating_mul(size) - left,
            });
        }
        Ok(n)
    }

    fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let n = self.len(field, 1)?;
        let bytes = self.take(field, 1, n)?;
        let text = bytes.strip_suffix(&[0]).unwrap_or(bytes);
        String::from_utf8(text.to_vec()).map_err(|_| CdrError::Invalid {
            field,
            message: "not UTF-8".into(),
        })
    }

    fn time(&mut self, field: &'static str) -> Result<Stamp, CdrError> {
        let sec = self.u32(field)? as i32;
        let nanosec = self.u32(field)?;
        if sec < 0 || nanosec >= 1_000_000_000 {
            return Err(CdrError::Invalid {
                field,
                message: format!(
                    "{sec} s {nanosec} ns: expected seconds ≥ 0 and nanoseconds < 1e9"
                ),
            });
        }
        Ok(Stamp(sec as u64 * 1_000_000_000 + u64::from(nanosec)))
    }

    fn header(&mut self) -> Result<Header, CdrError> {
        Ok(Header {
            stamp: self.time("header.stamp")?,
            frame_id: self.string("header.frame_id")?,
        })
    }

    fn transform(&mut self, field: &'static str) -> Result<Transform, CdrError> {
        Ok(Transform {
            translation: self.f64s(field)?,
            rotation: self.f64s(field)?,
        })
    }

    /// A `sensor_msgs/LaserScan`.
    pub fn laser_scan(mut self) -> Result<LaserScanMsg, CdrError> {
        let header = self.header()?;
        let mut v = [0f32; 7];
        for (x, field) in v.iter_mut().zip([
            "angle_min",
            "angle_max",
            "angle_increment",
            "time_increment",
            "scan_time",
            "range_min",
            "range_max",
        ]) {
            *x = self.f32(field)?;
        }
        let mut seq = |field| -> Result<Vec<f32>, CdrError> {
            let n = self.len(field, 4)?;
            (0..n).map(|_| self.f32(field)).collect()
        };
        let ranges = seq("ranges")?;
        let intensities = seq("intensities")?;
        Ok(LaserScanMsg {
            header,
            angle_min: v[0],
            angle_max: v[1],
            angle_increment: v[2],
            time_increment: v[3],
            scan_time: v[4],
            range_min: v[5],
            range_max: v[6],
            ranges,
            intensities,
        })
    }

    /// A `nav_msgs/Odometry`.
    pub fn odometry(mut self) -> Result<OdometryMsg, CdrError> {
        Ok(OdometryMsg {
            header: self.header()?,
            child_frame_id: self.string("child_frame_id")?,
            pose: self.transform("pose.pose")?,
            pose_covariance: self.f64s("pose.covariance")?,
            linear: self.f64s("twist.twist.linear")?,
            angular: self.f64s("twist.twist.angular")?,
            twist_covariance: self.f64s("twist.covariance")?,
        })
    }

    /// A `geometry_msgs/PoseStamped`.
    pub fn pose_stamped(mut self) -> Result<PoseStampedMsg, CdrError> {
        Ok(PoseStampedMsg {
            header: self.header()?,
            pose: self.transform("pose")?,
        })
    }

    /// A `std_msgs/String`.
    pub fn string_msg(mut self) -> Result<StringMsg, CdrError> {
        Ok(StringMsg(self.string("data")?))
    }

    /// A `tf2_msgs/TFMessage`.
    pub fn tf(mut self) -> Result<TfMessage, CdrError> {
        // A transform takes at least 4 + 4 + 4 + 4 + 56 bytes.
        let n = self.len("transforms", 72)?;
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            out.push(TransformStamped {
                header: self.header()?,
                child_frame_id: self.string("transforms.child_frame_id")?,
                transform: self.transform("transforms.transform")?,
            });
        }
        Ok(TfMessage(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan() -> LaserScanMsg {
        LaserScanMsg {
            header: Header::new(Stamp(1_500_000_001), "laser"),
            angle_min: -1.5,
            angle_max: 1.5,
            angle_increment: 1.0,
            time_increment: 0.0,
            scan_time: 0.2,
            range_min: 0.0,
            range_max: 32.0,
            ranges: vec![1.0, f32::INFINITY, 2.5, 3.0],
            intensities: vec![],
        }
    }

    #[test]
    fn a_scan_reads_back_and_is_laid_out_as_cdr_says() {
        let bytes = scan().to_cdr();
        assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
        // sec, nanosec, then the frame "laser" with its NUL (length 6).
        assert_eq!(&bytes[4..8], &1i32.to_le_bytes());
        assert_eq!(&bytes[8..12], &500_000_001u32.to_le_bytes());
        assert_eq!(&bytes[12..16], &6u32.to_le_bytes());
        assert_eq!(&bytes[16..22], b"laser\0");
        // angle_min aligned to 4 after the header: offset 24 (20 from the data start).
        assert_eq!(&bytes[24..28], &(-1.5f32).to_le_bytes());
        assert_eq!(
            CdrReader::new(&bytes).unwrap().laser_scan().unwrap(),
            scan()
        );
    }

    #[test]
    fn one_buffer_encodes_each_message_as_if_alone() {
        let long = LaserScanMsg {
            ranges: (0..1000).map(|i| i as f32 * 0.01).collect(),
            ..scan()
        };
        let odom = OdometryMsg {
            header: Header::new(Stamp(3), "odom"),
            child_frame_id: "base_link".into(),
            pose: Transform::planar(Pose2::new(1.0, 2.0, 3.0)),
            pose_covariance: [0.5; 36],
            linear: [0.1, 0.2, 0.3],
            angular: [0.4, 0.5, 0.6],
            twist_covariance: [0.25; 36],
        };
        let text = "{\"call\":\"drive\"}";
        let mut buffer = Vec::new();
        long.write_cdr(&mut buffer);
        assert_eq!(buffer, long.to_cdr());
        scan().write_cdr(&mut buffer);
        assert_eq!(
            buffer,
            scan().to_cdr(),
            "nothing of the longer message is left"
        );
        odom.write_cdr(&mut buffer);
        assert_eq!(CdrReader::new(&buffer).unwrap().odometry().unwrap(), odom);
        text.write_cdr(&mut buffer);
        // Borrowed text is the same std_msgs/String as owned text.
        assert_eq!(buffer, StringMsg(text.into()).to_cdr());
        assert_eq!(<str as Ros2Message>::NAME, StringMsg::NAME);
        assert_eq!(
            CdrReader::new(&buffer).unwrap().string_msg().unwrap().0,
            text
        );
    }

    #[test]
    fn odometry_and_tf_read_back() {
        let odom = OdometryMsg {
            header: Header::new(Stamp(7), "odom"),
            child_frame_id: "base_link".into(),
            pose: Transform::planar(Pose2::new(1.0, -2.0, 0.5)),
            pose_covariance: [0.0; 36],
            linear: [0.3, 0.0, 0.0],
            angular: [0.0, 0.0, 0.1],
            twist_covariance: [0.0; 36],
        };
        let back = CdrReader::new(&odom.to_cdr()).unwrap().odometry().unwrap();
        assert_eq!(back, odom);
        let p = back.pose.to_planar();
        assert!((p.theta - 0.5).abs() < 1e-12 && (p.x - 1.0).abs() < 1e-12);
        let tf = TfMessage(vec![TransformStamped {
            header: Header::new(Stamp(9), "odom"),
            child_frame_id: "base_link".into(),
            transform: Transform::IDENTITY,
        }]);
        assert_eq!(CdrReader::new(&tf.to_cdr()).unwrap().tf().unwrap(), tf);
    }

    #[test]
    fn truncated_and_foreign_messages_are_refused_with_the_field() {
        let bytes = scan().to_cdr();
        for cut in [0, 3, 10, 30, bytes.len() - 1] {
            let result = CdrReader::new(&bytes[..cut]).and_then(|r| r.laser_scan());
            assert!(
                matches!(result, Err(CdrError::Truncated { .. })),
                "{cut}: {result:?}"
            );
        }
        let mut big = bytes.clone();
        big[1] = 0;
        assert!(matches!(
            CdrReader::new(&big),
            Err(CdrError::Encapsulation(_))
        ));
        // An absurd sequence length is refused before anything is allocated.
        let mut absurd = TfMessage(vec![]).to_cdr();
        absurd[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = CdrReader::new(&absurd).unwrap().tf().unwrap_err();
        assert!(err.to_string().contains("transforms"), "{err}");
    }

    #[test]
    fn definitions_name_every_type_they_use() {
        let d = OdometryMsg::definition();
        for used in [
            "std_msgs/Header",
            "geometry_msgs/PoseWithCovariance",
            "geometry_msgs/Quaternion",
        ] {
            assert!(d.contains(&format!("MSG: {used}\n")), "{used}");
        }
        assert!(!LaserScanMsg::definition().contains("MSG: geometry_msgs"));
    }
}
