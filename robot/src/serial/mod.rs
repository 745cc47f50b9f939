//! [`SerialRobot`]: the real robot behind the hardware contract, over three byte streams.
//!
//! The base and pan-tilt microcontrollers speak App. A's line protocol at 9600 bps; the SICK LMS
//! speaks its binary telegrams. Each stream opens from an [`Endpoint`]: a serial device path, or
//! `tcp:HOST:PORT` (a serial-over-IP bridge, or `twin serve`, the twin's serial face). The same
//! controller code then drives the real robot and the twin.
//!
//! What the backend does when the line misbehaves:
//!
//! - **Timeouts.** Every wait has a deadline on the [`Clock`] the caller passes in (robot code
//!   never reads the wall clock itself); a stream read waits at most the poll interval, so nothing
//!   hangs. A request that gets no reply in time is sent again, up to
//!   [`SerialConfig::attempts`] times, and then fails with [`SerialError::Timeout`].
//! - **Garbage.** Lines that are not printable, over-long runs without a newline and lines that are
//!   not the reply expected (a pan-tilt narrating its homing, a late reply) are skipped and
//!   reported; after a timeout or garbage the input is drained before the next request, so a late
//!   reply is never taken for the next one's. The laser's decoder skips noise to the next telegram
//!   with a good CRC.
//! - **Dropped streams.** A stream that closes is reopened and the request repeated. Queries and
//!   absolute commands are repeated as they are; a relative motion (`a r i d`) whose
//!   acknowledgement was lost is repeated only if the base's `l` shows both motors off (had it
//!   arrived, they would be running), so a motion is not driven twice — unless it arrived, ran and
//!   ended entirely inside the outage.
//!
//! Everything of this kind is recorded as a [`LinkEvent`]: [`SerialRobot::take_events`] hands
//! them over.

mod head;
mod laser;
mod port;

pub use port::{Endpoint, EndpointError, Port, open};

use crate::hardware::{
    ArgumentError, Batteries, BatteryVoltages, DriveBase, DriveCommand, DriveStatus, DriveWait,
    ErrorKind, Hardware, HardwareError, Laser, LaserScan, PanTilt, PanTiltCommand, PanTiltStatus,
    PanTiltWait, SonarCommand, SonarEchoes, SonarRing,
};
use crate::protocol::base::{self, ReplyError};
use crate::protocol::line::{LineLink, LinkError};
use crate::protocol::pan_tilt as pt;
use crate::protocol::serial_time;
use crate::protocol::sick::{self, Frame, LmsConfig, Telegram};
use crate::time::{Clock, Stamp};
use core::fmt;
use core::time::Duration;
use laser::{LaserLink, LaserTiming};
use std::sync::Arc;

/// One of the robot's three serial devices.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Device {
    /// The base microcontroller: drive, sonar ring, batteries.
    Base,
    /// The pan-tilt microcontroller.
    PanTilt,
    /// The SICK LMS.
    Laser,
}

impl fmt::Display for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Device::Base => "base",
            Device::PanTilt => "pan-tilt",
            Device::Laser => "laser",
        })
    }
}

/// Something that happened on a link: a reconnection, skipped garbage, a repeated request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LinkEvent {
    /// When, on the backend's clock.
    pub stamp: Stamp,
    /// On which device's line.
    pub device: Device,
    /// What happened.
    pub what: String,
}

impl fmt::Display for LinkEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{}] {}: {}", self.stamp, self.device, self.what)
    }
}

/// How to reach the devices and how patient to be.
#[derive(Clone, Debug)]
pub struct SerialConfig {
    /// The base microcontroller.
    pub base: Endpoint,
    /// The pan-tilt microcontroller, if the robot has one.
    pub pan_tilt: Option<Endpoint>,
    /// The laser, if the robot has one.
    pub laser: Option<Endpoint>,
    /// Rate of the base's line (App. A: 9600).
    pub base_baud: u32,
    /// Rate of the pan-tilt's line (9600).
    pub pan_tilt_baud: u32,
    /// Rate of the laser's line (38400 once switched; the thesis ran it at 9600).
    pub laser_baud: u32,
    /// Time the LMS's mirror takes for one scan.
    pub laser_sweep: Duration,
    /// The laser's no-return value, millimetres.
    pub laser_range_max_mm: u16,
    /// Check the LMS reports millimetres over 32 m (and 180° at 0.5°), configuring it if not.
    pub configure_laser: bool,
    /// Longest wait for a reply beyond the request's own duration (robot clock).
    pub reply_timeout: Duration,
    /// How many times a request is tried before it fails.
    pub attempts: u32,
    /// Longest single read of a stream (wall time): how often deadlines are checked.
    pub poll: Duration,
    /// Longest the pan-tilt may take to home at power-up (robot clock).
    pub homing_limit: Duration,
    /// The pan-tilt head's geometry and units, when the laser rides on it: every scan then
    /// carries the head's angles at its stamp, from the pan-tilt's reports.
    pub head: Option<crate::mount::HeadGeometry>,
}

