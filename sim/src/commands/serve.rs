//! `twin serve`: the twin's serial face. The twin runs in (scaled) real time and offers its three
//! devices as byte streams — the base and pan-tilt microcontrollers speaking App. A's line
//! protocol through their ported firmware and serial timing ([`Board`]), and the SICK LMS
//! answering telegrams ([`LmsEmulator`]) — on TCP ports or pseudo-terminals, so the real
//! backend (`SerialRobot`), a terminal program or a legacy tool can drive it like the robot.
//!
//! What arrives from a client goes onto the simulated serial line at the device's rate: each byte
//! takes ten bit-times after the previous one, and a line reaches the firmware when its newline
//! has. Nothing grows without bound:
//!
//! - a line longer than the firmware's 256-byte `g_command_line` is discarded up to its newline
//!   (the real firmware would write past its buffer);
//! - bytes a client sends faster than the line carries them are dropped once a backlog of
//!   [`RX_BACKLOG`] bytes waits (a serial bridge's buffer overflows the same way);
//! - output waits for its time on the line and for the client to read it, up to
//!   [`MAX_PENDING_OUT`] bytes per device; older output is dropped beyond that, and output nobody
//!   is connected to hear is lost, as on an unplugged cable.
//!
//! A TCP face takes one client at a time: a new connection replaces the old one (a serial port
//! has one peer, and a client that reconnects after a network fault must not be locked out), and
//! starts with an empty line: it does not inherit its predecessor's unfinished bytes.

use crate::devices::firmware::{Board, MainLoop};
use crate::twin::Twin;
use core::fmt;
use core::str::FromStr;
use core::time::Duration;
use robot::hardware::LaserScan;
use robot::protocol::serial_time;
use robot::protocol::sick::{
    self, ACK, Frame, LmsConfig, MeasuredValues, NAK, Telegram, TelegramDecoder,
};
use robot::{Clock, Stamp};
use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Output bytes kept per device while the line or the client is slower.
pub const MAX_PENDING_OUT: usize = 64 * 1024;
/// Bytes from a client that may wait for the simulated line before more are dropped.
pub const RX_BACKLOG: usize = 256;
/// The firmware's command buffer, `g_command_line[256]`.
const LINE_LIMIT: usize = 256;

/// The robot's clock read off the wall: monotonic from when it was made, running `scale` times
/// faster than real time (1 on the real robot; the twin's speed when it is served faster).
#[derive(Clone, Debug)]
pub struct WallClock {
    origin: Instant,
    scale: f64,
}

impl WallClock {
    /// A clock starting at zero now, running `scale` times faster than the wall.
    pub fn new(scale: f64) -> Self {
        WallClock {
            origin: Instant::now(),
            scale,
        }
    }
}

impl Clock for WallClock {
    fn now(&self) -> Stamp {
        Stamp::from_secs_f64(self.origin.elapsed().as_secs_f64() * self.scale)
    }
}

/// Which of the served devices.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Served {
    /// The base microcontroller.
    Base,
    /// The pan-tilt microcontroller.
    PanTilt,
    /// The laser.
    Laser,
}

impl fmt::Display for Served {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(match self {
            Served::Base => "base",
            Served::PanTilt => "pan-tilt",
            Served::Laser => "laser",
        })
    }
}

/// Where a device is offered: `tcp:HOST:PORT` (port 0 picks a free one) or `pty`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Offer {
    /// A TCP listener.
    Tcp(String),
    /// A pseudo-terminal; its path is printed.
    Pty,
}

/// An offer that does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{0}` is not a place to serve a device: expected tcp:HOST:PORT (e.g. tcp:127.0.0.1:4001) or pty"
)]
pub struct OfferError(pub String);

impl FromStr for Offer {
    type Err = OfferError;

    /// ```
    /// use sim::commands::serve::Offer;
    /// assert_eq!("pty".parse(), Ok(Offer::Pty));
    /// assert_eq!("tcp:127.0.0.1:0".parse(), Ok(Offer::Tcp("127.0.0.1:0".into())));
    /// assert!("127.0.0.1:4001".parse::<Offer>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == "pty" {
            return Ok(Offer::Pty);
        }
        match s.strip_prefix("tcp:").and_then(|a| a.rsplit_once(':')) {
            Some((host, port)) if !host.is_empty() && port.parse::<u16>().is_ok() => {
                Ok(Offer::Tcp(s["tcp:".len()..].to_string()))
            }
            _ => Err(OfferError(s.into())),
        }
    }
}

/// Why the server cannot start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// A face cannot be opened.
    #[error("{device}: cannot offer {offer:?}: {source}")]
    Open {
        /// The device.
        device: Served,
        /// Where it was to be offered.
        offer: Offer,
        /// Why.
        #[source]
        source: io::Error,
    },
    /// The robot has no such device.
    #[error("the scenario's robot has no {0}")]
    NoDevice(Served),
}

