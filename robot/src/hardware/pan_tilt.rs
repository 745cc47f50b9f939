//! Types of the pan-tilt unit (thesis §2.5 and App. A.2.2).

use super::drive::Ramp;
use crate::time::Stamp;

/// Largest absolute pan position (0..=254 spans 0°..360°).
pub const PAN_MAX: u8 = 254;

/// Largest absolute tilt position (0..=100 spans −20°..+45°, ≈0.68° each).
pub const TILT_MAX: u8 = 100;

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

/// One command of the pan-tilt microcontroller that answers with its letter at once.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum PanTiltCommand {
    /// `g c`: pan to absolute position `c` (0..=254).
    Pan(u8),
    /// `e c`: tilt to absolute position `c` (0..=100).
    Tilt(u8),
    /// `k Pi Pf Tc`: acceleration ramp of the pan motor.
    PanRamp(Ramp),
    /// `K Pi Pf Tc`: acceleration ramp of the tilt motor.
    TiltRamp(Ramp),
    /// `p`: stop both motors.
    Stop,
}

/// The pan-tilt's `w ms [Fg Fe]`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PanTiltWait {
    /// Longest wait, ms.
    pub max_ms: u16,
    /// Wait for the pan motor to be off.
    pub pan: bool,
    /// Wait for the tilt motor to be off.
    pub tilt: bool,
}

/// The pan-tilt's status report (`l Cg Ce Eg Ee`).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct PanTiltStatus {
    /// When the firmware took this snapshot.
    pub stamp: Stamp,
    /// Pan motor counts since the last `g` or `e`.
    pub pan_counts: u32,
    /// Tilt motor counts since the last `g` or `e`.
    pub tilt_counts: u32,
    /// The pan motor is powered.
    pub pan_on: bool,
    /// The tilt motor is powered.
    pub tilt_on: bool,
}