impl SerialConfig {
    /// The thesis's robot on `base`, without pan-tilt or laser: 9600 bps lines, an LMS at 38400 bps
    /// with a 26.67 ms sweep and 32 m range, a 1 s reply timeout, three attempts, 10 ms polls.
    pub fn new(base: Endpoint) -> Self {
        SerialConfig {
            base,
            pan_tilt: None,
            laser: None,
            base_baud: 9600,
            pan_tilt_baud: 9600,
            laser_baud: 38_400,
            laser_sweep: Duration::from_micros(26_670),
            laser_range_max_mm: 32_000,
            configure_laser: true,
            reply_timeout: Duration::from_secs(1),
            attempts: 3,
            poll: Duration::from_millis(10),
            homing_limit: Duration::from_secs(120),
            head: None,
        }
    }
}

/// A failure of the serial backend.
#[derive(Debug, thiserror::Error)]
pub enum SerialError {
    /// An argument outside the documented range; nothing was sent.
    #[error(transparent)]
    Argument(#[from] ArgumentError),
    /// The device's stream cannot be opened.
    #[error("{device}: cannot open {endpoint}: {reason}")]
    Open {
        /// Which device.
        device: Device,
        /// Its address.
        endpoint: String,
        /// Why.
        reason: String,
    },
    /// No reply in time, however often the request was sent.
    #[error("{device}: no reply to `{request}` after {attempts} attempt(s) of {waited:?} each")]
    Timeout {
        /// Which device.
        device: Device,
        /// The request, without its newline.
        request: String,
        /// How long each attempt waited (robot clock).
        waited: Duration,
        /// Attempts made.
        attempts: u32,
    },
    /// The stream kept dropping.
    #[error("{device}: the link dropped during `{request}` ({reason}) and did not come back")]
    Disconnected {
        /// Which device.
        device: Device,
        /// The request.
        request: String,
        /// The last failure.
        reason: String,
    },
    /// A reply the protocol does not allow.
    #[error("{device}: {source}")]
    Reply {
        /// Which device.
        device: Device,
        /// What was wrong.
        #[source]
        source: ReplyError,
    },
    /// The laser answered something unexpected or refused a request.
    #[error("laser: {0}")]
    Laser(String),
    /// The robot has no such device.
    #[error("this robot has no {0}")]
    Unsupported(&'static str),
}

impl HardwareError for SerialError {
    fn kind(&self) -> ErrorKind {
        match self {
            SerialError::Argument(_) => ErrorKind::InvalidArgument,
            SerialError::Open { .. } | SerialError::Disconnected { .. } => ErrorKind::Disconnected,
            SerialError::Timeout { .. } => ErrorKind::Timeout,
            SerialError::Reply { .. } | SerialError::Laser(_) => ErrorKind::Protocol,
            SerialError::Unsupported(_) => ErrorKind::Unsupported,
        }
    }
}

/// What one attempt at a request gave.
enum Outcome {
    Reply(Stamp, String),
    TimedOut,
    Dropped(String),
}

/// Whether a request may simply be sent again after a failure.
#[derive(Copy, Clone, PartialEq, Eq)]
enum Retry {
    Yes,
    Never,
}

/// What the backend needs to talk: the clock, patience, and where to note what happened.
struct Ctx<'a> {
    clock: &'a dyn Clock,
    poll: Duration,
    attempts: u32,
    events: &'a mut Vec<LinkEvent>,
}

impl Ctx<'_> {
    fn note(&mut self, device: Device, what: impl Into<String>) {
        let stamp = self.clock.now();
        self.events.push(LinkEvent {
            stamp,
            device,
            what: what.into(),
        });
    }
}

/// A microcontroller's line.
struct LineDevice {
    device: Device,
    endpoint: Endpoint,
    baud: u32,
    link: Option<LineLink<Box<dyn Port>>>,
    /// Something may be left in the input (a late reply, garbage): drain before the next request.
    stale: bool,
    /// Lines skipped while waiting for replies since the last [`LineDevice::take_skipped`].
    skipped: Vec<String>,
}

impl LineDevice {
    fn new(device: Device, endpoint: Endpoint, baud: u32) -> Self {
        LineDevice {
            device,
            endpoint,
            baud,
            link: None,
            stale: false,
            skipped: Vec::new(),
        }
    }

