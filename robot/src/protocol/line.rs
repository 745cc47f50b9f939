//! The two microcontrollers' protocol over any byte stream: lines in, typed replies out.
//!
//! [`LineReader`] cuts a byte stream into `\n`-ended lines. It never holds more than
//! [`MAX_LINE`] bytes of an unfinished line: a longer run without a newline is reported
//! ([`LinkError::TooLong`]) and skipped up to the next newline, so a flood cannot grow memory and
//! the stream resynchronises on the next line. A read that returns nothing within the stream's own
//! read timeout is [`LinkError::Timeout`] (set it with `set_read_timeout` on a serial port or a TCP
//! stream: robot code never reads the clock itself); end of stream is
//! [`LinkError::Disconnected`].
//!
//! [`BaseLink`] and [`PanTiltLink`] speak the commands of [`base`] and
//! [`pan_tilt`] over a `Read + Write` stream: each command is checked (arguments
//! 0..=65535 and their documented ranges) before a byte is sent, then its reply is read and parsed.

use super::base::{self, ReplyError};
use super::pan_tilt;
use crate::hardware::{
    ArgumentError, BatteryVoltages, DriveCommand, DriveStatus, DriveWait, ErrorKind,
    PanTiltCommand, PanTiltStatus, PanTiltWait, SonarCommand,
};
use crate::time::Stamp;
use std::io::{self, Read, Write};

/// The longest line either firmware writes is well under this (the `?` help text's lines).
pub const MAX_LINE: usize = 256;