/// A device's end of the link: a TCP listener with its one client, or a pseudo-terminal.
enum Face {
    Tcp {
        listener: TcpListener,
        client: Option<(TcpStream, SocketAddr)>,
    },
    Pty {
        master: serialport::TTYPort,
        /// Held open so the master does not read end-of-file while no program has the path open.
        _slave: serialport::TTYPort,
        path: String,
    },
}

impl Face {
    fn open(offer: &Offer) -> io::Result<Face> {
        match offer {
            Offer::Tcp(address) => {
                let listener = TcpListener::bind(address)?;
                listener.set_nonblocking(true)?;
                Ok(Face::Tcp {
                    listener,
                    client: None,
                })
            }
            Offer::Pty => {
                use serialport::SerialPort;
                let (mut master, slave) = serialport::TTYPort::pair().map_err(io::Error::from)?;
                master
                    .set_timeout(Duration::ZERO)
                    .map_err(io::Error::from)?;
                let path = slave.name().unwrap_or_else(|| "(unnamed pty)".into());
                Ok(Face::Pty {
                    master,
                    _slave: slave,
                    path,
                })
            }
        }
    }

    /// Where clients connect.
    fn address(&self) -> String {
        match self {
            Face::Tcp { listener, .. } => listener
                .local_addr()
                .map_or_else(|e| format!("(unknown: {e})"), |a| format!("tcp:{a}")),
            Face::Pty { path, .. } => path.clone(),
        }
    }

    /// Takes a waiting connection, replacing the current client; true if a new client came.
    fn accept(&mut self, log: &mut Vec<String>, stats: &mut FaceStats) -> bool {
        let Face::Tcp { listener, client } = self else {
            return false;
        };
        let before = stats.connections;
        while let Ok((stream, peer)) = listener.accept() {
            if stream.set_nonblocking(true).is_err() {
                continue;
            }
            let _ = stream.set_nodelay(true);
            stats.connections += 1;
            match client.replace((stream, peer)) {
                Some((_, old)) => log.push(format!("{peer} connected, replacing {old}")),
                None => log.push(format!("{peer} connected")),
            }
        }
        stats.connections != before
    }

    /// Whether a client is there (a pseudo-terminal always is).
    fn connected(&self) -> bool {
        !matches!(self, Face::Tcp { client: None, .. })
    }

    /// Reads what has arrived (nothing if nobody is connected).
    fn read(&mut self, buf: &mut [u8], log: &mut Vec<String>) -> usize {
        let result = match self {
            Face::Tcp { client: None, .. } => return 0,
            Face::Tcp {
                client: Some((stream, _)),
                ..
            } => stream.read(buf),
            Face::Pty { master, .. } => master.read(buf),
        };
        match result {
            Ok(0) => {
                self.hang_up(log, "disconnected");
                0
            }
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock
                        | io::ErrorKind::TimedOut
                        | io::ErrorKind::Interrupted
                ) =>
            {
                0
            }
            Err(e) => {
                self.hang_up(log, &format!("dropped ({e})"));
                0
            }
        }
    }

    /// Writes as much of `bytes` as the client takes now; `None` when nobody is connected.
    fn write(&mut self, bytes: &[u8], log: &mut Vec<String>) -> Option<usize> {
        let result = match self {
            Face::Tcp { client: None, .. } => return None,
            Face::Tcp {
                client: Some((stream, _)),
                ..
            } => stream.write(bytes),
            Face::Pty { master, .. } => master.write(bytes),
        };
        match result {
            Ok(n) => Some(n),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock
                        | io::ErrorKind::TimedOut
                        | io::ErrorKind::Interrupted
                ) =>
            {
                Some(0)
            }
            Err(e) => {
                self.hang_up(log, &format!("dropped ({e})"));
                None
            }
        }
    }

    fn hang_up(&mut self, log: &mut Vec<String>, why: &str) {
        if let Face::Tcp { client, .. } = self
            && let Some((_, peer)) = client.take()
        {
            log.push(format!("{peer} {why}"));
        }
    }
}

/// What a device's face has seen.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FaceStats {
    /// Clients that connected.
    pub connections: u32,
    /// Bytes received from clients.
    pub bytes_in: u64,
    /// Bytes received but dropped: faster than the line, or past the firmware's buffer.
    pub bytes_dropped_in: u64,
    /// Complete lines (or telegrams) handed to the device.
    pub messages_in: u64,
    /// Bytes written to clients.
    pub bytes_out: u64,
    /// Output bytes lost: nobody connected, or the client too slow.
    pub bytes_dropped_out: u64,
}

/// A microcontroller's line: bytes in become lines for the board, the board's output goes out
/// when its time on the line has come.
struct LineFace {
    device: Served,
    face: Face,
    byte: Duration,
    line: Vec<u8>,
    discarding: bool,
    rx_free: Stamp,
    out: VecDeque<(Stamp, u8)>,
    /// The last byte taken from the board was not a newline: a reply is half out.
    mid_line: bool,
    /// Drop the board's output up to the end of the reply it is in (a new client starts on a
    /// fresh line).
    skip_to_newline: bool,
    stats: FaceStats,
}

