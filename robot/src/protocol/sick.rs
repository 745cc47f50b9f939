//! The SICK LMS2xx telegrams, as bytes (the LMS2xx telegram listing; thesis App. B).
//!
//! Every telegram is framed as
//!
//! ```text
//! STX 0x02 | address | length (u16 LE) | command | data … | [status] | CRC (u16 LE)
//! ```
//!
//! `length` counts the command, the data and — in the LMS's replies, whose address has bit 7 set
//! (`0x80` for the LMS at address 0) — the trailing status byte. The CRC runs over everything from
//! STX to the last byte before it ([`crc16`]). The LMS answers each request first with a single
//! byte, ACK `0x06` or NAK `0x15`, then with its reply telegram, whose command is the request's
//! with bit 7 set.
//!
//! The thesis runs the LMS at 180° and 0.5° (361 values), in millimetres with a 32 m range. In
//! that measuring mode each value's low 15 bits are the range and bit 15 is a flag: App. B's patch
//! to the Linux driver masks the high byte with `0x7f` (its prose says `0x7ff`; the code is what
//! the robot does), so ranges reach 32 767 mm.
//!
//! [`TelegramDecoder`] takes bytes as they arrive and yields ACKs, NAKs and checked telegrams; it
//! skips garbage and resynchronises on the next STX, never holding more than one telegram's worth
//! of bytes.

use crate::hardware::LaserScan;
use crate::time::Stamp;

/// Start of a telegram.
pub const STX: u8 = 0x02;
/// The LMS accepted a request.
pub const ACK: u8 = 0x06;
/// The LMS refused a request (bad CRC, unknown command).
pub const NAK: u8 = 0x15;
/// Address of telegrams sent to the LMS (address 0).
pub const TO_LMS: u8 = 0x00;
/// Address of the replies of the LMS at address 0.
pub const FROM_LMS: u8 = 0x80;
/// The longest command + data + status a telegram may carry (the listing's 812 bytes).
pub const MAX_LENGTH: usize = 812;
/// Password of the installation mode.
pub const INSTALLATION_PASSWORD: &[u8; 8] = b"SICK_LMS";

/// Request: change the operating mode (reply [`MODE_REPLY`]).
pub const SET_MODE: u8 = 0x20;
/// Request: measured values (reply [`MEASURED_VALUES`]).
pub const REQUEST_VALUES: u8 = 0x30;
/// Request: the LMS's status (reply `0xB1`).
pub const REQUEST_STATUS: u8 = 0x31;
/// Request: switch the variant, scan angle and resolution (reply [`VARIANT_REPLY`]).
pub const SET_VARIANT: u8 = 0x3B;
/// Reply to [`SET_MODE`].
pub const MODE_REPLY: u8 = 0xA0;
/// Reply to [`REQUEST_VALUES`]: the measured values.
pub const MEASURED_VALUES: u8 = 0xB0;
/// Reply to [`SET_VARIANT`].
pub const VARIANT_REPLY: u8 = 0xBB;
/// Request: the configuration (reply [`CONFIG_REPLY`]).
pub const REQUEST_CONFIG: u8 = 0x74;
/// Reply to [`REQUEST_CONFIG`]: the [`CONFIG_LENGTH`] configuration bytes.
pub const CONFIG_REPLY: u8 = 0xF4;
/// Request: write the configuration, in installation mode (reply [`SET_CONFIG_REPLY`]).
pub const SET_CONFIG: u8 = 0x77;
/// Reply to [`SET_CONFIG`]: `01` (done) or `00` (refused), then the configuration now in force.
pub const SET_CONFIG_REPLY: u8 = 0xF7;
/// Bytes of the configuration block (blocks A to A4 of the listing).
pub const CONFIG_LENGTH: usize = 34;
/// Measuring mode: 32 m range, field A in bit 15 (the mode App. B's `0x7f` mask reads).
pub const MEASURING_MODE_32M_FIELD_A: u8 = 0x06;
/// Measuring mode: 32 m range, reflector bit in bit 15.
pub const MEASURING_MODE_32M_REFLECTOR: u8 = 0x05;
/// Measured value unit: centimetres (the default).
pub const UNITS_CM: u8 = 0x00;
/// Measured value unit: millimetres (the thesis's configuration).
pub const UNITS_MM: u8 = 0x01;

