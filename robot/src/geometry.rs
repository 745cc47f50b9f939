//! Planar poses in REP-103 axes: x forward, y left, θ counter-clockwise from x, metres and radians.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Wraps an angle to `(-π, π]`.
///
/// ```
/// use robot::geometry::wrap_angle;
/// assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
/// assert!((wrap_angle(-0.25) + 0.25).abs() < 1e-15);
/// ```
pub fn wrap_angle(theta: f64) -> f64 {
    let mut a = theta % (2.0 * PI);
    if a <= -PI {
        a += 2.0 * PI;
    } else if a > PI {
        a -= 2.0 * PI;
    }
    a
}

/// A rigid transform of the plane: the pose of a frame (x, y, θ) in a parent frame.
///
/// Composition follows the usual `⊕`: `a.compose(&b)` is frame `b` expressed through `a`.
///
/// ```
/// use robot::Pose2;
/// let robot = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
/// let laser_on_robot = Pose2::new(0.1, 0.0, 0.0);
/// let laser = robot.compose(&laser_on_robot);
/// assert!((laser.x - 1.0).abs() < 1e-12 && (laser.y - 2.1).abs() < 1e-12);
/// ```
#[derive(Copy, Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    /// Position along the parent's x axis, metres.
    pub x: f64,
    /// Position along the parent's y axis, metres.
    pub y: f64,
    /// Heading, radians counter-clockwise from the parent's x axis.
    pub theta: f64,
}

impl Pose2 {
    /// The identity transform.
    pub const IDENTITY: Pose2 = Pose2 {
        x: 0.0,
        y: 0.0,
        theta: 0.0,
    };

    /// A pose from its parts.
    pub const fn new(x: f64, y: f64, theta: f64) -> Self {
        Pose2 { x, y, theta }
    }

    /// `self ⊕ other`: the pose `other`, given relative to `self`, expressed in `self`'s parent.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let (s, c) = self.theta.sin_cos();
        Pose2 {
            x: self.x + c * other.x - s * other.y,
            y: self.y + s * other.x + c * other.y,
            theta: wrap_angle(self.theta + other.theta),
        }
    }

    /// The inverse transform `⊖self`.
    pub fn inverse(&self) -> Pose2 {
        let (s, c) = self.theta.sin_cos();
        Pose2 {
            x: -c * self.x - s * self.y,
            y: s * self.x - c * self.y,
            theta: wrap_angle(-self.theta),
        }
    }

    /// `⊖self ⊕ other`: where `other` lies as seen from `self`.
    pub fn relative(&self, other: &Pose2) -> Pose2 {
        self.inverse().compose(other)
    }

    /// Maps a point given in this frame into the parent frame.
    pub fn transform_point(&self, x: f64, y: f64) -> (f64, f64) {
        let (s, c) = self.theta.sin_cos();
        (self.x + c * x - s * y, self.y + s * x + c * y)
    }

    /// Linear interpolation from `self` (s = 0) to `other` (s = 1), taking the short way round
    /// in angle.
    pub fn interpolate(&self, other: &Pose2, s: f64) -> Pose2 {
        Pose2 {
            x: self.x + (other.x - self.x) * s,
            y: self.y + (other.y - self.y) * s,
            theta: wrap_angle(self.theta + wrap_angle(other.theta - self.theta) * s),
        }
    }

    /// Euclidean distance between the two positions, metres.
    pub fn distance(&self, other: &Pose2) -> f64 {
        (self.x - other.x).hypot(self.y - other.y)
    }

    /// The unit quaternion `(qx, qy, qz, qw)` of the heading as a rotation about z.
    pub fn quaternion(&self) -> [f64; 4] {
        let (s, c) = (0.5 * self.theta).sin_cos();
        [0.0, 0.0, s, c]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-12
            && (a.y - b.y).abs() < 1e-12
            && wrap_angle(a.theta - b.theta).abs() < 1e-12
    }

    #[test]
    fn inverse_undoes_compose() {
        let a = Pose2::new(1.5, -0.3, 2.9);
        let b = Pose2::new(-0.2, 0.7, -1.1);
        assert!(close(
            &a.compose(&b).relative(&a.compose(&b)),
            &Pose2::IDENTITY
        ));
        assert!(close(&a.relative(&a.compose(&b)), &b));
        assert!(close(&a.compose(&a.inverse()), &Pose2::IDENTITY));
    }

    #[test]
    fn interpolation_takes_short_way_round_pi() {
        let a = Pose2::new(0.0, 0.0, 3.0);
        let b = Pose2::new(2.0, 0.0, -3.0);
        let m = a.interpolate(&b, 0.5);
        assert!((m.x - 1.0).abs() < 1e-12);
        assert!((m.theta.abs() - PI).abs() < 1e-9, "{}", m.theta);
    }

    #[test]
    fn quaternion_of_quarter_turn() {
        let q = Pose2::new(0.0, 0.0, PI / 2.0).quaternion();
        assert!((q[2] - (0.5f64).sqrt()).abs() < 1e-12 && (q[3] - (0.5f64).sqrt()).abs() < 1e-12);
    }
}