    fn connect(&mut self, ctx: &mut Ctx<'_>) -> Result<(), String> {
        if self.link.is_some() {
            return Ok(());
        }
        let port = open(&self.endpoint, self.baud, ctx.poll).map_err(|e| e.to_string())?;
        let mut link = LineLink::new(port);
        // End whatever partial line the firmware holds (noise, a command cut by the drop): it
        // executes the bare newline as an unknown command and says nothing.
        link.send("\n").map_err(|e| e.to_string())?;
        self.link = Some(link);
        ctx.note(self.device, format!("connected to {}", self.endpoint));
        Ok(())
    }

    /// Reads and discards what is waiting, until a read finds nothing.
    fn drain(&mut self, ctx: &mut Ctx<'_>) {
        self.stale = false;
        let Some(link) = self.link.as_mut() else {
            return;
        };
        for _ in 0..64 {
            match link.read_line() {
                Ok(line) => {
                    ctx.note(self.device, format!("discarded a late line {line:?}"));
                    self.skipped.push(line);
                }
                Err(LinkError::Timeout) => return,
                Err(LinkError::Disconnected | LinkError::Io(_)) => {
                    self.link = None;
                    return;
                }
                Err(e) => ctx.note(self.device, format!("discarded: {e}")),
            }
        }
    }

    /// Sends `line` once and waits for the line starting with `letter`, until `extra` (plus the
    /// line's own transmission time) has passed on the clock.
    fn attempt(&mut self, line: &str, letter: char, extra: Duration, ctx: &mut Ctx<'_>) -> Outcome {
        let Some(link) = self.link.as_mut() else {
            return Outcome::Dropped("not connected".into());
        };
        if let Err(e) = link.send(line) {
            return Outcome::Dropped(e.to_string());
        }
        let deadline = ctx.clock.now() + serial_time(line.len(), self.baud) + extra;
        loop {
            if ctx.clock.now() > deadline {
                self.stale = true;
                return Outcome::TimedOut;
            }
            match link.read_line() {
                Ok(reply) if reply.starts_with(letter) => {
                    let now = ctx.clock.now().0;
                    let on_line = serial_time(reply.len(), self.baud).as_nanos() as u64;
                    return Outcome::Reply(Stamp(now.saturating_sub(on_line)), reply);
                }
                Ok(other) => {
                    ctx.note(
                        self.device,
                        format!(
                            "skipped a line that is not the reply to `{}`: {other:?}",
                            line.trim_end()
                        ),
                    );
                    self.skipped.push(other);
                }
                Err(LinkError::Timeout) => {}
                Err(LinkError::Disconnected) => {
                    return Outcome::Dropped("the stream closed".into());
                }
                Err(LinkError::Io(e)) => return Outcome::Dropped(e.to_string()),
                Err(e) => {
                    self.stale = true;
                    ctx.note(self.device, format!("skipped: {e}"));
                }
            }
        }
    }

    /// The next line (any), until `deadline`.
    fn next_line(&mut self, deadline: Stamp, ctx: &mut Ctx<'_>) -> Outcome {
        let Some(link) = self.link.as_mut() else {
            return Outcome::Dropped("not connected".into());
        };
        loop {
            if ctx.clock.now() > deadline {
                self.stale = true;
                return Outcome::TimedOut;
            }
            match link.read_line() {
                Ok(line) => return Outcome::Reply(ctx.clock.now(), line),
                Err(LinkError::Timeout) => {}
                Err(LinkError::Disconnected) => {
                    return Outcome::Dropped("the stream closed".into());
                }
                Err(LinkError::Io(e)) => return Outcome::Dropped(e.to_string()),
                Err(e) => ctx.note(self.device, format!("skipped: {e}")),
            }
        }
    }