/// Operating mode: monitoring, measured values sent on request (the thesis's driver polls).
pub const MODE_REQUEST_VALUES: u8 = 0x25;
/// Operating mode: monitoring, every scan's values streamed.
pub const MODE_STREAM_VALUES: u8 = 0x24;
/// Operating mode: installation (needs [`INSTALLATION_PASSWORD`]).
pub const MODE_INSTALLATION: u8 = 0x00;

/// The LMS's CRC-16 (generator `0x8005`, each step folding in the current and previous byte), as
/// the telegram listing gives it in C.
///
/// ```
/// use robot::protocol::sick::crc16;
/// // "02 00 02 00 30 01" (one scan, please) ends in CRC 31 18.
/// assert_eq!(crc16(&[0x02, 0x00, 0x02, 0x00, 0x30, 0x01]), 0x1831);
/// ```
pub fn crc16(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0;
    let mut previous: u8 = 0;
    for &byte in bytes {
        crc = if crc & 0x8000 != 0 {
            ((crc & 0x7fff) << 1) ^ 0x8005
        } else {
            crc << 1
        };
        crc ^= u16::from(byte) | (u16::from(previous) << 8);
        previous = byte;
    }
    crc
}

/// One telegram: its address, command and data (a reply's status byte is in `status`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Telegram {
    /// [`TO_LMS`] for requests, [`FROM_LMS`] for replies.
    pub address: u8,
    /// The command byte.
    pub command: u8,
    /// The data bytes.
    pub data: Vec<u8>,
    /// The status byte replies end with (`None` in requests).
    pub status: Option<u8>,
}

/// A telegram that cannot be built or read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TelegramError {
    /// Too much data for one telegram.
    #[error("telegram length {0} is over the LMS2xx maximum of {MAX_LENGTH} bytes")]
    TooLong(usize),
    /// The first byte is not STX.
    #[error("telegram starts with 0x{0:02X}, expected STX 0x02")]
    NoStart(u8),
    /// Fewer bytes than the header announces.
    #[error("telegram truncated: {got} of {expected} bytes")]
    Truncated {
        /// Bytes the header announces, framing included.
        expected: usize,
        /// Bytes present.
        got: usize,
    },
    /// The checksum does not match.
    #[error("telegram CRC is 0x{got:04X}, the bytes give 0x{expected:04X}")]
    Crc {
        /// CRC of the bytes.
        expected: u16,
        /// CRC carried by the telegram.
        got: u16,
    },
    /// A length field of zero (no command byte) or too short for a reply's status.
    #[error("telegram length {0} leaves no room for its command (and a reply's status)")]
    Empty(usize),
}

impl Telegram {
    /// A request to the LMS.
    pub fn request(command: u8, data: Vec<u8>) -> Self {
        Telegram {
            address: TO_LMS,
            command,
            data,
            status: None,
        }
    }

    /// A reply of the LMS: the request's command with bit 7 set is the caller's to give.
    pub fn reply(command: u8, data: Vec<u8>, status: u8) -> Self {
        Telegram {
            address: FROM_LMS,
            command,
            data,
            status: Some(status),
        }
    }

    /// The bytes on the wire, STX to CRC.
    pub fn encode(&self) -> Result<Vec<u8>, TelegramError> {
        let length = 1 + self.data.len() + usize::from(self.status.is_some());
        if length > MAX_LENGTH {
            return Err(TelegramError::TooLong(length));
        }
        let mut bytes = Vec::with_capacity(length + 6);
        bytes.extend([STX, self.address]);
        bytes.extend((length as u16).to_le_bytes());
        bytes.push(self.command);
        bytes.extend(&self.data);
        bytes.extend(self.status);
        let crc = crc16(&bytes);
        bytes.extend(crc.to_le_bytes());
        Ok(bytes)
    }

