//! Types of the pan-tilt unit (thesis §2.5 and App. A.2.2).

use super::drive::Ramp;
use crate::time::Stamp;

/// Largest absolute pan position (0..=254 spans 0°..360°).
pub const PAN_MAX: u8 = 254;

/// Largest absolute tilt position (0..=100 spans −20°..+45°, ≈0.68° each).
pub const TILT_MAX: u8 = 100;

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
