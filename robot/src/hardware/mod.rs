//! The hardware contract: what the real robot offers its software.
//!
//! A backend — the twin's `SimRobot`, or the serial `SerialRobot` that talks to the two
//! microcontrollers and the SICK laser — implements these traits; controllers and estimators are
//! written against them and run unchanged on both. Every method is fallible, and every error
//! offers a [`HardwareError::kind`] so generic code can react (retry on a timeout, give up on a
//! bad argument) without knowing the backend.
//!
//! Nothing here assumes simulator powers: there is no teleport and no ground truth. A method
//! either sends what the firmware accepts (App. A of the thesis) or reads what a device reports,
//! each reading stamped with the robot clock's [`Stamp`](crate::Stamp) at which it was measured.
//! Blocking calls take their time the way the real devices do — a status query costs its serial
//! round trip, a scan arrives when the laser has sent it — so a backend's clock advances as the
//! controller talks to it.
//!
//! The firmware's own units are kept where the wire speaks them: motions in tenths of a motor
//! turn, wheel speeds in encoder counts per 1.024 ms control tick, ranges in millimetres. Turn
//! them into SI with [`DriveGeometry`](crate::DriveGeometry) and [`LaserScan`]'s helpers.

mod battery;
mod drive;
mod laser;
mod pan_tilt;
mod sonar;

pub use battery::BatteryVoltages;
pub use drive::{
    ArgumentError, DriveCommand, DriveStatus, DriveWait, Ramp, STATUS_COUNT_MODULUS,
    WHEEL_SPEED_LIMIT,
};
pub use laser::LaserScan;
pub use pan_tilt::{
    HeadAngles, PAN_MAX, PAN_TILT_SPEED_LIMIT, PanTiltCommand, PanTiltPosition, PanTiltStatus,
    PanTiltWait, TILT_MAX,
};
pub use sonar::{
    SONAR_COUNT, SONAR_NO_ECHO, SONAR_TIME_UNIT_S, SPEED_OF_SOUND, SonarCommand, SonarEchoes,
    echo_distance_m, echo_units,
};

use core::time::Duration;

/// What kind of failure a hardware error is, independent of the backend.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[non_exhaustive]
pub enum ErrorKind {
    /// An argument is outside what the firmware documents; nothing was sent.
    InvalidArgument,
    /// The device did not answer in time.
    Timeout,
    /// The link to the device is gone (port closed, connection dropped).
    Disconnected,
    /// The device answered something the protocol does not allow.
    Protocol,
    /// This backend does not offer the device or operation.
    Unsupported,
    /// Anything else (I/O failure, internal fault).
    Other,
}

/// An error raised by a hardware backend.
pub trait HardwareError: std::error::Error + Send + Sync + 'static {
    /// The backend-independent kind of this error.
    fn kind(&self) -> ErrorKind;
}

/// The root of the contract: the error type every device of a backend shares.
pub trait Hardware {
    /// The backend's error.
    type Error: HardwareError;
}

/// The drive base: the base microcontroller's motion commands and its status report.
///
/// Motion commands return as soon as the firmware acknowledged them (it answers with the command
/// letter at once); the motion goes on. Use [`DriveBase::wait_drive`] or poll
/// [`DriveBase::drive_status`] to learn when it ends.
pub trait DriveBase: Hardware {
    /// Sends one command and waits for its one-letter acknowledgement.
    fn drive(&mut self, command: DriveCommand) -> Result<(), Self::Error>;

    /// The firmware's `w`: returns when the flagged motors (and sonar) are idle, or when
    /// `wait.max_ms` have elapsed, whichever comes first.
    fn wait_drive(&mut self, wait: DriveWait) -> Result<(), Self::Error>;

    /// The firmware's `l`: wheel counters since the last motion command, and motor flags.
    fn drive_status(&mut self) -> Result<DriveStatus, Self::Error>;

    /// `a`: forward by `tenths` of a motor turn on each wheel.
    fn advance(&mut self, tenths: u16) -> Result<(), Self::Error> {
        self.drive(DriveCommand::Advance(tenths))
    }

    /// `r`: backward by `tenths` of a motor turn on each wheel.
    fn retreat(&mut self, tenths: u16) -> Result<(), Self::Error> {
        self.drive(DriveCommand::Retreat(tenths))
    }