    /// Reads exactly one telegram from `bytes` (extra bytes after it are ignored); returns it
    /// and the number of bytes it took.
    pub fn decode(bytes: &[u8]) -> Result<(Telegram, usize), TelegramError> {
        let &first = bytes.first().ok_or(TelegramError::Truncated {
            expected: 6,
            got: 0,
        })?;
        if first != STX {
            return Err(TelegramError::NoStart(first));
        }
        if bytes.len() < 4 {
            return Err(TelegramError::Truncated {
                expected: 6,
                got: bytes.len(),
            });
        }
        let address = bytes[1];
        let length = usize::from(u16::from_le_bytes([bytes[2], bytes[3]]));
        let reply = address & 0x80 != 0;
        if length > MAX_LENGTH {
            return Err(TelegramError::TooLong(length));
        }
        if length < 1 + usize::from(reply) {
            return Err(TelegramError::Empty(length));
        }
        let total = length + 6;
        if bytes.len() < total {
            return Err(TelegramError::Truncated {
                expected: total,
                got: bytes.len(),
            });
        }
        let expected = crc16(&bytes[..total - 2]);
        let got = u16::from_le_bytes([bytes[total - 2], bytes[total - 1]]);
        if expected != got {
            return Err(TelegramError::Crc { expected, got });
        }
        let body = &bytes[5..4 + length];
        let (data, status) = if reply {
            let (data, status) = body.split_at(body.len() - 1);
            (data.to_vec(), Some(status[0]))
        } else {
            (body.to_vec(), None)
        };
        let telegram = Telegram {
            address,
            command: bytes[4],
            data,
            status,
        };
        Ok((telegram, total))
    }

    /// Requests: measured values once (`30 01`).
    pub fn request_values() -> Self {
        Telegram::request(REQUEST_VALUES, vec![0x01])
    }

    /// Requests: the operating mode `mode` (the installation mode sends its password).
    pub fn set_mode(mode: u8) -> Self {
        let mut data = vec![mode];
        if mode == MODE_INSTALLATION {
            data.extend(INSTALLATION_PASSWORD);
        }
        Telegram::request(SET_MODE, data)
    }

    /// Requests: scan angle in degrees (100 or 180) and resolution in hundredths of a degree
    /// (25, 50, 100). The thesis: 180°, 0.5° (`3B B4 00 32 00`).
    pub fn set_variant(angle_deg: u16, resolution_centideg: u16) -> Self {
        let mut data = angle_deg.to_le_bytes().to_vec();
        data.extend(resolution_centideg.to_le_bytes());
        Telegram::request(SET_VARIANT, data)
    }
}

/// The LMS's configuration block as `74` reads it and `77` writes it: blanking (block A), stop and
/// peak thresholds (B), availability (C), measuring mode (D), unit (E), then the field and
/// restart settings (F to A4), which this crate keeps as read.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct LmsConfig(pub [u8; CONFIG_LENGTH]);

/// A configuration reply that does not read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// Another telegram.
    #[error("expected a configuration reply (0x{expected:02X}), got command 0x{got:02X}")]
    NotConfig {
        /// The reply expected.
        expected: u8,
        /// The command received.
        got: u8,
    },
    /// Too few bytes.
    #[error("configuration reply with {0} data bytes, expected at least {CONFIG_LENGTH}")]
    Short(usize),
    /// The LMS refused the new configuration.
    #[error("the LMS refused the configuration (is it in installation mode?)")]
    Refused,
}

impl LmsConfig {
    /// The measuring mode (block D).
    pub fn measuring_mode(&self) -> u8 {
        self.0[5]
    }

    /// The measured value unit (block E).
    pub fn units(&self) -> u8 {
        self.0[6]
    }

    /// Whether the LMS reports millimetres over 32 m, as the thesis configured it.
    pub fn is_mm_32m(&self) -> bool {
        self.units() == UNITS_MM
            && matches!(
                self.measuring_mode(),
                MEASURING_MODE_32M_FIELD_A | MEASURING_MODE_32M_REFLECTOR
            )
    }