impl LineFace {
    fn new(device: Served, face: Face, baud: u32) -> Self {
        LineFace {
            device,
            face,
            byte: serial_time(1, baud),
            line: Vec::new(),
            discarding: false,
            rx_free: Stamp::ZERO,
            out: VecDeque::new(),
            mid_line: false,
            skip_to_newline: false,
            stats: FaceStats::default(),
        }
    }

    /// Forgets the link's traffic when a client comes or goes: the unfinished line it typed,
    /// the lines the board has not read yet and every reply not yet sent. The board's state
    /// (motors, counters) stays, as on the robot.
    fn forget_link<F: MainLoop>(&mut self, board: &mut Board<F>) {
        self.line.clear();
        self.discarding = false;
        self.stats.bytes_dropped_out += self.out.len() as u64;
        self.out.clear();
        self.stats.bytes_dropped_out += board.forget_link() as u64;
        self.skip_to_newline = self.mid_line;
    }

    /// Moves bytes both ways at `now`.
    fn pump<F: MainLoop>(&mut self, now: Stamp, board: &mut Board<F>, log: &mut Vec<String>) {
        let mut notes = Vec::new();
        let was_connected = self.face.connected();
        if self.face.accept(&mut notes, &mut self.stats) {
            // A new client inherits nothing of its predecessor's.
            self.forget_link(board);
        }
        let backlog_limit = self.byte * RX_BACKLOG as u32;
        let mut buf = [0u8; 512];
        // Bounded per pump, so a flood cannot starve the simulation.
        for _ in 0..64 {
            let n = self.face.read(&mut buf, &mut notes);
            if n == 0 {
                break;
            }
            self.stats.bytes_in += n as u64;
            for &b in &buf[..n] {
                if self.rx_free > now + backlog_limit {
                    self.stats.bytes_dropped_in += 1;
                    continue;
                }
                let arrival = self.rx_free.max(now) + self.byte;
                self.rx_free = arrival;
                if self.discarding {
                    self.stats.bytes_dropped_in += 1;
                    self.discarding = b != b'\n';
                    continue;
                }
                self.line.push(b);
                if b == b'\n' {
                    board.deliver(arrival, std::mem::take(&mut self.line));
                    self.stats.messages_in += 1;
                } else if self.line.len() >= LINE_LIMIT {
                    self.stats.bytes_dropped_in += self.line.len() as u64;
                    self.line.clear();
                    self.discarding = true;
                    notes.push(format!(
                        "a line of over {LINE_LIMIT} bytes without a newline: discarded"
                    ));
                }
            }
        }
        if was_connected && !self.face.connected() {
            self.forget_link(board);
        }
        while let Some(byte) = board.pop_output() {
            self.mid_line = byte.1 != b'\n';
            if self.skip_to_newline {
                self.skip_to_newline = self.mid_line;
                self.stats.bytes_dropped_out += 1;
                continue;
            }
            if self.out.len() == MAX_PENDING_OUT {
                self.out.pop_front();
                self.stats.bytes_dropped_out += 1;
            }
            self.out.push_back(byte);
        }
        let ready = self.out.iter().take_while(|(t, _)| *t <= now).count();
        if ready > 0 {
            let bytes: Vec<u8> = self.out.iter().take(ready).map(|(_, b)| *b).collect();
            match self.face.write(&bytes, &mut notes) {
                Some(n) => {
                    self.out.drain(..n);
                    self.stats.bytes_out += n as u64;
                }
                None => {
                    self.out.drain(..ready);
                    self.stats.bytes_dropped_out += ready as u64;
                }
            }
        }
        log.extend(notes.into_iter().map(|n| format!("{}: {n}", self.device)));
    }
}

/// The SICK LMS's side of the protocol, as the twin offers it: the requests the thesis's setup
/// needs, answered like the LMS2xx listing says. Every request with a good CRC is acknowledged
/// (`06`) and answered; unknown commands get a NAK (`15`).
///
/// - `20 mode`: `24` streams every scan, `25` sends one per `30 01` (the power-on mode), `00`
///   with the password enters installation mode; the baud-rate modes (`40`, `41`, `42`) are
///   acknowledged but the twin keeps its line's timing. Reply `A0 00` (done) or `A0 01`.
/// - `30 01`: the next scan (`B0`).
/// - `3B angle resolution`: only the twin's 180° at 0.5° is accepted (`BB 01 …`, else `BB 00`).
/// - `74`: the configuration (`F4`). `77`: in installation mode the measuring mode and unit are
///   taken (`F7 01 …`), otherwise refused (`F7 00 …`). Centimetres are honoured in `B0`.
#[derive(Clone, Debug)]
pub struct LmsEmulator {
    mode: u8,
    config: LmsConfig,
    requested: bool,
    /// The variant its scans are: scan angle in degrees and resolution in hundredths of one.
    variant: (u16, u16),
}

