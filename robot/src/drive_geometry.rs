//! The nominal geometry of a differential drive, and conversions between SI units and the
//! firmware's units (encoder counts, tenths of a motor turn).
//!
//! The firmware counts 1000 encoder edges per turn of the motor rotor (500 CPR, both edges of
//! channel A) and takes motions in tenths of a rotor turn (`a10` = one turn = 1000 counts), so
//! one count is `π·D / (gear · 1000)` of wheel travel.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Encoder counts in one tenth of a motor turn (`clicks_stop = param * 100` in the firmware).
pub const COUNTS_PER_TENTH: u32 = 100;

/// What the robot's software believes about its wheels: the numbers odometry integrates with.
///
/// ```
/// use robot::DriveGeometry;
/// let p3dx = DriveGeometry { wheel_diameter_m: 0.195, track_m: 0.333, gear_ratio: 65.5, counts_per_rotor_turn: 1000 };
/// // One motor turn moves the wheel 1/65.5 of its circumference: about 9.35 mm.
/// assert!((p3dx.metres_per_tenth() * 10.0 - 0.009353).abs() < 1e-6);
/// // Half a metre is 535 tenths of a motor turn.
/// assert_eq!(p3dx.tenths_for_distance(0.5), Some(535));
/// ```
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DriveGeometry {
    /// Wheel diameter, metres.
    pub wheel_diameter_m: f64,
    /// Distance between the two wheels' contact points, metres.
    pub track_m: f64,
    /// Motor turns per wheel turn.
    pub gear_ratio: f64,
    /// Encoder counts per motor (rotor) turn.
    pub counts_per_rotor_turn: u32,
}

impl DriveGeometry {
    /// Wheel travel of one encoder count, metres.
    pub fn metres_per_count(&self) -> f64 {
        PI * self.wheel_diameter_m / (self.gear_ratio * f64::from(self.counts_per_rotor_turn))
    }

    /// Wheel travel of one tenth of a motor turn, metres.
    pub fn metres_per_tenth(&self) -> f64 {
        self.metres_per_count() * f64::from(self.counts_per_rotor_turn) / 10.0
    }

    /// The `a`/`r` argument for a straight move of `|distance|` metres, rounded to the nearest
    /// tenth; `None` when it does not fit the firmware's 16-bit argument.
    pub fn tenths_for_distance(&self, distance_m: f64) -> Option<u16> {
        to_u16((distance_m.abs() / self.metres_per_tenth()).round())
    }

    /// The `i`/`d` argument for a turn in place of `|angle|` radians (each wheel travels
    /// `angle · track / 2`); `None` when it does not fit.
    pub fn tenths_for_turn(&self, angle_rad: f64) -> Option<u16> {
        self.tenths_for_distance(angle_rad.abs() * self.track_m / 2.0)
    }

    /// The heading change of a turn in place where each wheel travelled `counts`, radians.
    pub fn turn_for_counts(&self, counts: f64) -> f64 {
        2.0 * counts * self.metres_per_count() / self.track_m
    }
}

/// The Pioneer-class geometry the unit tests use.
#[cfg(test)]
pub(crate) const TEST_GEOMETRY: DriveGeometry = DriveGeometry {
    wheel_diameter_m: 0.195,
    track_m: 0.333,
    gear_ratio: 65.5,
    counts_per_rotor_turn: 1000,
};

fn to_u16(x: f64) -> Option<u16> {
    (x.is_finite() && (0.0..=f64::from(u16::MAX)).contains(&x)).then_some(x as u16)
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: DriveGeometry = TEST_GEOMETRY;

    #[test]
    fn turn_and_counts_are_inverse() {
        let tenths = G.tenths_for_turn(25f64.to_radians()).unwrap();
        let angle = G.turn_for_counts(f64::from(tenths) * f64::from(COUNTS_PER_TENTH));
        // Motions are whole tenths of a motor turn: the angle is right to half a tenth.
        let half_tenth = G.turn_for_counts(f64::from(COUNTS_PER_TENTH)) / 2.0;
        assert!(
            (angle - 25f64.to_radians()).abs() <= half_tenth,
            "{}",
            angle.to_degrees()
        );
    }

    #[test]
    fn too_long_moves_do_not_fit() {
        assert_eq!(G.tenths_for_distance(100.0), None);
        assert_eq!(G.tenths_for_distance(f64::NAN), None);
        assert_eq!(G.tenths_for_distance(-0.5), Some(535));
    }
}