    /// Sends `line` and returns the reply starting with `letter` and its stamp, trying again
    /// (reconnecting when the stream dropped) up to `attempts` times if `retry` allows.
    fn request(
        &mut self,
        line: &str,
        letter: char,
        extra: Duration,
        retry: Retry,
        ctx: &mut Ctx<'_>,
    ) -> Result<(Stamp, String), SerialError> {
        let request = line.trim_end().to_string();
        let attempts = if retry == Retry::Yes {
            ctx.attempts.max(1)
        } else {
            1
        };
        let mut failure = SerialError::Timeout {
            device: self.device,
            request: request.clone(),
            waited: extra,
            attempts,
        };
        for attempt in 1..=attempts {
            if let Err(reason) = self.connect(ctx) {
                ctx.note(
                    self.device,
                    format!("cannot open {}: {reason}", self.endpoint),
                );
                failure = SerialError::Open {
                    device: self.device,
                    endpoint: self.endpoint.to_string(),
                    reason,
                };
                // Give a bridge or a re-plugged adapter a moment before the next attempt.
                std::thread::sleep(ctx.poll * 10);
                continue;
            }
            if self.stale {
                self.drain(ctx);
                if self.link.is_none() {
                    continue;
                }
            }
            match self.attempt(line, letter, extra, ctx) {
                Outcome::Reply(stamp, reply) => return Ok((stamp, reply)),
                Outcome::TimedOut => {
                    ctx.note(
                        self.device,
                        format!("no reply to `{request}` (attempt {attempt} of {attempts})"),
                    );
                    failure = SerialError::Timeout {
                        device: self.device,
                        request: request.clone(),
                        waited: extra,
                        attempts,
                    };
                }
                Outcome::Dropped(reason) => {
                    self.link = None;
                    ctx.note(
                        self.device,
                        format!("link dropped during `{request}` ({reason}): reconnecting"),
                    );
                    failure = SerialError::Disconnected {
                        device: self.device,
                        request: request.clone(),
                        reason,
                    };
                }
            }
        }
        Err(failure)
    }

    fn take_skipped(&mut self) -> Vec<String> {
        std::mem::take(&mut self.skipped)
    }
}

/// When the ring fires, as the base was told: enough to work out when each reading was taken.
#[derive(Clone, Debug)]
struct SonarSchedule {
    sequence: Vec<u8>,
    echo_ms: u16,
    relax_ms: u16,
    firing_since: Option<Stamp>,
}

impl SonarSchedule {
    /// The firmware's power-on settings: all 16 in order, 50 ms echo window, 20 ms relax.
    fn power_on() -> Self {
        SonarSchedule {
            sequence: (0..16).collect(),
            echo_ms: 50,
            relax_ms: 20,
            firing_since: None,
        }
    }

    /// When position `i` of the sequence was last stored, as of `now`: `sonar_demon` fires, arms,
    /// counts the echo window, relaxes and steps, one 1.024 ms tick each plus the two windows.
    fn measured(&self, i: usize, now: Stamp) -> Option<Stamp> {
        let t0 = self.firing_since?;
        let tick = 1_024_000u64;
        let n = self.sequence.len().max(1) as u64;
        let shot = (u64::from(self.echo_ms) + u64::from(self.relax_ms) + 3) * tick;
        let stored = (u64::from(self.echo_ms) + 1) * tick;
        let first = t0.0 + i as u64 * shot + stored;
        if now.0 < first {
            return None;
        }
        let cycles = (now.0 - first) / (n * shot);
        Some(Stamp(first + cycles * n * shot))
    }
}

/// The real robot (or `twin serve`) behind the hardware contract; see the [module](self) docs.
pub struct SerialRobot {
    config: SerialConfig,
    clock: Arc<dyn Clock>,
    base: LineDevice,
    pan_tilt: Option<LineDevice>,
    pan_tilt_ready: bool,
    laser: Option<LaserLink>,
    laser_configured: bool,
    sonar: SonarSchedule,
    head: Option<head::HeadTrack>,
    events: Vec<LinkEvent>,
}

impl SerialRobot {
    /// Opens the devices of `config`, stamping with `clock`. The base must answer a `*`; the
    /// laser (if any) is checked, configured if needed and set streaming. The pan-tilt is
    /// contacted on first use (it may still be homing).
    pub fn open(config: SerialConfig, clock: Arc<dyn Clock>) -> Result<Self, SerialError> {
        let mut robot = SerialRobot {
            base: LineDevice::new(Device::Base, config.base.clone(), config.base_baud),
            pan_tilt: config
                .pan_tilt
                .clone()
                .map(|e| LineDevice::new(Device::PanTilt, e, config.pan_tilt_baud)),
            pan_tilt_ready: false,
            laser: None,
            laser_configured: false,
            sonar: SonarSchedule::power_on(),
            head: config.head.map(head::HeadTrack::new),
            events: Vec::new(),
            config,
            clock,
        };
        // Whatever the base said before (its power-on greeting) is stale.
        robot.base.stale = true;
        robot.base_request("*\n", '*', Duration::ZERO, Retry::Yes)?;
        if robot.config.laser.is_some() {
            robot.laser_link()?;
        }
        Ok(robot)
    }

    /// The clock the backend stamps with.
    pub fn clock(&self) -> &Arc<dyn Clock> {
        &self.clock
    }