impl Default for LmsEmulator {
    fn default() -> Self {
        Self::new()
    }
}

impl LmsEmulator {
    /// An LMS just switched on: request mode, configured for millimetres over 32 m (as the
    /// thesis's laser was).
    pub fn new() -> Self {
        LmsEmulator {
            mode: sick::MODE_REQUEST_VALUES,
            config: LmsConfig([0; sick::CONFIG_LENGTH]).with_mm_32m(),
            requested: false,
            variant: (180, 50),
        }
    }

    /// [`LmsEmulator::new`] whose scans are `variant` (scan angle in degrees, resolution in
    /// hundredths of one, [`sick::lms_variant`]): the only variant it accepts (`3B`).
    pub fn with_variant(variant: (u16, u16)) -> Self {
        LmsEmulator {
            variant,
            ..Self::new()
        }
    }

    /// The configuration in force.
    pub fn config(&self) -> LmsConfig {
        self.config
    }

    /// The bytes answering one request telegram.
    pub fn handle(&mut self, request: &Telegram) -> Vec<u8> {
        let reply = |command, data| Telegram::reply(command, data, 0);
        let answer = match (request.command, request.data.as_slice()) {
            (sick::SET_MODE, [mode, rest @ ..]) => {
                let ok = match *mode {
                    sick::MODE_INSTALLATION => rest == sick::INSTALLATION_PASSWORD,
                    sick::MODE_STREAM_VALUES | sick::MODE_REQUEST_VALUES => true,
                    0x40..=0x42 => true,
                    _ => false,
                };
                if ok && !(0x40..=0x42).contains(mode) {
                    self.mode = *mode;
                }
                Some(reply(sick::MODE_REPLY, vec![u8::from(!ok)]))
            }
            (sick::REQUEST_VALUES, [0x01]) => {
                self.requested = true;
                None
            }
            (sick::SET_VARIANT, [a0, a1, r0, r1]) => {
                // The twin's laser is the robot file's: only its own variant is offered.
                let (angle, resolution) = self.variant;
                let ok = u16::from_le_bytes([*a0, *a1]) == angle
                    && u16::from_le_bytes([*r0, *r1]) == resolution;
                let mut answer = vec![u8::from(ok)];
                answer.extend(angle.to_le_bytes());
                answer.extend(resolution.to_le_bytes());
                Some(reply(sick::VARIANT_REPLY, answer))
            }
            (sick::REQUEST_CONFIG, []) => Some(reply(sick::CONFIG_REPLY, self.config.0.to_vec())),
            (sick::SET_CONFIG, data) if data.len() == sick::CONFIG_LENGTH => {
                let ok = self.mode == sick::MODE_INSTALLATION;
                if ok {
                    self.config.0[5] = data[5];
                    self.config.0[6] = data[6];
                }
                let mut answer = vec![u8::from(ok)];
                answer.extend(self.config.0);
                Some(reply(sick::SET_CONFIG_REPLY, answer))
            }
            _ => return vec![NAK],
        };
        let mut bytes = vec![ACK];
        if let Some(telegram) = answer {
            bytes.extend(telegram.encode().expect("replies are short"));
        }
        bytes
    }

    /// Forgets a requested scan not yet sent (its client has gone).
    pub fn forget_request(&mut self) {
        self.requested = false;
    }

    /// Whether the next scan should be sent (streaming, or one was requested).
    pub fn wants_scan(&self) -> bool {
        self.mode == sick::MODE_STREAM_VALUES || self.requested
    }

    /// The `B0` telegram of `scan`, in the configured unit.
    pub fn scan_telegram(&mut self, scan: &LaserScan) -> Vec<u8> {
        self.requested = false;
        let telegram = if self.config.units() == sick::UNITS_MM {
            MeasuredValues::telegram_mm(&scan.ranges_mm, 0)
        } else {
            let mut t = MeasuredValues::telegram_mm(
                &scan
                    .ranges_mm
                    .iter()
                    .map(|r| r.div_ceil(10))
                    .collect::<Vec<_>>(),
                0,
            );
            t.data[1] &= 0x3f; // unit bits 00: centimetres
            t
        };
        telegram.encode().expect("361 values fit a telegram")
    }
}

/// The laser's line: telegrams in, replies and scans out.
struct LmsFace {
    face: Face,
    baud: u32,
    decoder: TelegramDecoder,
    lms: LmsEmulator,
    out: VecDeque<(Stamp, Vec<u8>)>,
    out_bytes: usize,
    tx_free: Stamp,
    stats: FaceStats,
}