    /// `i`: turn left in place, each wheel travelling `tenths` of a motor turn.
    fn turn_left(&mut self, tenths: u16) -> Result<(), Self::Error> {
        self.drive(DriveCommand::TurnLeft(tenths))
    }

    /// `d`: turn right in place, each wheel travelling `tenths` of a motor turn.
    fn turn_right(&mut self, tenths: u16) -> Result<(), Self::Error> {
        self.drive(DriveCommand::TurnRight(tenths))
    }

    /// `v`: set the wheel speeds directly, in counts per control tick (negative is backward).
    fn set_wheel_speeds(&mut self, left: i16, right: i16) -> Result<(), Self::Error> {
        self.drive(DriveCommand::WheelSpeeds { left, right })
    }

    /// `p`: stop the drive motors (they brake).
    fn stop(&mut self) -> Result<(), Self::Error> {
        self.drive(DriveCommand::Stop)
    }

    /// `k`: the acceleration ramp used by the next motion command.
    fn set_ramp(&mut self, ramp: Ramp) -> Result<(), Self::Error> {
        self.drive(DriveCommand::Ramp(ramp))
    }
}

/// The laser rangefinder (SICK LMS, 361 readings over 180° in millimetres).
pub trait Laser: Hardware {
    /// Waits up to `timeout` for the next complete scan and returns it, or `Ok(None)` if none
    /// arrived in time. Scans are returned in order, each once.
    fn read_scan(&mut self, timeout: Duration) -> Result<Option<LaserScan>, Self::Error>;

    /// Returns the first scan measured at or after `since`, discarding older ones unread (a
    /// backend may skip decoding them); `Ok(None)` when the laser sends nothing for `timeout`.
    fn read_scan_since(
        &mut self,
        since: crate::Stamp,
        timeout: Duration,
    ) -> Result<Option<LaserScan>, Self::Error> {
        // Stamps grow scan after scan, so this ends once the laser is past `since`.
        loop {
            match self.read_scan(timeout)? {
                None => return Ok(None),
                Some(scan) if scan.stamp >= since => return Ok(Some(scan)),
                Some(_) => {}
            }
        }
    }
}

/// The ring of 16 Polaroid sonars, fired by the base microcontroller.
pub trait SonarRing: Hardware {
    /// Sends one sonar command (`S`, `s0`, `s1`, `s2`).
    fn sonar(&mut self, command: SonarCommand) -> Result<(), Self::Error>;

    /// The firmware's `s`: the latest echo time of each sonar of the firing sequence.
    fn sonar_echoes(&mut self) -> Result<SonarEchoes, Self::Error>;
}

/// The pan-tilt unit carrying the laser, driven by the second microcontroller.
pub trait PanTilt: Hardware {
    /// Sends one pan-tilt command and waits for its acknowledgement.
    fn pan_tilt(&mut self, command: PanTiltCommand) -> Result<(), Self::Error>;

    /// The pan-tilt's `w`: returns when the flagged motors are idle or after `wait.max_ms`.
    fn wait_pan_tilt(&mut self, wait: PanTiltWait) -> Result<(), Self::Error>;

    /// The pan-tilt's `l`: positions, clicks since the last index, switches and motor flags.
    fn pan_tilt_status(&mut self) -> Result<PanTiltStatus, Self::Error>;

    /// `g` and `e` to `target`, then polls `l` every `poll` until both motors are off and
    /// returns the last status (which still shows a motor on if `limit` polls were not enough).
    fn move_pan_tilt_to(
        &mut self,
        target: PanTiltPosition,
        poll: u16,
        limit: u32,
    ) -> Result<PanTiltStatus, Self::Error> {
        self.pan_tilt(PanTiltCommand::Pan(target.pan))?;
        self.pan_tilt(PanTiltCommand::Tilt(target.tilt))?;
        let mut status = self.pan_tilt_status()?;
        let mut polls = 0;
        while !status.idle() && polls < limit {
            self.wait_pan_tilt(PanTiltWait {
                max_ms: poll,
                pan: false,
                tilt: false,
            })?;
            status = self.pan_tilt_status()?;
            polls += 1;
        }
        Ok(status)
    }
}

/// The battery voltages measured by the base microcontroller.
pub trait Batteries: Hardware {
    /// The firmware's `t`: the four battery voltages in millivolts.
    fn battery_voltages(&mut self) -> Result<BatteryVoltages, Self::Error>;
}