    /// What happened on the links since the last call: reconnections, skipped garbage, repeated
    /// requests.
    pub fn take_events(&mut self) -> Vec<LinkEvent> {
        self.absorb_laser_notes();
        std::mem::take(&mut self.events)
    }

    /// Moves what the laser's reader noted into the event list.
    fn absorb_laser_notes(&mut self) {
        if let Some(laser) = &self.laser {
            let (notes, dropped) = laser.take_notes();
            let stamp = self.clock.now();
            for what in notes {
                self.events.push(LinkEvent {
                    stamp,
                    device: Device::Laser,
                    what,
                });
            }
            if dropped > 0 {
                self.events.push(LinkEvent {
                    stamp,
                    device: Device::Laser,
                    what: format!("{dropped} scan(s) dropped unread (queue full)"),
                });
            }
        }
    }

    fn base_request(
        &mut self,
        line: &str,
        letter: char,
        works_for: Duration,
        retry: Retry,
    ) -> Result<(Stamp, String), SerialError> {
        let extra = works_for + self.config.reply_timeout;
        let (mut ctx, device) = self.line(Device::Base)?;
        device.request(line, letter, extra, retry, &mut ctx)
    }

    /// What talking on a line needs, and the line of `device` (the base unless the pan-tilt).
    fn line(&mut self, device: Device) -> Result<(Ctx<'_>, &mut LineDevice), SerialError> {
        let line = match device {
            Device::PanTilt => self
                .pan_tilt
                .as_mut()
                .ok_or(SerialError::Unsupported("pan-tilt unit"))?,
            _ => &mut self.base,
        };
        let ctx = Ctx {
            clock: self.clock.as_ref(),
            poll: self.config.poll,
            attempts: self.config.attempts,
            events: &mut self.events,
        };
        Ok((ctx, line))
    }

    fn pan_tilt_request(
        &mut self,
        line: &str,
        letter: char,
        works_for: Duration,
    ) -> Result<(Stamp, String), SerialError> {
        self.wait_pan_tilt_ready()?;
        let extra = works_for + self.config.reply_timeout;
        let (mut ctx, device) = self.line(Device::PanTilt)?;
        device.request(line, letter, extra, Retry::Yes, &mut ctx)
    }

    /// Waits until the pan-tilt has finished homing: a `*` must come back, and if the unit is
    /// still narrating its homing (or a motor runs) the backend waits for its `Listo`. Returns at
    /// once after the first time.
    pub fn wait_pan_tilt_ready(&mut self) -> Result<(), SerialError> {
        if self.pan_tilt_ready {
            return Ok(());
        }
        let extra = self.config.reply_timeout;
        let homing_limit = self.config.homing_limit;
        let (mut ctx, device) = self.line(Device::PanTilt)?;
        device.request("*\n", '*', extra, Retry::Yes, &mut ctx)?;
        let narrated = device.take_skipped();
        let mut homing = !narrated.is_empty() && !narrated.iter().any(|l| l == pt::READY);
        if !homing {
            let (stamp, reply) =
                device.request(pt::STATUS_REQUEST, 'l', extra, Retry::Yes, &mut ctx)?;
            let status = pt::parse_status(&reply, stamp).map_err(|source| SerialError::Reply {
                device: Device::PanTilt,
                source,
            })?;
            homing = !status.idle() && !device.take_skipped().iter().any(|l| l == pt::READY);
        }
        if homing {
            ctx.note(Device::PanTilt, "homing: waiting for `Listo`");
            let deadline = ctx.clock.now() + homing_limit;
            loop {
                match device.next_line(deadline, &mut ctx) {
                    Outcome::Reply(_, line) if line == pt::READY => break,
                    Outcome::Reply(..) => {}
                    Outcome::TimedOut => {
                        return Err(SerialError::Timeout {
                            device: Device::PanTilt,
                            request: "(power-up homing)".into(),
                            waited: homing_limit,
                            attempts: 1,
                        });
                    }
                    Outcome::Dropped(reason) => {
                        device.link = None;
                        return Err(SerialError::Disconnected {
                            device: Device::PanTilt,
                            request: "(power-up homing)".into(),
                            reason,
                        });
                    }
                }
            }
        }
        self.pan_tilt_ready = true;
        Ok(())
    }

    fn reply_error(device: Device) -> impl FnOnce(ReplyError) -> SerialError {
        move |source| SerialError::Reply { device, source }
    }
}

// ------------------------------------------------------------------------------------ laser

impl SerialRobot {
    fn laser_timing(&self) -> LaserTiming {
        LaserTiming {
            baud: self.config.laser_baud,
            sweep: self.config.laser_sweep,
            range_max_mm: self.config.laser_range_max_mm,
        }
    }