impl LmsFace {
    fn queue(&mut self, ready: Stamp, bytes: Vec<u8>) {
        self.out_bytes += bytes.len();
        self.out.push_back((ready, bytes));
        while self.out_bytes > MAX_PENDING_OUT {
            let (_, dropped) = self
                .out
                .pop_front()
                .expect("over the limit means not empty");
            self.out_bytes -= dropped.len();
            self.stats.bytes_dropped_out += dropped.len() as u64;
        }
    }

    /// Forgets the link's traffic when a client comes or goes: its undecoded bytes, a scan it
    /// requested and every telegram not yet sent (the LMS's mode and configuration stay).
    fn forget_link(&mut self, now: Stamp) {
        self.decoder.clear();
        self.lms.forget_request();
        self.stats.bytes_dropped_out += self.out_bytes as u64;
        self.out.clear();
        self.out_bytes = 0;
        self.tx_free = now;
    }

    /// Moves bytes both ways; with `keep`, every scan delivered by now is also handed back (for
    /// the live view), whether the client asked for it or not.
    fn pump(
        &mut self,
        now: Stamp,
        twin: &mut Twin,
        log: &mut Vec<String>,
        keep: bool,
    ) -> Vec<LaserScan> {
        let mut kept = Vec::new();
        let mut notes = Vec::new();
        let was_connected = self.face.connected();
        if self.face.accept(&mut notes, &mut self.stats) {
            self.forget_link(now);
        }
        let mut buf = [0u8; 512];
        for _ in 0..64 {
            let n = self.face.read(&mut buf, &mut notes);
            if n == 0 {
                break;
            }
            self.stats.bytes_in += n as u64;
            self.decoder.push(&buf[..n]);
            while let Some(frame) = self.decoder.next_frame() {
                match frame {
                    Frame::Telegram(request) => {
                        self.stats.messages_in += 1;
                        let answer = self.lms.handle(&request);
                        let start = self.tx_free.max(now);
                        self.tx_free = start + serial_time(answer.len(), self.baud);
                        let ready = self.tx_free;
                        self.queue(ready, answer);
                    }
                    Frame::Skipped { bytes, .. } => self.stats.bytes_dropped_in += bytes as u64,
                    Frame::Ack | Frame::Nak => {}
                }
            }
        }
        if was_connected && !self.face.connected() {
            self.forget_link(now);
        }
        // Scans whose telegram has reached the host by now.
        while let Some(delivery) = twin.next_scan_delivery().filter(|d| *d <= now) {
            if self.lms.wants_scan() {
                let (_, scan) = twin.pop_scan().expect("a scan is on its way");
                let bytes = self.lms.scan_telegram(&scan);
                self.queue(delivery, bytes);
                if keep {
                    kept.push(scan);
                }
            } else if keep {
                kept.extend(twin.pop_scan().map(|(_, scan)| scan));
            } else {
                twin.drop_next_scan();
            }
        }
        while self.out.front().is_some_and(|(t, _)| *t <= now) {
            let (_, bytes) = self.out.front().expect("checked");
            match self.face.write(bytes, &mut notes) {
                Some(n) if n == bytes.len() => {
                    self.stats.bytes_out += n as u64;
                    self.out_bytes -= n;
                    self.out.pop_front();
                }
                Some(n) => {
                    // The client is slow: keep the rest for later.
                    self.stats.bytes_out += n as u64;
                    self.out_bytes -= n;
                    self.out.front_mut().expect("checked").1.drain(..n);
                    break;
                }
                None => {
                    let (_, bytes) = self.out.pop_front().expect("checked");
                    self.out_bytes -= bytes.len();
                    self.stats.bytes_dropped_out += bytes.len() as u64;
                }
            }
        }
        log.extend(notes.into_iter().map(|n| format!("laser: {n}")));
        kept
    }
}

/// Where and how fast to serve.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// Simulated seconds per wall-clock second (1: real time).
    pub speed: f64,
    /// The base microcontroller's face.
    pub base: Offer,
    /// The pan-tilt's face, if offered.
    pub pan_tilt: Option<Offer>,
    /// The laser's face, if offered.
    pub laser: Option<Offer>,
    /// Publishes the scans and the truth live (`twin serve --live`).
    pub live: Option<ServedLive>,
}

/// What `twin serve --live` publishes with.
#[derive(Clone, Debug)]
pub struct ServedLive {
    /// The server.
    pub server: std::sync::Arc<super::live::LiveServer>,
    /// Where the laser sits on the base (the robot description's).
    pub mount: robot::mount::LaserMount,
    /// Mean time between scans, seconds.
    pub scan_period_s: f64,
}

/// The twin with its devices offered; see the [module](self) documentation.
pub struct Server {
    twin: Twin,
    speed: f64,
    base: LineFace,
    pan_tilt: Option<LineFace>,
    laser: Option<LmsFace>,
    log: Vec<String>,
    live: Option<ServedLive>,
}

