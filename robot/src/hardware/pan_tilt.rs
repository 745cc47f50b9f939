//! Types of the pan-tilt unit (thesis §2.5, App. A.2.2, and the firmware of App. A.3.2).
//!
//! The unit counts positions in whole turns of its motors: one pan position is 360°/254 of pan,
//! one tilt position about 0.65° of tilt. It homes at power-up to pan position 0 (the laser
//! looking forward) and tilt position 0 (its lower switch, about −20°). Where the prose and the
//! firmware disagree, the types follow the firmware: the status report has nine fields, and there
//! is no stop command (`do_command` has no `p`; a move ends at its target or at a limit switch).

use super::drive::{ArgumentError, Ramp};
use crate::time::Stamp;

/// Largest absolute pan position of the documented span (0..=254 spans 0°..360°). The firmware
/// of the thesis's robot clamps pan targets to 248 (`MAX_ABS_GIRO`).
pub const PAN_MAX: u8 = 254;

/// Largest absolute tilt position (0..=100 spans −20°..+45°, ≈0.65° each).
pub const TILT_MAX: u8 = 100;

/// Largest speed a pan-tilt ramp may ask for, counts per tick: the pulse accumulators that
/// measure the speed are 8-bit.
pub const PAN_TILT_SPEED_LIMIT: u16 = 255;

/// An absolute pan-tilt position in the controller's units.
///
/// The thesis gives the spans: pan 0..=254 over a full turn from the homing switch, tilt
/// 0..=100 from −20° (the homing switch) to +45°. The angle conversions use those nominal spans.
///
/// ```
/// use robot::hardware::PanTiltPosition;
/// let home = PanTiltPosition::HOME;
/// assert!((home.tilt_rad().to_degrees() + 20.0).abs() < 1e-12);
/// let level = PanTiltPosition::nearest(0.0, 0.0);
/// assert_eq!(level.tilt, 31); // 20° above the home position at 0.65° per step
/// ```
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PanTiltPosition {
    /// Pan position, 0..=254.
    pub pan: u8,
    /// Tilt position, 0..=100.
    pub tilt: u8,
}

impl PanTiltPosition {
    /// Where the unit homes at power-up: pan 0°, tilt −20°.
    pub const HOME: PanTiltPosition = PanTiltPosition { pan: 0, tilt: 0 };
    /// Tilt at position 0, radians.
    pub const TILT_MIN_RAD: f64 = -20.0 * std::f64::consts::PI / 180.0;
    /// Tilt at position 100, radians.
    pub const TILT_MAX_RAD: f64 = 45.0 * std::f64::consts::PI / 180.0;

    /// Pan angle from the home position, radians counter-clockwise (nominal span).
    pub fn pan_rad(&self) -> f64 {
        f64::from(self.pan) * std::f64::consts::TAU / f64::from(PAN_MAX)
    }

    /// Tilt angle above the horizontal, radians (nominal span).
    pub fn tilt_rad(&self) -> f64 {
        Self::TILT_MIN_RAD
            + f64::from(self.tilt) * (Self::TILT_MAX_RAD - Self::TILT_MIN_RAD) / f64::from(TILT_MAX)
    }

    /// The position nearest to the given angles, clamped to the ranges.
    pub fn nearest(pan_rad: f64, tilt_rad: f64) -> Self {
        let pan = (pan_rad.rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU
            * f64::from(PAN_MAX))
        .round();
        let tilt = ((tilt_rad - Self::TILT_MIN_RAD) / (Self::TILT_MAX_RAD - Self::TILT_MIN_RAD)
            * f64::from(TILT_MAX))
        .round();
        PanTiltPosition {
            pan: pan.clamp(0.0, f64::from(PAN_MAX)) as u8,
            tilt: tilt.clamp(0.0, f64::from(TILT_MAX)) as u8,
        }
    }
}

/// Where the pan-tilt head points: pan counter-clockwise from the base's forward axis, tilt of the
/// laser's scan plane up from level (positive: the forward beams rise), radians.
///
/// A [`LaserScan`](super::LaserScan) carries the angles at which it was measured; turn them into
/// the laser's pose on the base with [`LaserMount`](crate::mount::LaserMount).
#[derive(Copy, Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HeadAngles {
    /// Pan, radians counter-clockwise.
    pub pan: f64,
    /// Tilt, radians up.
    pub tilt: f64,
}