    /// The laser's link, (re)opened, configured once and set streaming.
    fn laser_link(&mut self) -> Result<&mut LaserLink, SerialError> {
        let endpoint = self
            .config
            .laser
            .clone()
            .ok_or(SerialError::Unsupported("laser"))?;
        if self.laser.as_ref().is_some_and(|l| !l.alive()) {
            // Keep what the reader noted before it stopped.
            self.absorb_laser_notes();
            self.laser = None;
            self.note(Device::Laser, "link dropped: reconnecting");
        }
        if self.laser.is_none() {
            let mut failure = String::new();
            for attempt in 1..=self.config.attempts.max(1) {
                match LaserLink::open(
                    &endpoint,
                    &self.laser_timing(),
                    self.config.poll,
                    Arc::clone(&self.clock),
                ) {
                    Ok(link) => {
                        self.laser = Some(link);
                        break;
                    }
                    Err(e) => {
                        failure = e.to_string();
                        self.note(
                            Device::Laser,
                            format!("cannot open {endpoint} (attempt {attempt}): {failure}"),
                        );
                        std::thread::sleep(self.config.poll * 10);
                    }
                }
            }
            if self.laser.is_none() {
                return Err(SerialError::Open {
                    device: Device::Laser,
                    endpoint: endpoint.to_string(),
                    reason: failure,
                });
            }
            self.note(Device::Laser, format!("connected to {endpoint}"));
            if self.config.configure_laser && !self.laser_configured {
                self.configure_laser()?;
                self.laser_configured = true;
            }
            self.laser_request(
                &Telegram::set_mode(sick::MODE_STREAM_VALUES),
                sick::MODE_REPLY,
            )
            .and_then(|reply| match reply.data.first() {
                Some(0) => Ok(()),
                other => Err(SerialError::Laser(format!(
                    "streaming mode refused (A0 status {other:?})"
                ))),
            })?;
        }
        Ok(self.laser.as_mut().expect("opened above"))
    }

    fn note(&mut self, device: Device, what: impl Into<String>) {
        let stamp = self.clock.now();
        self.events.push(LinkEvent {
            stamp,
            device,
            what: what.into(),
        });
    }

    /// Sends a request telegram and returns the reply with command `reply`, after the LMS's
    /// ACK; a NAK or silence is tried again.
    fn laser_request(&mut self, request: &Telegram, reply: u8) -> Result<Telegram, SerialError> {
        let attempts = self.config.attempts.max(1);
        let timeout = self.config.reply_timeout;
        let poll = self.config.poll;
        let clock = Arc::clone(&self.clock);
        let mut failure = String::from("no reply");
        for attempt in 1..=attempts {
            let link = self
                .laser
                .as_mut()
                .ok_or(SerialError::Unsupported("laser"))?;
            link.clear_replies();
            if let Err(e) = link.send(request) {
                failure = e.to_string();
                break;
            }
            let deadline = clock.now() + timeout;
            let mut got = None;
            while clock.now() <= deadline && link.alive() {
                match link.next_reply(poll) {
                    Some(Frame::Telegram(t)) if t.command == reply => {
                        got = Some(t);
                        break;
                    }
                    Some(Frame::Nak) => {
                        failure = "NAK".into();
                        break;
                    }
                    _ => {}
                }
            }
            if let Some(t) = got {
                return Ok(t);
            }
            self.note(
                Device::Laser,
                format!(
                    "request 0x{:02X}: {failure} (attempt {attempt} of {attempts})",
                    request.command
                ),
            );
        }
        Err(SerialError::Laser(format!(
            "request 0x{:02X} got no reply 0x{reply:02X}: {failure}",
            request.command
        )))
    }

    /// Reads the LMS's configuration and, unless it reports millimetres over 32 m, writes that
    /// (installation mode, `77`); then selects 180° at 0.5° (`3B`).
    fn configure_laser(&mut self) -> Result<(), SerialError> {
        let laser_error = |e: sick::ConfigError| SerialError::Laser(e.to_string());
        let reply = self.laser_request(&Telegram::request_config(), sick::CONFIG_REPLY)?;
        let config = LmsConfig::from_reply(&reply).map_err(laser_error)?;
        if !config.is_mm_32m() {
            self.note(
                Device::Laser,
                "configuring millimetres over 32 m (installation mode)",
            );
            let mode = self.laser_request(
                &Telegram::set_mode(sick::MODE_INSTALLATION),
                sick::MODE_REPLY,
            )?;
            if mode.data.first() != Some(&0) {
                return Err(SerialError::Laser("installation mode refused".into()));
            }
            let done = self.laser_request(
                &Telegram::set_config(&config.with_mm_32m()),
                sick::SET_CONFIG_REPLY,
            )?;
            LmsConfig::from_reply(&done).map_err(laser_error)?;
        }
        let variant = self.laser_request(&Telegram::set_variant(180, 50), sick::VARIANT_REPLY)?;
        if variant.data.first() != Some(&1) {
            return Err(SerialError::Laser(
                "the LMS refused the 180°, 0.5° variant".into(),
            ));
        }
        Ok(())
    }
}