impl Server {
    /// Opens the faces of `options` for `twin`.
    pub fn new(twin: Twin, options: &ServeOptions) -> Result<Self, ServeError> {
        let open = |device, offer: &Offer| {
            Face::open(offer).map_err(|source| ServeError::Open {
                device,
                offer: offer.clone(),
                source,
            })
        };
        let base = LineFace::new(
            Served::Base,
            open(Served::Base, &options.base)?,
            twin.board().baud(),
        );
        let pan_tilt = match &options.pan_tilt {
            Some(offer) => {
                let baud = twin
                    .pan_tilt_board()
                    .ok_or(ServeError::NoDevice(Served::PanTilt))?
                    .baud();
                Some(LineFace::new(
                    Served::PanTilt,
                    open(Served::PanTilt, offer)?,
                    baud,
                ))
            }
            None => None,
        };
        let laser = match &options.laser {
            Some(offer) => Some(LmsFace {
                face: open(Served::Laser, offer)?,
                baud: twin.laser().baud(),
                decoder: TelegramDecoder::new(),
                lms: sick::lms_variant(twin.laser().beams().len())
                    .map_or_else(LmsEmulator::new, LmsEmulator::with_variant),
                out: VecDeque::new(),
                out_bytes: 0,
                tx_free: Stamp::ZERO,
                stats: FaceStats::default(),
            }),
            None => None,
        };
        Ok(Server {
            twin,
            speed: options.speed,
            base,
            pan_tilt,
            laser,
            log: Vec::new(),
            live: options.live.clone(),
        })
        .inspect(|server| {
            if let Some(live) = &server.live {
                announce(live, &server.twin);
            }
        })
    }

    /// Where each offered device can be reached.
    pub fn addresses(&self) -> Vec<(Served, String)> {
        self.faces(|face, _| face.address())
    }

    /// The twin.
    pub fn twin(&self) -> &Twin {
        &self.twin
    }

    /// What each face has seen.
    pub fn stats(&self) -> Vec<(Served, FaceStats)> {
        self.faces(|_, stats| stats.clone())
    }

    /// `f` of each offered device's face and statistics, base first.
    fn faces<T>(&self, f: impl Fn(&Face, &FaceStats) -> T) -> Vec<(Served, T)> {
        let mut out = vec![(Served::Base, f(&self.base.face, &self.base.stats))];
        if let Some(p) = &self.pan_tilt {
            out.push((Served::PanTilt, f(&p.face, &p.stats)));
        }
        if let Some(l) = &self.laser {
            out.push((Served::Laser, f(&l.face, &l.stats)));
        }
        out
    }

    /// Moves bytes both ways on every face at the twin's present.
    fn pump(&mut self) {
        let now = self.twin.now();
        self.base.pump(now, self.twin.board_mut(), &mut self.log);
        if let Some(face) = &mut self.pan_tilt
            && let Some(board) = self.twin.pan_tilt_board_mut()
        {
            face.pump(now, board, &mut self.log);
        }
        let keep = self.live.is_some();
        let scans = match &mut self.laser {
            Some(face) => face.pump(now, &mut self.twin, &mut self.log, keep),
            None if keep => {
                let mut scans = Vec::new();
                while self.twin.next_scan_delivery().is_some_and(|d| d <= now) {
                    scans.extend(self.twin.pop_scan().map(|(_, scan)| scan));
                }
                scans
            }
            None => Vec::new(),
        };
        if let Some(live) = &self.live {
            for scan in &scans {
                publish(live, &self.twin, scan);
            }
        }
    }

