//! [`SimRobot`]: the twin behind the robot crate's hardware contract.
//!
//! Every call goes through the same bytes as on the real robot: a drive command is encoded to its
//! line, sent over the simulated 9600 bps line to the ported firmware, and the firmware's reply is
//! read back and parsed. Time passes the way it does for a real controller: sending takes ten
//! bit-times per byte, the firmware answers when its main loop gets to the line, the reply takes
//! its own transmission time, and a scan arrives when the laser has sent it. The controller's
//! clock (the *host* time) advances with those waits; the world is stepped until it has caught up.
//!
//! The world steps 8.192 ms at a time, so after a wait it may be up to one step ahead of the
//! controller's clock (or further, if you step the twin yourself: that is the controller
//! sleeping). Before every exchange the controller's clock catches up with the world, so a command
//! is never sent into the simulated past; exchanges are thus timed to within one step.
//!
//! The pan-tilt microcontroller has its own serial line. At power-up it homes the head while
//! narrating on that line; the first pan-tilt call waits for its `Listo`, as a real backend must
//! (commands sent during homing would disturb it).
//!
//! Ground truth is not part of the contract: it is offered by the sim-only [`GroundTruth`] trait.

use crate::config::{ConfigError, Scenario};
use crate::devices::laser::LaserFrame;
use crate::twin::{TICK, Twin};
use core::time::Duration;
use robot::hardware::{
    ArgumentError, Batteries, BatteryVoltages, DriveBase, DriveCommand, DriveStatus, DriveWait,
    ErrorKind, Hardware, HardwareError, Laser, LaserScan, PanTilt, PanTiltCommand, PanTiltStatus,
    PanTiltWait, SonarCommand, SonarEchoes, SonarRing,
};
use robot::protocol::base::{
    BATTERY_REQUEST, ReplyError, SONAR_REQUEST, STATUS_REQUEST, encode_command, encode_sonar,
    encode_wait, parse_ack, parse_battery, parse_sonar_report, parse_status,
};
use robot::protocol::pan_tilt as pt_protocol;
use robot::protocol::serial_time;
use robot::{Pose2, Stamp};
use std::collections::VecDeque;

/// How long the twin waits for a reply beyond what the command itself takes.
const REPLY_MARGIN: Duration = Duration::from_millis(500);

/// What the twin knows that the robot does not.
pub trait GroundTruth {
    /// The true pose of the base now.
    fn true_pose(&self) -> Pose2;
    /// The true pose at `t`, or `None` outside the simulated time.
    fn true_pose_at(&self, t: Stamp) -> Option<Pose2>;
    /// Length of the true path so far, metres.
    fn distance_travelled(&self) -> f64;
    /// Times the base came into contact with a wall.
    fn collisions(&self) -> u32;
    /// The laser's true frame at `t` (its optical centre and where it looks), or `None` outside
    /// the simulated time.
    fn laser_frame_at(&self, t: Stamp) -> Option<LaserFrame>;
}

impl GroundTruth for Twin {
    fn true_pose(&self) -> Pose2 {
        Twin::true_pose(self)
    }
    fn true_pose_at(&self, t: Stamp) -> Option<Pose2> {
        Twin::true_pose_at(self, t)
    }
    fn distance_travelled(&self) -> f64 {
        Twin::distance_travelled(self)
    }
    fn collisions(&self) -> u32 {
        Twin::collisions(self)
    }
    fn laser_frame_at(&self, t: Stamp) -> Option<LaserFrame> {
        Twin::laser_frame_at(self, t)
    }
}