impl Hardware for SerialRobot {
    type Error = SerialError;
}

impl DriveBase for SerialRobot {
    fn drive(&mut self, command: DriveCommand) -> Result<(), SerialError> {
        let line = base::encode_command(&command)?;
        let letter = command.letter();
        let relative = matches!(
            command,
            DriveCommand::Advance(_)
                | DriveCommand::Retreat(_)
                | DriveCommand::TurnLeft(_)
                | DriveCommand::TurnRight(_)
        );
        let retry = if relative { Retry::Never } else { Retry::Yes };
        let reply = match self.base_request(&line, letter, Duration::ZERO, retry) {
            Ok((_, reply)) => reply,
            Err(e)
                if relative && matches!(e.kind(), ErrorKind::Timeout | ErrorKind::Disconnected) =>
            {
                // Did it arrive? A motion that arrived has its motors running.
                let status = self.drive_status()?;
                if status.left_on || status.right_on {
                    self.note(
                        Device::Base,
                        format!(
                            "`{}` was not acknowledged but the motors run: it arrived",
                            line.trim_end()
                        ),
                    );
                    return Ok(());
                }
                self.note(
                    Device::Base,
                    format!("`{}` did not arrive: sending it again", line.trim_end()),
                );
                self.base_request(&line, letter, Duration::ZERO, Retry::Yes)?
                    .1
            }
            Err(e) => return Err(e),
        };
        base::parse_ack(&reply, letter).map_err(Self::reply_error(Device::Base))
    }

    fn wait_drive(&mut self, wait: DriveWait) -> Result<(), SerialError> {
        let line = base::encode_wait(&wait);
        let works_for = Duration::from_micros(1024) * u32::from(wait.max_ms);
        let (_, reply) = self.base_request(&line, 'w', works_for, Retry::Yes)?;
        base::parse_ack(&reply, 'w').map_err(Self::reply_error(Device::Base))
    }

    fn drive_status(&mut self) -> Result<DriveStatus, SerialError> {
        let (stamp, reply) =
            self.base_request(base::STATUS_REQUEST, 'l', Duration::ZERO, Retry::Yes)?;
        base::parse_status(&reply, stamp).map_err(Self::reply_error(Device::Base))
    }
}

impl SerialRobot {
    /// The scan with the head's angles at its stamp, when the laser rides on the head.
    fn with_head(&self, mut scan: LaserScan) -> LaserScan {
        scan.head = self.head.as_ref().and_then(|h| h.at(scan.stamp));
        scan
    }
}

impl Laser for SerialRobot {
    fn read_scan(&mut self, timeout: Duration) -> Result<Option<LaserScan>, SerialError> {
        let deadline = self.clock.now() + timeout;
        let poll = self.config.poll;
        loop {
            let link = self.laser_link()?;
            if let Some(scan) = link.next_scan(poll) {
                return Ok(Some(self.with_head(scan)));
            }
            if self.clock.now() > deadline {
                return Ok(None);
            }
        }
    }

    fn read_scan_since(
        &mut self,
        since: Stamp,
        timeout: Duration,
    ) -> Result<Option<LaserScan>, SerialError> {
        let mut deadline = self.clock.now() + timeout;
        let poll = self.config.poll;
        loop {
            let link = self.laser_link()?;
            link.drop_scans_before(since);
            if let Some(scan) = link.next_scan(poll) {
                if scan.stamp >= since {
                    return Ok(Some(self.with_head(scan)));
                }
                // As in the contract's default, the timeout restarts with every scan.
                deadline = self.clock.now() + timeout;
            }
            if self.clock.now() > deadline {
                return Ok(None);
            }
        }
    }
}

impl SonarRing for SerialRobot {
    fn sonar(&mut self, command: SonarCommand) -> Result<(), SerialError> {
        let (line, letter) = base::encode_sonar(&command)?;
        let (stamp, reply) = self.base_request(&line, letter, Duration::ZERO, Retry::Yes)?;
        base::parse_ack(&reply, letter).map_err(Self::reply_error(Device::Base))?;
        match command {
            SonarCommand::Sequence(sequence) => self.sonar.sequence = sequence,
            SonarCommand::Timing { echo_ms, relax_ms } => {
                self.sonar.echo_ms = echo_ms;
                self.sonar.relax_ms = relax_ms;
            }
            SonarCommand::Firing(true) => self.sonar.firing_since = Some(stamp),
            SonarCommand::Firing(false) => self.sonar.firing_since = None,
        }
        Ok(())
    }