    /// The same configuration in millimetres over 32 m (field A mode).
    pub fn with_mm_32m(mut self) -> Self {
        self.0[5] = MEASURING_MODE_32M_FIELD_A;
        self.0[6] = UNITS_MM;
        self
    }

    /// Reads a `F4` reply (to `74`) or a `F7` reply (to `77`, refused unless its first byte is 1).
    pub fn from_reply(telegram: &Telegram) -> Result<Self, ConfigError> {
        let data = match telegram.command {
            CONFIG_REPLY => &telegram.data[..],
            SET_CONFIG_REPLY => match telegram.data.split_first() {
                Some((1, rest)) => rest,
                Some(_) => return Err(ConfigError::Refused),
                None => return Err(ConfigError::Short(0)),
            },
            got => {
                return Err(ConfigError::NotConfig {
                    expected: CONFIG_REPLY,
                    got,
                });
            }
        };
        let block = data
            .get(..CONFIG_LENGTH)
            .ok_or(ConfigError::Short(data.len()))?;
        let mut bytes = [0; CONFIG_LENGTH];
        bytes.copy_from_slice(block);
        Ok(LmsConfig(bytes))
    }
}

impl Telegram {
    /// Requests: the configuration (`74`).
    pub fn request_config() -> Self {
        Telegram::request(REQUEST_CONFIG, Vec::new())
    }

    /// Requests: write `config` (`77`, installation mode only).
    pub fn set_config(config: &LmsConfig) -> Self {
        Telegram::request(SET_CONFIG, config.0.to_vec())
    }
}

/// One thing read off the laser's line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Frame {
    /// ACK `0x06`.
    Ack,
    /// NAK `0x15`.
    Nak,
    /// A complete telegram with a good CRC.
    Telegram(Telegram),
    /// Bytes thrown away to find the next frame: garbage, or a telegram with a bad CRC or an
    /// impossible length.
    Skipped {
        /// How many bytes.
        bytes: usize,
        /// Why.
        reason: String,
    },
}

/// Turns a byte stream into [`Frame`]s: push what arrives, then take frames until `None`.
///
/// Holds at most one telegram's worth of bytes (`MAX_LENGTH + 6`) plus what the last push added.
#[derive(Clone, Debug, Default)]
pub struct TelegramDecoder {
    buffer: Vec<u8>,
}

impl TelegramDecoder {
    /// An empty decoder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buffer.extend_from_slice(bytes);
    }

    /// Bytes waiting for the rest of a telegram.
    pub fn pending(&self) -> usize {
        self.buffer.len()
    }

    /// Drops whatever is buffered (after a reconnection).
    pub fn clear(&mut self) {
        self.buffer.clear();
    }

    /// The next frame, or `None` until more bytes arrive.
    pub fn next_frame(&mut self) -> Option<Frame> {
        let &first = self.buffer.first()?;
        match first {
            ACK => {
                self.buffer.remove(0);
                return Some(Frame::Ack);
            }
            NAK => {
                self.buffer.remove(0);
                return Some(Frame::Nak);
            }
            STX => {}
            _ => {
                let garbage = self
                    .buffer
                    .iter()
                    .position(|&b| matches!(b, STX | ACK | NAK))
                    .unwrap_or(self.buffer.len());
                self.buffer.drain(..garbage);
                return Some(Frame::Skipped {
                    bytes: garbage,
                    reason: "bytes outside a telegram".into(),
                });
            }
        }
        match Telegram::decode(&self.buffer) {
            Ok((telegram, used)) => {
                self.buffer.drain(..used);
                Some(Frame::Telegram(telegram))
            }
            Err(TelegramError::Truncated { .. }) => {
                // A false start whose length field promises more than has come would hold back
                // every real telegram behind it until that many bytes arrive: if a complete one
                // with a good CRC already starts later in the buffer, the start was false.
                let later = (1..self.buffer.len()).find(|&at| {
                    self.buffer[at] == STX && Telegram::decode(&self.buffer[at..]).is_ok()
                })?;
                self.buffer.drain(..later);
                Some(Frame::Skipped {
                    bytes: later,
                    reason: "a false start: a complete telegram follows".into(),
                })
            }
            Err(error) => {
                // Not a telegram after all: drop its STX and look again from the next byte.
                self.buffer.remove(0);
                Some(Frame::Skipped {
                    bytes: 1,
                    reason: error.to_string(),
                })
            }
        }
    }
}