    /// Runs until `stop` is set or, if given, `duration` of simulated time has passed; hands
    /// each connection, disconnection and discarded input to `on_log` as it happens.
    pub fn run(
        &mut self,
        stop: &AtomicBool,
        duration: Option<Duration>,
        mut on_log: impl FnMut(Stamp, &str),
    ) {
        let started = Instant::now();
        let origin = self.twin.now();
        let end = duration.map(|d| origin + d);
        while !stop.load(Ordering::Relaxed) {
            let target = origin + started.elapsed().mul_f64(self.speed);
            if end.is_some_and(|end| target >= end) {
                break;
            }
            self.pump();
            while self.twin.now() < target {
                self.twin.step();
            }
            self.pump();
            for line in self.log.drain(..) {
                on_log(self.twin.now(), &line);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn answer(lms: &mut LmsEmulator, request: Telegram) -> Telegram {
        let bytes = lms.handle(&request);
        assert_eq!(bytes[0], ACK, "every good request is acknowledged");
        Telegram::decode(&bytes[1..]).unwrap().0
    }

    #[test]
    fn the_lms_takes_a_configuration_only_in_installation_mode() {
        let mut lms = LmsEmulator::new();
        let cm = LmsConfig([0; sick::CONFIG_LENGTH]);
        let refused = answer(&mut lms, Telegram::set_config(&cm));
        assert_eq!(
            LmsConfig::from_reply(&refused),
            Err(sick::ConfigError::Refused)
        );
        let wrong = answer(&mut lms, Telegram::request(sick::SET_MODE, vec![0, b'x']));
        assert_eq!(wrong.data, vec![1], "a wrong password is refused");
        let mode = answer(&mut lms, Telegram::set_mode(sick::MODE_INSTALLATION));
        assert_eq!(mode.data, vec![0]);
        let done = answer(&mut lms, Telegram::set_config(&cm));
        assert!(!LmsConfig::from_reply(&done).unwrap().is_mm_32m());
        // Now in centimetres: a 1234 mm range goes out as 124 cm.
        let scan = LaserScan {
            stamp: Stamp::ZERO,
            angle_min: -1.5,
            angle_increment: 0.01,
            range_max_mm: 32_000,
            ranges_mm: vec![1234; 361],
            head: None,
        };
        let bytes = lms.scan_telegram(&scan);
        let values = MeasuredValues::from_telegram(&Telegram::decode(&bytes).unwrap().0).unwrap();
        assert_eq!(values.unit, sick::RangeUnit::Centimetres);
        assert_eq!(values.ranges[0], 124);
    }

    #[test]
    fn the_lms_streams_or_answers_one_request_at_a_time() {
        let mut lms = LmsEmulator::new();
        assert!(!lms.wants_scan(), "power-on: request mode, nothing asked");
        assert_eq!(lms.handle(&Telegram::request_values()), vec![ACK]);
        assert!(lms.wants_scan());
        let scan = LaserScan {
            stamp: Stamp::ZERO,
            angle_min: -1.5,
            angle_increment: 0.01,
            range_max_mm: 32_000,
            ranges_mm: vec![5000; 361],
            head: None,
        };
        assert_eq!(lms.scan_telegram(&scan).len(), 732);
        assert!(!lms.wants_scan(), "one scan per request");
        answer(&mut lms, Telegram::set_mode(sick::MODE_STREAM_VALUES));
        lms.scan_telegram(&scan);
        assert!(lms.wants_scan(), "streaming goes on");
        let variant = answer(&mut lms, Telegram::set_variant(100, 25));
        assert_eq!(variant.data[0], 0, "only 180° at 0.5° is offered");
        assert_eq!(lms.handle(&Telegram::request(0x66, vec![])), vec![NAK]);
    }

    /// The variant offered is the laser's own, read from its field, and the reply states it.
    #[test]
    fn the_lms_offers_its_own_variant() {
        for (beams, angle, resolution) in [(361, 180, 50), (181, 180, 100), (401, 100, 25)] {
            let variant = sick::lms_variant(beams).expect("an LMS variant");
            let mut lms = LmsEmulator::with_variant(variant);
            let own = answer(&mut lms, Telegram::set_variant(angle, resolution));
            let mut expected = vec![1];
            expected.extend(angle.to_le_bytes());
            expected.extend(resolution.to_le_bytes());
            assert_eq!(own.data, expected);
            let other = answer(
                &mut lms,
                Telegram::set_variant(180, if resolution == 50 { 100 } else { 50 }),
            );
            assert_eq!(
                other.data[0], 0,
                "{angle}° at {resolution}: another variant refused"
            );
        }
    }
}

/// The served twin's topics: no odometry (the host computes it from the firmware's counts), so
/// the truth places the base (`map` → `base_link`), beside `/scan`, `/ground_truth`, `/clock` and
/// the head's joints.
fn announce(live: &ServedLive, twin: &Twin) {
    use robot::logs::ros2::Encoded;
    let statics = crate::output::static_transforms(&live.mount, &[]);
    live.server
        .publish("/tf_static", Stamp::ZERO, &Encoded::of(&statics));
    let empty = crate::output::no_scan();
    let _ = twin;
    for (topic, msg) in served_topics(live, &empty, robot::Pose2::IDENTITY) {
        live.server.advertise(topic, &msg);
    }
}

fn served_topics(
    live: &ServedLive,
    scan: &LaserScan,
    truth: robot::Pose2,
) -> Vec<(&'static str, robot::logs::ros2::Encoded)> {
    use robot::logs::ros2::{ClockMsg, Encoded, Header, PoseStampedMsg, TfMessage, Transform};
    let t = scan.stamp;
    let mut tf = vec![robot::logs::ros2::TransformStamped {
        header: Header::new(t, "map"),
        child_frame_id: "base_link".into(),
        transform: Transform::planar(truth),
    }];
    if let Some(head) = scan.head {
        tf.extend(crate::output::head_transforms(&live.mount, t, head));
    }
    let period = live.scan_period_s;
    vec![
        ("/clock", Encoded::of(&ClockMsg(t))),
        ("/tf", Encoded::of(&TfMessage(tf))),
        (
            "/ground_truth",
            Encoded::of(&PoseStampedMsg {
                header: Header::new(t, "map"),
                pose: Transform::planar(truth),
            }),
        ),
        ("/scan", Encoded::of(&crate::output::scan_msg(scan, period))),
    ]
}

fn publish(live: &ServedLive, twin: &Twin, scan: &LaserScan) {
    let truth = twin
        .true_pose_at(scan.stamp)
        .unwrap_or_else(|| twin.true_pose());
    for (topic, msg) in served_topics(live, scan, truth) {
        live.server.publish(topic, scan.stamp, &msg);
    }
}

/// `twin serve`: run the twin in (scaled) real time and offer its devices byte for byte, as the
/// robot's serial ports would: the base and pan-tilt firmware and the SICK LMS's telegrams, on
/// TCP ports or pseudo-terminals. Runs until killed (or for --duration).
#[derive(Clone, Debug, clap::Args)]
pub struct ServeArgs {
    /// The scenario file: its world, robot, noise and seed (its script is not run).
    pub scenario: std::path::PathBuf,
    /// Where to offer the base microcontroller: tcp:HOST:PORT (port 0: any free) or pty.
    #[arg(long)]
    pub base: Offer,
    /// Where to offer the pan-tilt microcontroller (robots with a pan-tilt).
    #[arg(long = "pantilt")]
    pub pan_tilt: Option<Offer>,
    /// Where to offer the laser.
    #[arg(long)]
    pub laser: Option<Offer>,
    /// Simulated seconds per wall-clock second.
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Stop after this many simulated seconds.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Seed replacing the scenario's.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Also publish the scans and the true pose over the Foxglove WebSocket protocol on this
    /// address (e.g. 127.0.0.1:8765).
    #[arg(long, value_name = "ADDR")]
    pub live: Option<String>,
    /// Print only the addresses and errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `twin serve`.
pub fn main(args: ServeArgs) -> Result<(), super::CommandError> {
    use super::CommandError;

    if !(args.speed > 0.0 && args.speed <= 1000.0) {
        return Err(CommandError::option(
            "--speed",
            "must be above 0 and at most 1000",
            args.speed,
        ));
    }
    let duration = match args.duration {
        Some(d) if d > 0.0 && d.is_finite() => Some(Duration::from_secs_f64(d)),
        Some(d) => {
            return Err(CommandError::option(
                "--duration",
                "must be a positive number of seconds",
                d,
            ));
        }
        None => None,
    };
    let scenario = crate::config::Scenario::load(&args.scenario)?;
    // The host reads a scan's field from its count of values, as an LMS sends it.
    let laser = &scenario.robot.laser;
    let spans = sick::lms_variant(usize::from(laser.beams))
        .is_some_and(|(angle, _)| f64::from(angle) == laser.fov_deg.get());
    if !spans {
        return Err(CommandError::option(
            "the scenario",
            "must give its robot an LMS to serve (181 or 361 beams over 180°, 101, 201 or 401 over 100°)",
            format!("{} beams over {}°", laser.beams, laser.fov_deg.get()),
        ));
    }
    let twin = Twin::new(
        &scenario.world,
        &scenario.robot,
        &scenario.noise,
        args.seed.unwrap_or(scenario.seed),
    )?;
    let live = match &args.live {
        Some(addr) => Some(ServedLive {
            server: std::sync::Arc::new(super::live::LiveServer::start(addr)?),
            mount: scenario.robot.mount(),
            scan_period_s: crate::output::scan_period_s(&scenario.robot.laser),
        }),
        None => None,
    };
    let options = ServeOptions {
        speed: args.speed,
        base: args.base,
        pan_tilt: args.pan_tilt,
        laser: args.laser,
        live,
    };
    let mut server = Server::new(twin, &options)?;
    // SIGINT and SIGTERM end the run like --duration does: the statistics are printed. The
    // handlers are in place before the addresses are printed, so a client that reads them and
    // stops the server at once finds it ready to stop cleanly.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, std::sync::Arc::clone(&stop)).map_err(|source| {
            CommandError::Io {
                what: "installing the signal handlers",
                source,
            }
        })?;
    }
    say!(
        "serving {} ({}) at {}x real time",
        scenario.name,
        scenario.robot.name,
        options.speed
    );
    for (device, address) in server.addresses() {
        say!("{device:<9} {address}");
    }
    if let Some(live) = &options.live {
        say!("live      ws://{} (Foxglove WebSocket)", live.server.addr());
    }
    std::io::stdout()
        .flush()
        .map_err(|source| CommandError::Io {
            what: "writing stdout",
            source,
        })?;
    let quiet = args.quiet;
    server.run(&stop, duration, |t, line| {
        if !quiet {
            eprintln!("[{t}] {line}");
        }
    });
    if !quiet {
        for (device, stats) in server.stats() {
            say!(
                "{device}: {} connection(s), {} bytes in ({} dropped), {} messages, {} bytes out ({} lost)",
                stats.connections,
                stats.bytes_in,
                stats.bytes_dropped_in,
                stats.messages_in,
                stats.bytes_out,
                stats.bytes_dropped_out
            );
        }
    }
    Ok(())
}
