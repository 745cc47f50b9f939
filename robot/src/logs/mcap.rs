//! MCAP files of ROS 2 messages: written by [`Recorder`] (the twin's runs and the real robot's
//! drives), read by [`read_mcap`] into a [`RecordedLog`] so that `twin map` maps bags from any
//! ROS 2 robot.
//!
//! Reading takes the first `sensor_msgs/LaserScan` topic (`/scan` when there are several), the
//! odometry from `nav_msgs/Odometry` or, when the bag has none, from `/tf`'s `odom` → base
//! transforms, and the laser's mount on the base from `/tf_static` (the chain of static
//! transforms from the base to the scan's frame; identity when there is none, as for a CARMEN
//! log that does not say). Chunks may be compressed with zstd or lz4 (as `ros2 bag record
//! --compression-mode` and Foxglove write them): they are decoded by Rust decoders (`ruzstd`,
//! `lz4_flex`) into a plain copy in memory, which the mcap crate then reads — its own codecs are
//! C libraries this build leaves out. The twin writes uncompressed files.

use super::{LogError, LogEvent, LogFormat, RecordedLog};
use crate::geometry::Pose2;
use crate::localization::{RangeScan, fan_within_a_turn};
use crate::logs::ros2::{CdrReader, Ros2Message, TransformStamped};
use crate::time::Stamp;
use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::path::Path;

/// Why a recording cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file cannot be created.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The MCAP writer refused.
    #[error("MCAP: {0}")]
    Mcap(#[from] mcap::McapError),
}

/// Writes ROS 2 messages into an MCAP file: one channel per topic, CDR-encoded, each message
/// logged and published at the time given (simulated or robot time, never the wall clock).
pub struct Recorder<W: Write + Seek> {
    writer: mcap::Writer<W>,
    channels: BTreeMap<String, u16>,
    sequence: u32,
    /// The message being written, encoded: one buffer for every message.
    scratch: Vec<u8>,
}

impl Recorder<std::io::BufWriter<std::fs::File>> {
    /// A recording into a new file at `path`.
    pub fn create(path: &Path) -> Result<Self, RecordError> {
        let file = super::create_file(path).map_err(|source| RecordError::Io {
            file: path.display().to_string(),
            source,
        })?;
        Recorder::new(std::io::BufWriter::with_capacity(1 << 18, file))
    }
}

impl<W: Write + Seek> Recorder<W> {
    /// A recording into `w`.
    pub fn new(w: W) -> Result<Self, RecordError> {
        let writer = mcap::WriteOptions::new()
            .compression(None)
            .profile("ros2")
            .library("robot-twin")
            .create(w)?;
        Ok(Recorder {
            writer,
            channels: BTreeMap::new(),
            sequence: 0,
            scratch: Vec::new(),
        })
    }

    /// Writes `msg` on `topic`, stamped `at` (its channel and schema added on first use).
    pub fn write<M: Ros2Message + ?Sized>(
        &mut self,
        topic: &str,
        at: Stamp,
        msg: &M,
    ) -> Result<(), RecordError> {
        let mut cdr = std::mem::take(&mut self.scratch);
        msg.write_cdr(&mut cdr);
        let written = self.write_cdr(topic, at, (M::NAME, M::definition), &cdr);
        self.scratch = cdr;
        written
    }

    /// Writes `cdr`, a message of the type named, on `topic`, stamped `at`.
    fn write_cdr(
        &mut self,
        topic: &str,
        at: Stamp,
        (name, definition): (&str, fn() -> String),
        cdr: &[u8],
    ) -> Result<(), RecordError> {
        let channel_id = match self.channels.get(topic) {
            Some(&id) => id,
            None => {
                let schema = self
                    .writer
                    .add_schema(name, "ros2msg", definition().as_bytes())?;
                let id = self
                    .writer
                    .add_channel(schema, topic, "cdr", &BTreeMap::new())?;
                self.channels.insert(topic.to_string(), id);
                id
            }
        };
        self.sequence += 1;
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time: at.0,
                publish_time: at.0,
            },
            cdr,
        )?;
        Ok(())
    }

    /// Messages written so far.
    pub fn messages(&self) -> u32 {
        self.sequence
    }

    /// Writes the summary and flushes.
    pub fn finish(self) -> Result<(), RecordError> {
        self.finish_into().map(drop)
    }

    /// Writes the summary and flushes; the writer back.
    pub fn finish_into(mut self) -> Result<W, RecordError> {
        self.writer.finish()?;
        let mut inner = self.writer.into_inner();
        inner.flush().map_err(|source| RecordError::Io {
            file: "the recording".into(),
            source,
        })?;
        Ok(inner)
    }
}