/// The unit of the measured values, from bits 14–15 of their count word.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum RangeUnit {
    /// Centimetres (the LMS's default, 8 m mode).
    Centimetres,
    /// Millimetres (the thesis's configuration).
    Millimetres,
}

/// A measured-values reply (`B0`) that does not read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ValuesError {
    /// Another telegram.
    #[error("expected measured values (command 0xB0), got command 0x{0:02X}")]
    NotValues(u8),
    /// The data is shorter or longer than its count says.
    #[error("measured values announce {count} values ({expected} data bytes), carry {got}")]
    Length {
        /// Values announced.
        count: usize,
        /// Data bytes they need.
        expected: usize,
        /// Data bytes present.
        got: usize,
    },
    /// Unit bits the listing leaves reserved.
    #[error("measured values with reserved unit bits {0:#04b}")]
    Unit(u8),
    /// A count of values that no variant of the LMS sends ([`lms_field`]).
    #[error(
        "measured values carry {0} values; an LMS sends 181 or 361 (180° at 1° or 0.5°) or 101, 201 or 401 (100° at 1°, 0.5° or 0.25°)"
    )]
    Field(usize),
}

/// The LMS's variants (`3B`, [`Telegram::set_variant`]) by the number of values a scan carries:
/// the count, the scan angle in degrees and the resolution in hundredths of a degree, as the
/// telegram states them. The LMS sweeps from its right, centred ahead: 180° from −90°, 100°
/// from −50°.
const LMS_VARIANTS: [(usize, u16, u16); 5] = [
    (181, 180, 100),
    (361, 180, 50),
    (101, 100, 100),
    (201, 100, 50),
    (401, 100, 25),
];

/// The variant that sends scans of `count` values: its scan angle in degrees and resolution in
/// hundredths of a degree; `None` when no variant sends that many.
pub fn lms_variant(count: usize) -> Option<(u16, u16)> {
    LMS_VARIANTS
        .iter()
        .find(|(n, _, _)| *n == count)
        .map(|&(_, angle, resolution)| (angle, resolution))
}

/// The first beam's bearing and the step, radians, of a scan of `count` values as the LMS sends
/// it ([`lms_variant`]); `None` when no variant sends that many.
pub fn lms_field(count: usize) -> Option<(f64, f64)> {
    lms_variant(count).map(|(angle, resolution)| {
        (
            (-f64::from(angle) / 2.0).to_radians(),
            (f64::from(resolution) / 100.0).to_radians(),
        )
    })
}

/// The values of one scan as the LMS sends them in the 32 m measuring mode.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeasuredValues {
    /// The unit of `ranges`.
    pub unit: RangeUnit,
    /// Ranges in `unit`, 15 bits (App. B's mask).
    pub ranges: Vec<u16>,
    /// Bit 15 of each value (the reflector / field A flag of the 32 m modes).
    pub flags: Vec<bool>,
    /// The reply's status byte (0 when all is well).
    pub status: u8,
}