impl crate::odometry::Interpolate for HeadAngles {
    fn interpolate(&self, other: &HeadAngles, s: f64) -> HeadAngles {
        HeadAngles {
            pan: self.pan + (other.pan - self.pan) * s,
            tilt: self.tilt + (other.tilt - self.tilt) * s,
        }
    }
}

/// One command of the pan-tilt microcontroller that answers with its letter at once.
///
/// There is no stop: the firmware's `do_command` has no `p` (the prose's table lists one, the
/// code ignores it without an answer).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum PanTiltCommand {
    /// `g c`: pan to absolute position `c` (0..=254; the thesis's firmware stops at 248).
    Pan(u8),
    /// `e c`: tilt to absolute position `c` (0..=100).
    Tilt(u8),
    /// `k Pi Pf Tc`: acceleration ramp of the pan motor.
    PanRamp(Ramp),
    /// `K Pi Pf Tc`: acceleration ramp of the tilt motor.
    TiltRamp(Ramp),
}

impl PanTiltCommand {
    /// The command letter, which is also the acknowledgement.
    pub fn letter(&self) -> char {
        match self {
            PanTiltCommand::Pan(_) => 'g',
            PanTiltCommand::Tilt(_) => 'e',
            PanTiltCommand::PanRamp(_) => 'k',
            PanTiltCommand::TiltRamp(_) => 'K',
        }
    }

    /// Checks the arguments against the documented ranges.
    ///
    /// ```
    /// use robot::hardware::PanTiltCommand;
    /// assert!(PanTiltCommand::Tilt(100).validate().is_ok());
    /// let err = PanTiltCommand::Tilt(101).validate().unwrap_err();
    /// assert_eq!(err.to_string(), "`e` argument c = 101 is out of range: expected 0..=100");
    /// ```
    pub fn validate(&self) -> Result<(), ArgumentError> {
        let speed = i64::from(PAN_TILT_SPEED_LIMIT);
        match *self {
            PanTiltCommand::Pan(c) => ArgumentError::check('g', "c", c.into(), 0, PAN_MAX.into()),
            PanTiltCommand::Tilt(c) => ArgumentError::check('e', "c", c.into(), 0, TILT_MAX.into()),
            PanTiltCommand::PanRamp(r) | PanTiltCommand::TiltRamp(r) => {
                let letter = self.letter();
                ArgumentError::check(letter, "Pi", r.initial.into(), 0, speed)?;
                ArgumentError::check(letter, "Pf", r.top.into(), 0, speed)
            }
        }
    }
}

/// The pan-tilt's `w ms Fg Fe`.
///
/// As the firmware is written (`check_end_wait`), only "wait for the pan alone" (`Fg` = 1,
/// `Fe` = 0) ends early when the motor stops; every other form waits the full `max_ms`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct PanTiltWait {
    /// Longest wait, in control ticks of 1.024 ms.
    pub max_ms: u16,
    /// Wait for the pan motor to be off.
    pub pan: bool,
    /// Wait for the tilt motor to be off.
    pub tilt: bool,
}

/// The pan-tilt's status report, as `report_status` writes it:
/// `l abs_giro g_giro_clicks abs_elev g_elev_clicks TopeIzq TopeDer TopeInf Eg Ee`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct PanTiltStatus {
    /// When the firmware took this snapshot.
    pub stamp: Stamp,
    /// Absolute pan position (index pulses counted since homing).
    pub pan: i16,
    /// Encoder clicks since the pan motor's last counted index pulse (2 per channel-B edge).
    pub pan_clicks: i16,
    /// Absolute tilt position.
    pub tilt: i16,
    /// Encoder clicks since the tilt motor's last counted index pulse.
    pub tilt_clicks: i16,
    /// The pan's left limit switch is pressed.
    pub left_limit: bool,
    /// The pan's right limit switch is pressed.
    pub right_limit: bool,
    /// The tilt's lower limit switch is pressed.
    pub lower_limit: bool,
    /// The pan motor is powered.
    pub pan_on: bool,
    /// The tilt motor is powered.
    pub tilt_on: bool,
}

impl PanTiltStatus {
    /// Both motors are off.
    pub fn idle(&self) -> bool {
        !self.pan_on && !self.tilt_on
    }
}