/// A file's problem, named with the file.
fn malformed(file: &str, message: String) -> LogError {
    LogError::Malformed {
        file: file.to_string(),
        line: 0,
        message,
    }
}

/// `bytes` with every compressed chunk decoded: the file itself when none is compressed, else a
/// plain copy (the same schemas, channels and messages, uncompressed chunks). A chunk in another
/// compression, one that does not decode, or one whose size is not what its header says, is an
/// error naming the file and the chunk.
pub fn plain<'a>(bytes: &'a [u8], file: &str) -> Result<std::borrow::Cow<'a, [u8]>, LogError> {
    use mcap::records::Record;
    use std::collections::BTreeSet;
    let bad = |what: String| malformed(file, what);
    let records =
        || mcap::read::LinearReader::new(bytes).map_err(|e| bad(format!("not an MCAP file ({e})")));
    // Plain and whole: read as it is. (The reader yields its error again and again once it
    // has one: stop at the first; the copy below names it.)
    let plain_and_whole = records()?
        .find_map(|r| match r {
            Ok(Record::Chunk { header, .. }) if !header.compression.is_empty() => Some(false),
            Ok(_) => None,
            Err(_) => Some(false),
        })
        .unwrap_or(true);
    if plain_and_whole {
        return Ok(std::borrow::Cow::Borrowed(bytes));
    }
    let failed = |e: mcap::McapError| bad(format!("cannot copy it uncompressed: {e}"));
    let mut writer = mcap::WriteOptions::new()
        .compression(None)
        .profile("ros2")
        .library("robot-twin")
        .create(std::io::Cursor::new(Vec::new()))
        .map_err(failed)?;
    let (mut schemas, mut channels) = (BTreeSet::new(), BTreeSet::new());
    let mut copy = |record: Record<'_>| -> Result<(), LogError> {
        match record {
            Record::Schema { header, data } if schemas.insert(header.id) => {
                writer
                    .add_schema_with_id(header.id, &header.name, &header.encoding, &data)
                    .map_err(failed)?;
            }
            Record::Channel(c) if channels.insert(c.id) => {
                writer
                    .add_channel_with_id(
                        c.id,
                        c.schema_id,
                        &c.topic,
                        &c.message_encoding,
                        &c.metadata,
                    )
                    .map_err(failed)?;
            }
            Record::Message { header, data } => {
                writer
                    .write_to_known_channel(&header, &data)
                    .map_err(failed)?;
            }
            _ => {}
        }
        Ok(())
    };
    for (n, record) in records()?.enumerate() {
        let record = record.map_err(|e| {
            bad(format!(
                "cannot read record {} (is the file cut short?): {e}",
                n + 1
            ))
        })?;
        let Record::Chunk { header, data } = record else {
            copy(record)?;
            continue;
        };
        let chunk = |what: String| bad(format!("chunk at record {}: {what}", n + 1));
        let raw = decompress(&header.compression, &data).map_err(chunk)?;
        if raw.len() as u64 != header.uncompressed_size {
            return Err(chunk(format!(
                "{} bytes once decoded, its header says {}",
                raw.len(),
                header.uncompressed_size
            )));
        }
        for inner in mcap::read::LinearReader::sans_magic(&raw) {
            copy(inner.map_err(|e| chunk(e.to_string()))?)?;
        }
    }
    writer.finish().map_err(failed)?;
    Ok(std::borrow::Cow::Owned(writer.into_inner().into_inner()))
}