impl MeasuredValues {
    /// Reads a `B0` reply.
    pub fn from_telegram(telegram: &Telegram) -> Result<Self, ValuesError> {
        if telegram.command != MEASURED_VALUES {
            return Err(ValuesError::NotValues(telegram.command));
        }
        let data = &telegram.data;
        let header = match data.get(..2) {
            Some(h) => u16::from_le_bytes([h[0], h[1]]),
            None => {
                return Err(ValuesError::Length {
                    count: 0,
                    expected: 2,
                    got: data.len(),
                });
            }
        };
        let count = usize::from(header & 0x03ff);
        let unit = match header >> 14 {
            0 => RangeUnit::Centimetres,
            1 => RangeUnit::Millimetres,
            bits => return Err(ValuesError::Unit(bits as u8)),
        };
        if data.len() != 2 + 2 * count {
            return Err(ValuesError::Length {
                count,
                expected: 2 + 2 * count,
                got: data.len(),
            });
        }
        let words = data[2..]
            .chunks_exact(2)
            .map(|w| u16::from_le_bytes([w[0], w[1]]));
        let (ranges, flags) = words.map(|w| (w & 0x7fff, w & 0x8000 != 0)).unzip();
        Ok(MeasuredValues {
            unit,
            ranges,
            flags,
            status: telegram.status.unwrap_or(0),
        })
    }

    /// The `B0` reply carrying `ranges_mm` (the twin's LMS), millimetre unit, no flags.
    pub fn telegram_mm(ranges_mm: &[u16], status: u8) -> Telegram {
        let count = ranges_mm.len().min(0x03ff) as u16;
        let mut data = (count | 0x4000).to_le_bytes().to_vec();
        for &r in &ranges_mm[..usize::from(count)] {
            data.extend((r & 0x7fff).to_le_bytes());
        }
        Telegram::reply(MEASURED_VALUES, data, status)
    }