/// What can go wrong talking to a microcontroller.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// Nothing arrived within the stream's read timeout.
    #[error("no reply within the read timeout")]
    Timeout,
    /// The stream ended (port closed, connection dropped).
    #[error("the link closed")]
    Disconnected,
    /// More than [`MAX_LINE`] bytes without a newline: skipped up to the next newline.
    #[error("more than {MAX_LINE} bytes without a newline (starting {start:?}): skipped")]
    TooLong {
        /// The first bytes of the run, as text where they are text.
        start: String,
    },
    /// A line with bytes that are not printable ASCII: noise on the line.
    #[error("garbled line {0:?}")]
    Garbled(String),
    /// A line that is not the reply the command expects.
    #[error(transparent)]
    Reply(#[from] ReplyError),
    /// An argument outside its range: nothing was sent.
    #[error(transparent)]
    Argument(#[from] ArgumentError),
    /// Any other I/O failure.
    #[error("I/O error on the link: {0}")]
    Io(#[from] io::Error),
}

impl LinkError {
    /// The backend-independent kind of this error.
    pub fn kind(&self) -> ErrorKind {
        match self {
            LinkError::Timeout => ErrorKind::Timeout,
            LinkError::Disconnected => ErrorKind::Disconnected,
            LinkError::TooLong { .. } | LinkError::Garbled(_) | LinkError::Reply(_) => {
                ErrorKind::Protocol
            }
            LinkError::Argument(_) => ErrorKind::InvalidArgument,
            LinkError::Io(_) => ErrorKind::Other,
        }
    }
}

/// Cuts a byte stream into lines; see the [module](self) documentation.
#[derive(Clone, Debug, Default)]
pub struct LineReader {
    pending: Vec<u8>,
    skipping: bool,
}

impl LineReader {
    /// A reader with nothing pending.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets any partial line (after a reconnection).
    pub fn clear(&mut self) {
        self.pending.clear();
        self.skipping = false;
    }

    /// The next complete line from what was buffered, newline included, if there is one.
    fn buffered_line(&mut self) -> Option<Result<String, LinkError>> {
        loop {
            let Some(end) = self.pending.iter().position(|&b| b == b'\n') else {
                if self.pending.len() > MAX_LINE {
                    let start = String::from_utf8_lossy(&self.pending[..16]).into_owned();
                    self.pending.clear();
                    self.skipping = true;
                    return Some(Err(LinkError::TooLong { start }));
                }
                if self.skipping {
                    self.pending.clear();
                }
                return None;
            };
            let line: Vec<u8> = self.pending.drain(..=end).collect();
            if std::mem::take(&mut self.skipping) {
                continue; // the tail of an over-long run
            }
            let text = line[..line.len() - 1]
                .strip_suffix(b"\r")
                .unwrap_or(&line[..line.len() - 1]);
            return Some(if text.iter().all(|b| (0x20..0x7f).contains(b)) {
                Ok(String::from_utf8_lossy(&line).into_owned())
            } else {
                Err(LinkError::Garbled(
                    String::from_utf8_lossy(text).into_owned(),
                ))
            });
        }
    }

    /// Reads from `stream` until a line is complete and returns it, newline included.
    pub fn read_line<R: Read>(&mut self, stream: &mut R) -> Result<String, LinkError> {
        let mut chunk = [0u8; 64];
        loop {
            if let Some(line) = self.buffered_line() {
                return line;
            }
            match stream.read(&mut chunk) {
                Ok(0) => return Err(LinkError::Disconnected),
                Ok(n) => self.pending.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                    ) =>
                {
                    return Err(LinkError::Timeout);
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::ConnectionReset
                            | io::ErrorKind::ConnectionAborted
                            | io::ErrorKind::BrokenPipe
                            | io::ErrorKind::UnexpectedEof
                    ) =>
                {
                    return Err(LinkError::Disconnected);
                }
                Err(e) => return Err(LinkError::Io(e)),
            }
        }
    }
}

/// A line-protocol stream: writes command lines, reads reply lines.
#[derive(Debug)]
pub struct LineLink<S> {
    stream: S,
    reader: LineReader,
}

impl<S: Read + Write> LineLink<S> {
    /// Talks over `stream`.
    pub fn new(stream: S) -> Self {
        LineLink {
            stream,
            reader: LineReader::new(),
        }
    }

    /// The stream, e.g. to change its timeout.
    pub fn stream_mut(&mut self) -> &mut S {
        &mut self.stream
    }

    /// Sends one line (newline included in `line`).
    pub fn send(&mut self, line: &str) -> Result<(), LinkError> {
        let sent = self
            .stream
            .write_all(line.as_bytes())
            .and_then(|()| self.stream.flush());
        sent.map_err(|e| match e.kind() {
            io::ErrorKind::BrokenPipe
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::ConnectionAborted => LinkError::Disconnected,
            io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut => LinkError::Timeout,
            _ => LinkError::Io(e),
        })
    }

    /// The next reply line.
    pub fn read_line(&mut self) -> Result<String, LinkError> {
        self.reader.read_line(&mut self.stream)
    }

    /// Sends `request` and parses the one-line reply with `parse`.
    pub fn query<T>(
        &mut self,
        request: &str,
        parse: impl FnOnce(&str) -> Result<T, ReplyError>,
    ) -> Result<T, LinkError> {
        self.send(request)?;
        let reply = self.read_line()?;
        Ok(parse(&reply)?)
    }

    /// Sends `line` and checks that the reply is `letter` alone.
    pub fn acknowledged(&mut self, line: &str, letter: char) -> Result<(), LinkError> {
        self.query(line, |reply| base::parse_ack(reply, letter))
    }
}

/// The base microcontroller over a byte stream.
#[derive(Debug)]
pub struct BaseLink<S>(pub LineLink<S>);

impl<S: Read + Write> BaseLink<S> {
    /// Talks to the base over `stream`.
    pub fn new(stream: S) -> Self {
        BaseLink(LineLink::new(stream))
    }

    /// A motion or set-up command, acknowledged by its letter.
    pub fn command(&mut self, command: &DriveCommand) -> Result<(), LinkError> {
        let line = base::encode_command(command)?;
        self.0.acknowledged(&line, command.letter())
    }

    /// `w`: returns when the firmware answers (the stream's read timeout must exceed
    /// `wait.max_ms`).
    pub fn wait(&mut self, wait: &DriveWait) -> Result<(), LinkError> {
        self.0.acknowledged(&base::encode_wait(wait), 'w')
    }

    /// `l`: the wheel counters and flags, stamped `stamp`.
    pub fn status(&mut self, stamp: Stamp) -> Result<DriveStatus, LinkError> {
        self.0
            .query(base::STATUS_REQUEST, |line| base::parse_status(line, stamp))
    }

    /// `t`: the battery voltages, stamped `stamp`.
    pub fn battery(&mut self, stamp: Stamp) -> Result<BatteryVoltages, LinkError> {
        self.0.query(base::BATTERY_REQUEST, |line| {
            base::parse_battery(line, stamp)
        })
    }

    /// A sonar command, acknowledged by its letter.
    pub fn sonar(&mut self, command: &SonarCommand) -> Result<(), LinkError> {
        let (line, letter) = base::encode_sonar(command)?;
        self.0.acknowledged(&line, letter)
    }

    /// Bare `s`: the echo times of the `count` positions of the firing sequence.
    pub fn sonar_report(&mut self, count: usize) -> Result<Vec<u16>, LinkError> {
        self.0.send(base::SONAR_REQUEST)?;
        let lines = (0..count)
            .map(|_| self.0.read_line())
            .collect::<Result<Vec<_>, _>>()?;
        let lines: Vec<&str> = lines.iter().map(String::as_str).collect();
        Ok(base::parse_sonar_report(&lines, count)?)
    }
}

/// The pan-tilt microcontroller over a byte stream.
#[derive(Debug)]
pub struct PanTiltLink<S>(pub LineLink<S>);

impl<S: Read + Write> PanTiltLink<S> {
    /// Talks to the pan-tilt over `stream`.
    pub fn new(stream: S) -> Self {
        PanTiltLink(LineLink::new(stream))
    }

    /// A move or ramp command, acknowledged by its letter.
    pub fn command(&mut self, command: &PanTiltCommand) -> Result<(), LinkError> {
        let line = pan_tilt::encode_command(command)?;
        self.0.acknowledged(&line, command.letter())
    }

    /// `w`: returns when the firmware answers.
    pub fn wait(&mut self, wait: &PanTiltWait) -> Result<(), LinkError> {
        self.0.acknowledged(&pan_tilt::encode_wait(wait), 'w')
    }

    /// `l`: positions, clicks, switches and motor flags, stamped `stamp`.
    pub fn status(&mut self, stamp: Stamp) -> Result<PanTiltStatus, LinkError> {
        self.0.query(pan_tilt::STATUS_REQUEST, |line| {
            pan_tilt::parse_status(line, stamp)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::Ramp;
    use std::collections::VecDeque;

    /// A scripted device: what it will answer, and what it was sent. An empty answer queue
    /// times out, as a silent serial port does.
    #[derive(Default)]
    struct Device {
        replies: VecDeque<Vec<u8>>,
        sent: Vec<u8>,
        closed: bool,
    }

    impl Device {
        fn answering(replies: &[&[u8]]) -> Self {
            Device {
                replies: replies.iter().map(|r| r.to_vec()).collect(),
                ..Device::default()
            }
        }
    }

    impl Read for Device {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            match self.replies.front_mut() {
                Some(reply) => {
                    let n = reply.len().min(buf.len());
                    buf[..n].copy_from_slice(&reply[..n]);
                    reply.drain(..n);
                    if reply.is_empty() {
                        self.replies.pop_front();
                    }
                    Ok(n)
                }
                None if self.closed => Ok(0),
                None => Err(io::ErrorKind::TimedOut.into()),
            }
        }
    }

    impl Write for Device {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            self.sent.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn commands_go_out_byte_exact_and_replies_parse() {
        let mut base = BaseLink::new(Device::answering(&[
            b"a\n",
            b"k\nl10.03 9.98 1 1 0\n",
            b"t12716 25394 12859 25837\n",
            b"S\ns1634\n1779\n65535\n",
            b"w\n",
        ]));
        base.command(&DriveCommand::Advance(535)).unwrap();
        base.command(&DriveCommand::Ramp(Ramp::POWER_ON)).unwrap();
        let status = base.status(Stamp::ZERO).unwrap();
        assert_eq!((status.left_counts, status.right_counts), (1003, 998));
        assert_eq!(base.battery(Stamp::ZERO).unwrap().logic_12_mv, 12716);
        base.sonar(&SonarCommand::Sequence(vec![0, 1, 2])).unwrap();
        assert_eq!(base.sonar_report(3).unwrap(), vec![1634, 1779, 65535]);
        base.wait(&DriveWait::motors(5000)).unwrap();
        assert_eq!(
            String::from_utf8(base.0.stream_mut().sent.clone()).unwrap(),
            "a535\nk5 30 50\nl\nt\nS0 1 2\ns\nw5000 1 1 0\n"
        );

        let mut head = PanTiltLink::new(Device::answering(&[b"g\n", b"l127 0 50 3 0 0 0 1 0\n"]));
        head.command(&PanTiltCommand::Pan(127)).unwrap();
        let s = head.status(Stamp::ZERO).unwrap();
        assert_eq!((s.pan, s.tilt_clicks, s.pan_on), (127, 3, true));
        assert_eq!(head.0.stream_mut().sent, b"g127\nl\n");
    }

    #[test]
    fn out_of_range_arguments_send_nothing() {
        let mut base = BaseLink::new(Device::default());
        let error = base
            .command(&DriveCommand::WheelSpeeds {
                left: 500,
                right: 0,
            })
            .unwrap_err();
        assert_eq!(error.kind(), ErrorKind::InvalidArgument);
        assert!(base.0.stream_mut().sent.is_empty());
    }

    #[test]
    fn silence_garbage_floods_and_hangups_are_typed_errors() {
        // Silence.
        let mut base = BaseLink::new(Device::default());
        assert!(matches!(
            base.command(&DriveCommand::Stop),
            Err(LinkError::Timeout)
        ));
        // A wrong reply names the command and the line.
        let mut base = BaseLink::new(Device::answering(&[b"x\n"]));
        let e = base.command(&DriveCommand::Stop).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Protocol);
        assert!(e.to_string().contains("`p`") && e.to_string().contains("\"x\""));
        // Noise bytes, then a flood without newlines, then the real reply: each is reported and
        // the reply still arrives.
        let flood = vec![b'#'; 5 * MAX_LINE];
        let mut link = LineLink::new(Device::answering(&[b"\x01\xfe\n", &flood, b"\np\n"]));
        assert!(matches!(link.read_line(), Err(LinkError::Garbled(_))));
        assert!(matches!(link.read_line(), Err(LinkError::TooLong { .. })));
        assert_eq!(link.read_line().unwrap(), "p\n");
        assert!(link.reader.pending.len() <= MAX_LINE + 64);
        // A partial line and then the far end hangs up.
        let mut device = Device::answering(&[b"l10.0"]);
        device.closed = true;
        let mut base = BaseLink::new(device);
        let e = base.status(Stamp::ZERO).unwrap_err();
        assert!(matches!(e, LinkError::Disconnected), "{e}");
        assert_eq!(e.kind(), ErrorKind::Disconnected);
    }
}