/// A chunk's records decoded from `compression` (`zstd`, `lz4` or none).
fn decompress(compression: &str, data: &[u8]) -> Result<Vec<u8>, String> {
    use std::io::Read;
    let mut out = Vec::new();
    match compression {
        "" => out.extend_from_slice(data),
        "zstd" => {
            let mut decoder =
                ruzstd::decoding::StreamingDecoder::new(data).map_err(|e| format!("zstd: {e}"))?;
            decoder
                .read_to_end(&mut out)
                .map_err(|e| format!("zstd: {e}"))?;
        }
        "lz4" => {
            lz4_flex::frame::FrameDecoder::new(data)
                .read_to_end(&mut out)
                .map_err(|e| format!("lz4: {e}"))?;
        }
        other => {
            return Err(format!(
                "compressed with {other:?}: expected \"zstd\", \"lz4\" or none"
            ));
        }
    }
    Ok(out)
}

/// The messages of an MCAP file in file order, numbered from 0; one that cannot be read is an
/// error naming the file and the message. `bytes` must be [`plain`].
fn messages<'a>(
    bytes: &'a [u8],
    file: &'a str,
) -> Result<impl Iterator<Item = (usize, Result<mcap::Message<'a>, LogError>)> + 'a, LogError> {
    let stream = mcap::MessageStream::new(bytes)
        .map_err(|e| malformed(file, format!("not an MCAP file ({e})")))?;
    Ok(stream.enumerate().map(move |(n, message)| {
        (
            n,
            message.map_err(|e| malformed(file, format!("message {}: {e}", n + 1))),
        )
    }))
}

/// The base frames a bag's odometry may name.
const BASE_FRAMES: [&str; 2] = ["base_link", "base_footprint"];

/// Reads an MCAP file of ROS 2 messages (see the module's documentation).
pub fn read_mcap(bytes: &[u8], file: &str) -> Result<RecordedLog, LogError> {
    let bytes = &*plain(bytes, file)?;
    let malformed = |what: String| malformed(file, what);
    let mut log = RecordedLog::new(LogFormat::Mcap);
    let mut scan_topic: Option<String> = None;
    let mut odometry: Vec<(Stamp, Pose2)> = Vec::new();
    let mut tf_odometry: Vec<(Stamp, Pose2)> = Vec::new();
    let mut statics: BTreeMap<String, TransformStamped> = BTreeMap::new();
    let mut scans: Vec<RangeScan> = Vec::new();
    let mut scan_frame = String::new();
    for (n, message) in messages(bytes, file)? {
        let message = message?;
        let channel = &message.channel;
        let schema = channel.schema.as_ref().map(|s| s.name.as_str());
        if channel.message_encoding != "cdr" {
            log.skip(&channel.topic);
            continue;
        }
        let bad = |e: crate::logs::ros2::CdrError| {
            malformed(format!(
                "message {} on {} ({}): {e}",
                n + 1,
                channel.topic,
                schema.unwrap_or("no schema")
            ))
        };
        let reader = CdrReader::new(&message.data).map_err(bad)?;
        match schema {
            Some("sensor_msgs/msg/LaserScan") => {
                let topic = scan_topic.get_or_insert_with(|| channel.topic.clone());
                if *topic != channel.topic {
                    if channel.topic == "/scan" && scans.is_empty() {
                        *topic = channel.topic.clone();
                    } else {
                        log.skip(&channel.topic);
                        continue;
                    }
                }
                let msg = reader.laser_scan().map_err(bad)?;
                let range_max = f64::from(msg.range_max);
                let plausible = range_max > 0.0
                    && range_max < 1e4
                    && msg.angle_increment.is_finite()
                    && msg.angle_min.is_finite()
                    && fan_within_a_turn(f64::from(msg.angle_increment), msg.ranges.len());
                if !plausible {
                    return Err(malformed(format!(
                        "message {} on {}: range_max {} m, angle_min {}, angle_increment {}, {} beams: expected a positive range_max below 10 km, finite angles and beams apart within a turn",
                        n + 1,
                        channel.topic,
                        msg.range_max,
                        msg.angle_min,
                        msg.angle_increment,
                        msg.ranges.len()
                    )));
                }
                scan_frame.clone_from(&msg.header.frame_id);
                // REP-117: +inf no return, -inf too close, NaN erroneous: all "nothing here".
                let ranges = msg
                    .ranges
                    .iter()
                    .map(|&r| {
                        let r = f64::from(r);
                        if r.is_finite() && r >= 0.0 && r < range_max {
                            r
                        } else {
                            range_max
                        }
                    })
                    .collect();
                let mut scan = RangeScan::new(
                    f64::from(msg.angle_min),
                    f64::from(msg.angle_increment),
                    range_max,
                    ranges,
                );
                scan.stamp = msg.header.stamp;
                scans.push(scan);
            }
            Some("nav_msgs/msg/Odometry") => {
                let msg = reader.odometry().map_err(bad)?;
                odometry.push((msg.header.stamp, msg.pose.to_planar()));
            }
            Some("tf2_msgs/msg/TFMessage") => {
                let msg = reader.tf().map_err(bad)?;
                for t in msg.0 {
                    if channel.topic == "/tf_static" {
                        statics.insert(t.child_frame_id.clone(), t);
                    } else if t.header.frame_id == "odom"
                        && BASE_FRAMES.contains(&t.child_frame_id.as_str())
                    {
                        tf_odometry.push((t.header.stamp, t.transform.to_planar()));
                    }
                }
            }
            _ => log.skip(&channel.topic),
        }
    }
    if odometry.is_empty() {
        odometry = tf_odometry;
    }
    log.mount = static_mount(&statics, &scan_frame).unwrap_or(Pose2::IDENTITY);
    // Both streams in time order, odometry first at equal stamps (the scan then finds it).
    let mut events: Vec<(Stamp, u8, LogEvent)> = odometry
        .into_iter()
        .map(|(stamp, pose)| (stamp, 0, LogEvent::Odometry { stamp, pose }))
        .chain(scans.into_iter().map(|s| (s.stamp, 1, LogEvent::Scan(s))))
        .collect();
    events.sort_by_key(|(stamp, order, _)| (*stamp, *order));
    log.events = events.into_iter().map(|(_, _, e)| e).collect();
    if log.scans() == 0 {
        return Err(LogError::NoScans {
            file: file.to_string(),
            format: LogFormat::Mcap,
            lines: 0,
            skipped: log.skipped_lines(),
        });
    }
    Ok(log)
}

/// The topic a recording's tape of contract exchanges is on: one exchange a message, as JSON in a
/// `std_msgs/String` (so ROS 2 tools play the file and show the tape as text).
pub const TAPE_TOPIC: &str = "/hardware/tape";

/// The contract exchanges recorded in an MCAP file ([`TAPE_TOPIC`]), in order.
pub fn read_tape(bytes: &[u8], file: &str) -> Result<Vec<crate::replay::Exchange>, LogError> {
    let bytes = &*plain(bytes, file)?;
    let malformed = |what: String| malformed(file, what);
    let mut tape = Vec::new();
    for (n, message) in messages(bytes, file)? {
        let message = message?;
        if message.channel.topic != TAPE_TOPIC {
            continue;
        }
        let bad = |e: String| {
            malformed(format!(
                "message {} on {TAPE_TOPIC} (exchange {}): {e}",
                n + 1,
                tape.len()
            ))
        };
        let text = CdrReader::new(&message.data)
            .and_then(CdrReader::string_msg)
            .map_err(|e| bad(e.to_string()))?;
        let exchange = serde_json::from_str(&text.0).map_err(|e| bad(e.to_string()))?;
        tape.push(exchange);
    }
    if tape.is_empty() {
        return Err(malformed(format!(
            "no {TAPE_TOPIC} messages: a replay needs the contract's exchanges, which `twin run` and `twin drive` record"
        )));
    }
    Ok(tape)
}

/// The planar pose of `frame` on the base by the chain of static transforms, if it reaches a
/// base frame.
fn static_mount(statics: &BTreeMap<String, TransformStamped>, frame: &str) -> Option<Pose2> {
    let mut pose = Pose2::IDENTITY;
    let mut at = frame.to_string();
    for _ in 0..=statics.len() {
        if BASE_FRAMES.contains(&at.as_str()) {
            return Some(pose);
        }
        let t = statics.get(&at)?;
        pose = t.transform.to_planar().compose(&pose);
        at.clone_from(&t.header.frame_id);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::logs::ros2::{Header, LaserScanMsg, OdometryMsg, TfMessage, Transform};

    fn bag(odometry_by_tf: bool) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        let mut rec = Recorder::new(&mut out).unwrap();
        rec.write(
            "/tf_static",
            Stamp::ZERO,
            &TfMessage(vec![TransformStamped {
                header: Header::new(Stamp::ZERO, "base_link"),
                child_frame_id: "laser".into(),
                transform: Transform::planar(Pose2::new(0.1, 0.0, 0.0)),
            }]),
        )
        .unwrap();
        for k in 0..3u64 {
            let at = Stamp(k * 100_000_000);
            let pose = Pose2::new(0.1 * k as f64, 0.0, 0.0);
            if odometry_by_tf {
                rec.write(
                    "/tf",
                    at,
                    &TfMessage(vec![TransformStamped {
                        header: Header::new(at, "odom"),
                        child_frame_id: "base_link".into(),
                        transform: Transform::planar(pose),
                    }]),
                )
                .unwrap();
            } else {
                rec.write(
                    "/odom",
                    at,
                    &OdometryMsg {
                        header: Header::new(at, "odom"),
                        child_frame_id: "base_link".into(),
                        pose: Transform::planar(pose),
                        pose_covariance: [0.0; 36],
                        linear: [0.0; 3],
                        angular: [0.0; 3],
                        twist_covariance: [0.0; 36],
                    },
                )
                .unwrap();
            }
            rec.write(
                "/scan",
                at,
                &LaserScanMsg {
                    header: Header::new(at, "laser"),
                    angle_min: -1.0,
                    angle_max: 1.0,
                    angle_increment: 1.0,
                    time_increment: 0.0,
                    scan_time: 0.1,
                    range_min: 0.0,
                    range_max: 8.0,
                    ranges: vec![1.0, f32::INFINITY, f32::NAN],
                    intensities: vec![],
                },
            )
            .unwrap();
        }
        assert_eq!(rec.messages(), 7);
        rec.finish().unwrap();
        out.into_inner()
    }

    #[test]
    fn a_bag_reads_back_as_scans_odometry_and_mount() {
        for by_tf in [false, true] {
            let log = read_mcap(&bag(by_tf), "t.mcap").unwrap();
            assert_eq!((log.scans(), log.odometry_samples()), (3, 3), "{by_tf}");
            assert!((log.mount.x - 0.1).abs() < 1e-12);
            let LogEvent::Scan(s) = &log.events[1] else {
                panic!("odometry first, then its scan: {:?}", log.events[1]);
            };
            assert_eq!(s.ranges, vec![1.0, 8.0, 8.0], "no returns are the maximum");
        }
    }

    /// A scan whose beams wind round more than a turn, or stand on one bearing, is refused
    /// naming the message; a full turn with its closing beam is read.
    #[test]
    fn a_scan_that_winds_round_is_refused_by_message() {
        let one_scan = |increment: f32, beams: usize| {
            let mut out = std::io::Cursor::new(Vec::new());
            let mut rec = Recorder::new(&mut out).unwrap();
            rec.write(
                "/scan",
                Stamp::ZERO,
                &LaserScanMsg {
                    header: Header::new(Stamp::ZERO, "laser"),
                    angle_min: -3.0,
                    angle_max: 3.0,
                    angle_increment: increment,
                    time_increment: 0.0,
                    scan_time: 0.1,
                    range_min: 0.0,
                    range_max: 8.0,
                    ranges: vec![2.0; beams],
                    intensities: vec![],
                },
            )
            .unwrap();
            rec.finish().unwrap();
            read_mcap(&out.into_inner(), "w.mcap")
        };
        for (increment, beams) in [(1.0, 10), (0.0, 5), (1f32.to_radians(), 400)] {
            let err = one_scan(increment, beams).unwrap_err().to_string();
            assert!(
                err.starts_with("w.mcap") && err.contains("message 1 on /scan"),
                "{err}"
            );
            assert!(err.contains("beams apart within a turn"), "{err}");
        }
        let turn = one_scan(1f32.to_radians(), 361).unwrap();
        assert_eq!(turn.scans(), 1);
    }

    #[test]
    fn the_same_messages_give_the_same_bytes() {
        assert_eq!(bag(false), bag(false));
    }

    #[test]
    fn garbage_and_cut_files_are_refused_by_name() {
        let err = read_mcap(b"not mcap at all", "x.mcap").unwrap_err();
        assert!(err.to_string().starts_with("x.mcap"), "{err}");
        let full = bag(false);
        for cut in [8, full.len() / 2, full.len() - 10] {
            assert!(read_mcap(&full[..cut], "cut.mcap").is_err(), "{cut}");
        }
    }
}