/// A failure of the simulated hardware.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// An argument outside the documented range; nothing was sent.
    #[error(transparent)]
    Argument(#[from] ArgumentError),
    /// The firmware did not answer in time (unknown commands get no answer).
    #[error("no reply to `{command}` within {waited:?} of simulated time")]
    Timeout {
        /// The line sent, without its newline.
        command: String,
        /// How long the twin waited.
        waited: Duration,
    },
    /// The firmware answered something the protocol does not allow.
    #[error(transparent)]
    Reply(#[from] ReplyError),
    /// The simulated robot does not have this device.
    #[error("this robot has no {0}")]
    Unsupported(&'static str),
}

impl HardwareError for SimError {
    fn kind(&self) -> ErrorKind {
        match self {
            SimError::Argument(_) => ErrorKind::InvalidArgument,
            SimError::Timeout { .. } => ErrorKind::Timeout,
            SimError::Reply(_) => ErrorKind::Protocol,
            SimError::Unsupported(_) => ErrorKind::Unsupported,
        }
    }
}

/// One of the robot's two microcontroller serial lines.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Port {
    /// The base microcontroller: drive, sonar, batteries.
    Base,
    /// The pan-tilt microcontroller.
    PanTilt,
}

/// The host's end of a serial line.
#[derive(Clone, Debug)]
struct Line {
    /// Bit rate.
    baud: u32,
    /// Bytes received, with their arrival times.
    rx: VecDeque<(Stamp, u8)>,
}

impl Line {
    fn new(baud: u32) -> Self {
        Line {
            baud,
            rx: VecDeque::new(),
        }
    }
}

/// How long the pan-tilt may take to home at power-up before the backend gives up.
const HOMING_LIMIT: Duration = Duration::from_secs(120);

/// The twin, driven through the hardware contract.
pub struct SimRobot {
    twin: Twin,
    /// The controller's clock.
    host: Stamp,
    /// The base microcontroller's line.
    base: Line,
    /// The pan-tilt microcontroller's line, if the robot has one.
    pan_tilt: Option<Line>,
    /// The pan-tilt has said `Listo`.
    pan_tilt_ready: bool,
    /// The sonar firing sequence last set (`S`), the firmware's default at power-on.
    sonar_sequence: Vec<u8>,
}

impl SimRobot {
    /// Wraps a twin whose base talks at `base_baud`, and waits for the base's power-on greeting
    /// (which it discards, as a backend flushes its input when it connects).
    pub fn new(twin: Twin, base_baud: u32) -> Self {
        let pan_tilt = twin.pan_tilt_board().map(|b| Line::new(b.baud()));
        let mut robot = SimRobot {
            twin,
            host: Stamp::ZERO,
            base: Line::new(base_baud),
            pan_tilt,
            pan_tilt_ready: false,
            sonar_sequence: (0..16).collect(),
        };
        let greeting_done =
            robot.read_line(Port::Base, "(power-on greeting)", Stamp::from_millis(500));
        debug_assert!(greeting_done.is_ok(), "the firmware greets at power-on");
        robot.base.rx.clear();
        robot
    }

    /// The twin of a scenario, with its robot at the world's start pose.
    pub fn from_scenario(scenario: &Scenario) -> Result<Self, ConfigError> {
        let twin = Twin::new(
            &scenario.world,
            &scenario.robot,
            &scenario.noise,
            scenario.seed,
        )?;
        Ok(Self::new(twin, scenario.robot.drive.serial_baud))
    }

    /// The twin inside.
    pub fn twin(&self) -> &Twin {
        &self.twin
    }

    /// The twin inside, to step it or look into it.
    pub fn twin_mut(&mut self) -> &mut Twin {
        &mut self.twin
    }

    /// The controller's clock: when its last exchange with the hardware ended.
    pub fn host_time(&self) -> Stamp {
        self.host
    }

    /// Steps the world until it has reached `t`.
    pub fn advance_to(&mut self, t: Stamp) {
        while self.twin.now() < t {
            self.twin.step();
        }
    }

    /// The controller cannot act before the world's present: its clock catches up.
    fn catch_up(&mut self) {
        self.host = self.host.max(self.twin.now());
    }

    fn line_mut(&mut self, port: Port) -> &mut Line {
        match port {
            Port::Base => &mut self.base,
            Port::PanTilt => self
                .pan_tilt
                .as_mut()
                .expect("pan-tilt calls check the unit exists"),
        }
    }

    /// Moves the bytes the microcontroller has sent into the host's receive buffer.
    fn receive(&mut self, port: Port) {
        let mut bytes = Vec::new();
        match port {
            Port::Base => bytes.extend(std::iter::from_fn(|| self.twin.board_mut().pop_output())),
            Port::PanTilt => {
                if let Some(board) = self.twin.pan_tilt_board_mut() {
                    bytes.extend(std::iter::from_fn(|| board.pop_output()));
                }
            }
        }
        self.line_mut(port).rx.extend(bytes);
    }

    /// Sends one line to the base and returns its reply line and when the firmware wrote it.
    fn transact(&mut self, line: &str, works_for: Duration) -> Result<(Stamp, String), SimError> {
        self.transact_on(Port::Base, line, works_for)
    }

    /// Sends one line on `port` and returns the reply line and when the firmware wrote it.
    fn transact_on(
        &mut self,
        port: Port,
        line: &str,
        works_for: Duration,
    ) -> Result<(Stamp, String), SimError> {
        self.catch_up();
        let arrival = self.host + serial_time(line.len(), self.line_mut(port).baud);
        let bytes = line.as_bytes().to_vec();
        match port {
            Port::Base => self.twin.board_mut().deliver(arrival, bytes),
            Port::PanTilt => self
                .twin
                .pan_tilt_board_mut()
                .expect("pan-tilt calls check the unit exists")
                .deliver(arrival, bytes),
        }
        self.host = arrival;
        let deadline = arrival + works_for + REPLY_MARGIN;
        self.read_line(port, line.trim_end(), deadline)
    }

    /// Reads the next complete line from `port`, stepping the world until it has arrived.
    /// Returns when the firmware wrote it and the text.
    fn read_line(
        &mut self,
        port: Port,
        command: &str,
        deadline: Stamp,
    ) -> Result<(Stamp, String), SimError> {
        loop {
            self.receive(port);
            let line = self.line_mut(port);
            if let Some(end) = line.rx.iter().position(|(_, b)| *b == b'\n') {
                let arrived = line.rx[end].0;
                if arrived <= deadline {
                    let written = before(line.rx[0].0, serial_time(1, line.baud));
                    let bytes: Vec<u8> = line.rx.drain(..=end).map(|(_, b)| b).collect();
                    self.host = self.host.max(arrived);
                    return Ok((written, String::from_utf8_lossy(&bytes).into_owned()));
                }
            }
            if self.twin.now() >= deadline {
                let waited = deadline.saturating_since(self.host);
                self.host = self.host.max(deadline);
                return Err(SimError::Timeout {
                    command: command.to_string(),
                    waited,
                });
            }
            self.twin.step();
        }
    }
}

/// `t − d`, or zero.
fn before(t: Stamp, d: Duration) -> Stamp {
    Stamp(t.0.saturating_sub(d.as_nanos() as u64))
}

impl Hardware for SimRobot {
    type Error = SimError;
}

impl DriveBase for SimRobot {
    fn drive(&mut self, command: DriveCommand) -> Result<(), SimError> {
        let line = encode_command(&command)?;
        let (_, reply) = self.transact(&line, Duration::ZERO)?;
        parse_ack(&reply, command.letter())?;
        Ok(())
    }

    fn wait_drive(&mut self, wait: DriveWait) -> Result<(), SimError> {
        let line = encode_wait(&wait);
        let ticks = TICK * u32::from(wait.max_ms);
        let (_, reply) = self.transact(&line, ticks)?;
        parse_ack(&reply, 'w')?;
        Ok(())
    }

    fn drive_status(&mut self) -> Result<DriveStatus, SimError> {
        let (written, reply) = self.transact(STATUS_REQUEST, Duration::ZERO)?;
        Ok(parse_status(&reply, written)?)
    }
}

impl Laser for SimRobot {
    fn read_scan(&mut self, timeout: Duration) -> Result<Option<LaserScan>, SimError> {
        self.catch_up();
        Ok(self.take_scan_by(self.host + timeout))
    }

    /// Skips older scans without casting their beams. As in the contract's default, the
    /// timeout restarts with every scan that arrives, kept or not.
    fn read_scan_since(
        &mut self,
        since: Stamp,
        timeout: Duration,
    ) -> Result<Option<LaserScan>, SimError> {
        self.catch_up();
        let mut deadline = self.host + timeout;
        loop {
            if let Some(delivery) = self.twin.skip_scans_before(since) {
                deadline = deadline.max(delivery + timeout);
            }
            if self
                .twin
                .next_scan_delivery()
                .is_some_and(|d| d <= deadline)
            {
                return Ok(self.take_scan_by(deadline));
            }
            if self.twin.now() >= deadline {
                self.host = self.host.max(deadline);
                return Ok(None);
            }
            self.twin.step();
        }
    }
}

impl SimRobot {
    /// Steps until a queued scan is delivered by `deadline` (and takes it) or the world reaches
    /// `deadline`.
    fn take_scan_by(&mut self, deadline: Stamp) -> Option<LaserScan> {
        loop {
            if self
                .twin
                .next_scan_delivery()
                .is_some_and(|d| d <= deadline)
            {
                let (delivery, scan) = self.twin.pop_scan().expect("a scan is queued");
                self.host = self.host.max(delivery);
                return Some(scan);
            }
            if self.twin.now() >= deadline {
                self.host = self.host.max(deadline);
                return None;
            }
            self.twin.step();
        }
    }
}

impl SonarRing for SimRobot {
    fn sonar(&mut self, command: SonarCommand) -> Result<(), SimError> {
        if self.twin.sonar().is_none() {
            return Err(SimError::Unsupported("sonar ring"));
        }
        let (line, letter) = encode_sonar(&command)?;
        let (_, reply) = self.transact(&line, Duration::ZERO)?;
        parse_ack(&reply, letter)?;
        if let SonarCommand::Sequence(sequence) = command {
            self.sonar_sequence = sequence;
        }
        Ok(())
    }

    fn sonar_echoes(&mut self) -> Result<SonarEchoes, SimError> {
        if self.twin.sonar().is_none() {
            return Err(SimError::Unsupported("sonar ring"));
        }
        let count = self.sonar_sequence.len();
        let (written, first) = self.transact(SONAR_REQUEST, Duration::ZERO)?;
        let mut lines = vec![first];
        let deadline = self.host + REPLY_MARGIN;
        while lines.len() < count {
            lines.push(self.read_line(Port::Base, "s", deadline)?.1);
        }
        let refs: Vec<&str> = lines.iter().map(String::as_str).collect();
        let times = parse_sonar_report(&refs, count)?;
        let measured = self.twin.sonar_measured();
        Ok(SonarEchoes {
            stamp: written,
            sequence: self.sonar_sequence.clone(),
            times,
            measured: (0..count).map(|i| measured[i]).collect(),
        })
    }
}

impl SimRobot {
    /// Waits until the pan-tilt has finished homing (its `Listo`), discarding what it narrates
    /// on the way. Returns at once after the first time.
    pub fn wait_pan_tilt_ready(&mut self) -> Result<(), SimError> {
        if self.pan_tilt.is_none() {
            return Err(SimError::Unsupported("pan-tilt unit"));
        }
        if self.pan_tilt_ready {
            return Ok(());
        }
        self.catch_up();
        let deadline = Stamp::ZERO + HOMING_LIMIT;
        loop {
            let (_, line) = self.read_line(Port::PanTilt, "(power-up homing)", deadline)?;
            if line == pt_protocol::READY {
                self.pan_tilt_ready = true;
                return Ok(());
            }
        }
    }
}

impl PanTilt for SimRobot {
    fn pan_tilt(&mut self, command: PanTiltCommand) -> Result<(), SimError> {
        self.wait_pan_tilt_ready()?;
        let line = pt_protocol::encode_command(&command)?;
        let (_, reply) = self.transact_on(Port::PanTilt, &line, Duration::ZERO)?;
        parse_ack(&reply, command.letter())?;
        Ok(())
    }

    fn wait_pan_tilt(&mut self, wait: PanTiltWait) -> Result<(), SimError> {
        self.wait_pan_tilt_ready()?;
        let line = pt_protocol::encode_wait(&wait);
        let (_, reply) = self.transact_on(Port::PanTilt, &line, TICK * u32::from(wait.max_ms))?;
        parse_ack(&reply, 'w')?;
        Ok(())
    }

    fn pan_tilt_status(&mut self) -> Result<PanTiltStatus, SimError> {
        self.wait_pan_tilt_ready()?;
        let (written, reply) =
            self.transact_on(Port::PanTilt, pt_protocol::STATUS_REQUEST, Duration::ZERO)?;
        Ok(pt_protocol::parse_status(&reply, written)?)
    }
}

impl Batteries for SimRobot {
    fn battery_voltages(&mut self) -> Result<BatteryVoltages, SimError> {
        let (written, reply) = self.transact(BATTERY_REQUEST, Duration::ZERO)?;
        Ok(parse_battery(&reply, written)?)
    }
}

impl GroundTruth for SimRobot {
    fn true_pose(&self) -> Pose2 {
        self.twin.true_pose()
    }
    fn true_pose_at(&self, t: Stamp) -> Option<Pose2> {
        self.twin.true_pose_at(t)
    }
    fn distance_travelled(&self) -> f64 {
        self.twin.distance_travelled()
    }
    fn collisions(&self) -> u32 {
        self.twin.collisions()
    }
    fn laser_frame_at(&self, t: Stamp) -> Option<LaserFrame> {
        self.twin.laser_frame_at(t)
    }
}