    fn sonar_echoes(&mut self) -> Result<SonarEchoes, SerialError> {
        let count = self.sonar.sequence.len();
        let mut failure = None;
        for _ in 0..self.config.attempts.max(1) {
            let (stamp, first) =
                self.base_request(base::SONAR_REQUEST, 's', Duration::ZERO, Retry::Yes)?;
            let deadline = self.clock.now() + self.config.reply_timeout;
            let mut lines = vec![first];
            let (mut ctx, device) = self.line(Device::Base)?;
            while lines.len() < count {
                match device.next_line(deadline, &mut ctx) {
                    Outcome::Reply(_, line) => lines.push(line),
                    Outcome::TimedOut => break,
                    Outcome::Dropped(_) => {
                        device.link = None;
                        break;
                    }
                }
            }
            let refs: Vec<&str> = lines.iter().map(String::as_str).collect();
            match base::parse_sonar_report(&refs, count) {
                Ok(times) => {
                    return Ok(SonarEchoes {
                        stamp,
                        sequence: self.sonar.sequence.clone(),
                        times,
                        measured: (0..count).map(|i| self.sonar.measured(i, stamp)).collect(),
                    });
                }
                Err(e) => {
                    self.base.stale = true;
                    self.note(
                        Device::Base,
                        format!("sonar report unreadable ({e}): asking again"),
                    );
                    failure = Some(e);
                }
            }
        }
        Err(SerialError::Reply {
            device: Device::Base,
            source: failure.expect("at least one attempt failed"),
        })
    }
}

impl PanTilt for SerialRobot {
    fn pan_tilt(&mut self, command: PanTiltCommand) -> Result<(), SerialError> {
        let line = pt::encode_command(&command)?;
        let letter = command.letter();
        let (stamp, reply) = self.pan_tilt_request(&line, letter, Duration::ZERO)?;
        base::parse_ack(&reply, letter).map_err(Self::reply_error(Device::PanTilt))?;
        if let (Some(head), PanTiltCommand::Pan(_) | PanTiltCommand::Tilt(_)) =
            (&mut self.head, command)
        {
            head.commanded(stamp);
        }
        Ok(())
    }

    fn wait_pan_tilt(&mut self, wait: PanTiltWait) -> Result<(), SerialError> {
        let line = pt::encode_wait(&wait);
        let works_for = Duration::from_micros(1024) * u32::from(wait.max_ms);
        let (_, reply) = self.pan_tilt_request(&line, 'w', works_for)?;
        base::parse_ack(&reply, 'w').map_err(Self::reply_error(Device::PanTilt))
    }

    fn pan_tilt_status(&mut self) -> Result<PanTiltStatus, SerialError> {
        let (stamp, reply) = self.pan_tilt_request(pt::STATUS_REQUEST, 'l', Duration::ZERO)?;
        let status = pt::parse_status(&reply, stamp).map_err(Self::reply_error(Device::PanTilt))?;
        if let Some(head) = &mut self.head {
            head.observe(&status);
        }
        Ok(status)
    }
}

impl Batteries for SerialRobot {
    fn battery_voltages(&mut self) -> Result<BatteryVoltages, SerialError> {
        let (stamp, reply) =
            self.base_request(base::BATTERY_REQUEST, 't', Duration::ZERO, Retry::Yes)?;
        base::parse_battery(&reply, stamp).map_err(Self::reply_error(Device::Base))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sonar_readings_are_dated_by_the_firing_schedule() {
        let mut s = SonarSchedule::power_on();
        s.sequence = vec![0, 4, 8];
        s.echo_ms = 10;
        s.relax_ms = 7;
        let now = Stamp::from_millis(1000);
        assert_eq!(s.measured(0, now), None, "not firing");
        s.firing_since = Some(Stamp::from_millis(100));
        let shot = 20 * 1_024_000;
        // Position 1 is stored one shot and 11 ticks after firing started, then every 3 shots.
        let first = 100_000_000 + shot + 11 * 1_024_000;
        let got = s.measured(1, now).unwrap();
        assert!(got.0 <= now.0 && now.0 - got.0 < 3 * shot);
        assert_eq!((got.0 - first) % (3 * shot), 0);
        assert_eq!(
            s.measured(2, Stamp::from_millis(101)),
            None,
            "not yet fired"
        );
    }
}