    /// The scan in REP-103 bearings, ranges in millimetres; a value at or above `range_max_mm`
    /// is no return. The count of values gives the variant's field ([`lms_field`]): 181 or 361
    /// values span 180° from −90° (the thesis's variant), 101, 201 or 401 span 100° from −50°.
    pub fn to_scan(&self, stamp: Stamp, range_max_mm: u16) -> Result<LaserScan, ValuesError> {
        let count = self.ranges.len();
        let (angle_min, angle_increment) = lms_field(count).ok_or(ValuesError::Field(count))?;
        let scale = match self.unit {
            RangeUnit::Centimetres => 10,
            RangeUnit::Millimetres => 1,
        };
        let ranges_mm = self
            .ranges
            .iter()
            .map(|&r| r.saturating_mul(scale).min(range_max_mm))
            .collect();
        Ok(LaserScan {
            stamp,
            angle_min,
            angle_increment,
            range_max_mm,
            ranges_mm,
            head: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Golden telegrams, their CRCs computed independently of this code (a Python transcription
    /// of the listing's C routine) and matching those quoted by open LMS2xx drivers.
    const GOLDEN: [(&str, &[u8]); 6] = [
        (
            "one scan",
            &[0x02, 0x00, 0x02, 0x00, 0x30, 0x01, 0x31, 0x18],
        ),
        ("stream", &[0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08]),
        (
            "poll mode",
            &[0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08],
        ),
        (
            "180° at 0.5°",
            &[
                0x02, 0x00, 0x05, 0x00, 0x3B, 0xB4, 0x00, 0x32, 0x00, 0x3B, 0x1F,
            ],
        ),
        (
            "read configuration",
            &[0x02, 0x00, 0x01, 0x00, 0x74, 0x50, 0x12],
        ),
        (
            "mm, 32 m (other blocks zero)",
            &[
                0x02, 0x00, 0x23, 0x00, 0x77, 0x00, 0x00, 0x00, 0x00, 0x00, 0x06, 0x01, 0x00, 0x00,
                0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xAB, 0x70,
            ],
        ),
    ];

    #[test]
    fn requests_match_the_golden_bytes() {
        let built = [
            Telegram::request_values(),
            Telegram::set_mode(MODE_STREAM_VALUES),
            Telegram::set_mode(MODE_REQUEST_VALUES),
            Telegram::set_variant(180, 50),
            Telegram::request_config(),
            Telegram::set_config(&LmsConfig([0; CONFIG_LENGTH]).with_mm_32m()),
        ];
        for ((name, golden), telegram) in GOLDEN.iter().zip(built) {
            assert_eq!(telegram.encode().unwrap(), *golden, "{name}");
            let (back, used) = Telegram::decode(golden).unwrap();
            assert_eq!((back, used), (telegram, golden.len()), "{name}");
        }
    }

    #[test]
    fn configuration_replies_read_and_refusals_are_errors() {
        let mut block = vec![0u8; CONFIG_LENGTH];
        block[5] = MEASURING_MODE_32M_FIELD_A;
        block[6] = UNITS_MM;
        let read = LmsConfig::from_reply(&Telegram::reply(CONFIG_REPLY, block.clone(), 0));
        assert!(read.unwrap().is_mm_32m());
        let mut done = vec![1];
        done.extend(&block);
        assert!(
            LmsConfig::from_reply(&Telegram::reply(SET_CONFIG_REPLY, done.clone(), 0))
                .unwrap()
                .is_mm_32m()
        );
        done[0] = 0;
        assert_eq!(
            LmsConfig::from_reply(&Telegram::reply(SET_CONFIG_REPLY, done, 0)),
            Err(ConfigError::Refused)
        );
        assert_eq!(
            LmsConfig::from_reply(&Telegram::reply(CONFIG_REPLY, block[..9].to_vec(), 0)),
            Err(ConfigError::Short(9))
        );
        let centimetres = LmsConfig([0; CONFIG_LENGTH]);
        assert!(!centimetres.is_mm_32m());
        assert!(centimetres.with_mm_32m().is_mm_32m());
    }

    #[test]
    fn installation_mode_carries_its_password() {
        let t = Telegram::set_mode(MODE_INSTALLATION).encode().unwrap();
        assert_eq!(&t[..5], &[0x02, 0x00, 0x0A, 0x00, 0x20]);
        assert_eq!(&t[5..14], b"\x00SICK_LMS");
    }

    #[test]
    fn a_scan_survives_the_round_trip_with_the_thesis_mask() {
        // 361 values; one at 32 767 mm, the largest the 0x7f mask lets through.
        let mut ranges: Vec<u16> = (0..361).map(|i| 500 + 37 * i as u16).collect();
        ranges[7] = 32_767;
        let bytes = MeasuredValues::telegram_mm(&ranges, 0x10).encode().unwrap();
        assert_eq!(bytes.len(), 4 + 1 + 2 + 722 + 1 + 2);
        assert_eq!(&bytes[..7], &[0x02, 0x80, 0xD6, 0x02, 0xB0, 0x69, 0x41]);
        let (t, _) = Telegram::decode(&bytes).unwrap();
        let v = MeasuredValues::from_telegram(&t).unwrap();
        assert_eq!(v.unit, RangeUnit::Millimetres);
        assert_eq!(v.ranges, ranges);
        assert_eq!(v.status, 0x10);
        let scan = v.to_scan(Stamp::ZERO, 32_000).unwrap();
        assert_eq!(scan.len(), 361);
        assert_eq!(scan.range_m(7), None, "at or past 32 m is no return");
        assert_eq!(scan.range_m(0), Some(0.5));
        assert!((scan.angle(360) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn flag_bit_is_not_range_and_centimetres_scale() {
        // A hand-built B0 in centimetres: 2 values, the second with bit 15 set.
        let data = vec![0x02, 0x00, 0x2C, 0x01, 0x90, 0x81];
        let t = Telegram::reply(MEASURED_VALUES, data, 0);
        let v = MeasuredValues::from_telegram(&t).unwrap();
        assert_eq!(v.ranges, vec![300, 400]);
        assert_eq!(v.flags, vec![false, true]);
        // Two values are no variant's scan: named, not spread over a field.
        let refused = v.to_scan(Stamp::ZERO, 8_000).unwrap_err();
        assert_eq!(refused, ValuesError::Field(2));
        assert!(refused.to_string().contains("carry 2 values"), "{refused}");
        // The same values in a 100° scan at 1°, in centimetres: scaled to millimetres.
        let mut ranges = vec![300u16; 101];
        ranges[1] = 400;
        let mut t = MeasuredValues::telegram_mm(&ranges, 0);
        t.data[1] &= 0x3f;
        let scan = MeasuredValues::from_telegram(&t)
            .unwrap()
            .to_scan(Stamp::ZERO, 8_000)
            .unwrap();
        assert_eq!(scan.ranges_mm[..2], [3_000, 4_000]);
    }

    #[test]
    fn each_variant_spans_its_own_field() {
        // (values, first and last bearing in degrees): 180° from the right, 100° centred.
        for (count, first, last) in [
            (181, -90.0, 90.0),
            (361, -90.0, 90.0),
            (101, -50.0, 50.0),
            (201, -50.0, 50.0),
            (401, -50.0, 50.0),
        ] {
            let t = MeasuredValues::telegram_mm(&vec![1_000; count], 0);
            let scan = MeasuredValues::from_telegram(&t)
                .unwrap()
                .to_scan(Stamp::ZERO, 32_000)
                .unwrap();
            let degrees = |i: usize| scan.angle(i).to_degrees();
            assert!((degrees(0) - first).abs() < 1e-9, "{count}: {}", degrees(0));
            assert!(
                (degrees(count - 1) - last).abs() < 1e-9,
                "{count}: {}",
                degrees(count - 1)
            );
        }
        for count in [0, 1, 180, 360, 400, 402] {
            let t = MeasuredValues::telegram_mm(&vec![1_000; count], 0);
            let values = MeasuredValues::from_telegram(&t).unwrap();
            assert_eq!(
                values.to_scan(Stamp::ZERO, 32_000),
                Err(ValuesError::Field(count))
            );
        }
    }

    #[test]
    fn bad_telegrams_are_named() {
        let mut bytes = GOLDEN[0].1.to_vec();
        bytes[7] ^= 0xff;
        assert!(matches!(
            Telegram::decode(&bytes),
            Err(TelegramError::Crc { .. })
        ));
        assert!(matches!(
            Telegram::decode(&bytes[..5]),
            Err(TelegramError::Truncated {
                expected: 8,
                got: 5
            })
        ));
        assert_eq!(Telegram::decode(&[0x55]), Err(TelegramError::NoStart(0x55)));
        assert_eq!(
            Telegram::decode(&[0x02, 0x80, 0xff, 0xff]),
            Err(TelegramError::TooLong(0xffff))
        );
        let t = Telegram::reply(MEASURED_VALUES, vec![0x05, 0x40, 1, 2], 0);
        assert!(matches!(
            MeasuredValues::from_telegram(&t),
            Err(ValuesError::Length { count: 5, .. })
        ));
    }

    #[test]
    fn the_decoder_resynchronises_after_garbage_and_split_reads() {
        let scan = MeasuredValues::telegram_mm(&[1000; 361], 0)
            .encode()
            .unwrap();
        let mut corrupt = scan.clone();
        corrupt[100] ^= 0x01;
        let mut stream = vec![0x41, 0x42, STX, 0x00];
        stream.push(ACK);
        stream.extend(&corrupt);
        stream.extend([0x99, NAK]);
        stream.extend(&scan);
        let mut decoder = TelegramDecoder::new();
        let mut frames = Vec::new();
        // Three bytes at a time, as a slow serial line delivers them.
        for chunk in stream.chunks(3) {
            decoder.push(chunk);
            while let Some(frame) = decoder.next_frame() {
                frames.push(frame);
            }
        }
        let telegrams = frames
            .iter()
            .filter(|f| matches!(f, Frame::Telegram(_)))
            .count();
        assert_eq!(telegrams, 1, "only the intact scan");
        assert!(frames.contains(&Frame::Ack) && frames.contains(&Frame::Nak));
        assert!(matches!(frames.last(), Some(Frame::Telegram(_))));
        assert!(
            frames
                .iter()
                .any(|f| matches!(f, Frame::Skipped { reason, .. } if reason.contains("CRC")))
        );
        assert_eq!(decoder.pending(), 0);
    }
}
