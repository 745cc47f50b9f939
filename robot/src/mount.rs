//! Where the laser sits on the base: on a fixed mount, or on the pan-tilt head (thesis §4.2,
//! Eq. 4.1–4.6, App. D).
//!
//! The head has two joints on one vertical line: the pan axis rises from the base at
//! `axis[0..2]`, the tilt axis crosses it at height `axis[2]`. The laser's optical centre rides
//! `laser_forward` ahead of and `laser_up` above the tilt axis *in the tilting frame* (App. D's
//! `DELTAZ` = 45 mm and `DELTAY` = 8 mm). In REP-103 axes (x forward, y left, z up) a reading `d`
//! at beam angle `α` is, on the base,
//!
//! ```text
//! P_base = T(axis) · Rz(pan) · Ry(−tilt) · T(laser_forward, 0, laser_up) · (d cos α, d sin α, 0)
//! ```
//!
//! which is Eq. 4.1 `[Mr_g][Mr_i][Mt_s]P_s` with the axes renamed (the thesis's OpenGL frame has
//! y up and z forward; its Eq. 4.2 `(d sin α, 0, d cos α)` is this `(d cos α, d sin α, 0)`), and
//! `[Mt_r][Mr_r]` is the base's pose in the world. Two places where App. D's code differs from
//! Eq. 4.1 are decided by the real head's mechanics, not by the listing:
//!
//! - **the offset turns with the tilt.** The listing computes `Rot_Y(pan) · T(0, DELTAY, DELTAZ) ·
//!   Rot_X(−elev) · p`: it tilts the reading about the laser's own centre, then adds an offset
//!   that never tilts. The laser is bolted to the tilting plate, so its centre swings on a circle
//!   about the tilt axis: the order of Eq. 4.1 (offset first, then the tilt). At +45° the
//!   listing's order misplaces every point by up to 3.5 cm.
//! - **no +1 mm.** `MULTIPLICA_MT_P` adds `p[3]` where it meant to multiply by it, moving every
//!   coordinate by 1 mm; that is a slip, not geometry.
//!
//! The angles are the joints' (positions turned into radians by [`HeadGeometry::angles`]), so the
//! same chain serves the twin (true angles) and the real robot (the angles its pan-tilt reports).

use crate::geometry::Pose2;
use crate::hardware::HeadAngles;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

/// The pan-tilt head's geometry and its units, as a robot description gives them.
///
/// ```
/// use robot::mount::HeadGeometry;
/// use robot::hardware::HeadAngles;
/// let head = HeadGeometry::THESIS;
/// // Level and forward, the laser's centre is 45 mm ahead of and 8 mm above the tilt axis.
/// let laser = head.laser_on_base(HeadAngles::default());
/// let c = laser.origin();
/// assert!((c[0] - 0.045).abs() < 1e-12 && (c[2] - (1.042 + 0.008)).abs() < 1e-12);
/// // Position 31 is level on the thesis's robot; each position is 0.65° of tilt.
/// let a = head.angles(0, 0, 32, 0);
/// assert!((a.tilt.to_degrees() - 0.65).abs() < 1e-12);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct HeadGeometry {
    /// The pan axis's position on the base (x ahead of the axle, y left) and the tilt axis's
    /// height above the floor, metres.
    pub axis: [f64; 3],
    /// The laser's optical centre ahead of the tilt axis, in the tilting frame, metres.
    pub laser_forward: f64,
    /// The laser's optical centre above the tilt axis, in the tilting frame, metres.
    pub laser_up: f64,
    /// Pan per position (one motor turn), radians.
    pub pan_per_position: f64,
    /// Tilt per position (one motor turn), radians.
    pub tilt_per_position: f64,
    /// The tilt position at which the scan plane is level.
    pub level_position: f64,
}

impl HeadGeometry {
    /// The thesis's robot as `scenarios/robots/thesis-roca.toml` describes it: tilt axis 1.042 m
    /// above the floor on the base's centre, laser 45 mm ahead and 8 mm above it (App. D), 254
    /// pan positions per turn (§2.5), 0.65° per tilt position, level at tilt position 31.
    pub const THESIS: HeadGeometry = HeadGeometry {
        axis: [0.0, 0.0, 1.042],
        laser_forward: 0.045,
        laser_up: 0.008,
        pan_per_position: std::f64::consts::TAU / 254.0,
        tilt_per_position: 0.65 * std::f64::consts::PI / 180.0,
        level_position: 31.0,
    };

    /// The joints' angles when the firmware reports positions `pan` and `tilt` and, since each
    /// position's index pulse, `pan_clicks` and `tilt_clicks` (1000 per position, signed by the
    /// direction of travel: the `l` report's fields).
    pub fn angles(&self, pan: i16, pan_clicks: i16, tilt: i16, tilt_clicks: i16) -> HeadAngles {
        let turns = |position: i16, clicks: i16| f64::from(position) + f64::from(clicks) / 1000.0;
        HeadAngles {
            pan: turns(pan, pan_clicks) * self.pan_per_position,
            tilt: (turns(tilt, tilt_clicks) - self.level_position) * self.tilt_per_position,
        }
    }

    /// The laser's pose on the base with the head at `angles`: Eq. 4.1's chain from the laser
    /// to the base.
    pub fn laser_on_base(&self, angles: HeadAngles) -> LaserPose {
        let axis = Translation3::new(self.axis[0], self.axis[1], self.axis[2]);
        let pan = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), angles.pan);
        // REP-103 pitch is positive nose-down: a tilt up is a negative rotation about y.
        let tilt = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -angles.tilt);
        let offset = Translation3::new(self.laser_forward, 0.0, self.laser_up);
        LaserPose(
            Isometry3::from_parts(axis, pan)
                * Isometry3::from_parts(Translation3::identity(), tilt)
                * Isometry3::from_parts(offset, UnitQuaternion::identity()),
        )
    }
}

/// Where the laser is on the base.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum LaserMount {
    /// Bolted to the base: its pose in the plane and the height of its scan plane.
    Fixed {
        /// Position and heading on the base.
        pose: Pose2,
        /// Height of the optical centre above the floor, metres.
        z: f64,
    },
    /// On the pan-tilt head.
    Head(HeadGeometry),
}

impl LaserMount {
    /// The laser's pose on the base for a scan measured with the head at `head`; `None` for a
    /// laser on the head when the head's angles are unknown.
    pub fn laser_on_base(&self, head: Option<HeadAngles>) -> Option<LaserPose> {
        match self {
            LaserMount::Fixed { pose, z } => Some(LaserPose(Isometry3::from_parts(
                Translation3::new(pose.x, pose.y, *z),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), pose.theta),
            ))),
            LaserMount::Head(geometry) => head.map(|a| geometry.laser_on_base(a)),
        }
    }
}

/// A laser's pose in 3D: its optical centre and axes (x along the middle beam, y towards the
/// first beam's opposite — the laser's left —, z the scan plane's normal) in a parent frame.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LaserPose(pub Isometry3<f64>);

impl LaserPose {
    /// The pose of a laser at `(planar.x, planar.y, z)` whose middle beam has heading
    /// `planar.theta` and rises by `tilt` (no roll: the pan-tilt head cannot roll it), as
    /// `scans.jsonl` records it.
    pub fn from_planar(planar: Pose2, z: f64, tilt: f64) -> Self {
        LaserPose(
            Isometry3::from_parts(
                Translation3::new(planar.x, planar.y, z),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), planar.theta),
            ) * Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -tilt),
            ),
        )
    }

    /// The optical centre in the parent frame, metres.
    pub fn origin(&self) -> [f64; 3] {
        let t = self.0.translation.vector;
        [t.x, t.y, t.z]
    }

    /// The reading `range` metres along the beam at `angle`, in the parent frame.
    pub fn point(&self, angle: f64, range: f64) -> [f64; 3] {
        let (s, c) = angle.sin_cos();
        let p = self.0 * Point3::new(range * c, range * s, 0.0);
        [p.x, p.y, p.z]
    }

    /// The same pose seen from a frame in which the parent sits at `base` (in the plane): the
    /// laser in the world when the base is at `base`.
    pub fn on(&self, base: Pose2) -> LaserPose {
        let base = Isometry3::from_parts(
            Translation3::new(base.x, base.y, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), base.theta),
        );
        LaserPose(base * self.0)
    }

    /// The rotation as a row-major 3×3 matrix: column 0 is the middle beam's direction, column 1
    /// the laser's left.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let m = self.0.rotation.to_rotation_matrix();
        let m = m.matrix();
        [0, 1, 2].map(|r| [m[(r, 0)], m[(r, 1)], m[(r, 2)]])
    }

    /// Heading of the middle beam in the parent's plane, radians.
    pub fn yaw(&self) -> f64 {
        let r = self.rotation();
        r[1][0].atan2(r[0][0])
    }

    /// Tilt of the scan plane: elevation of the middle beam above the parent's plane, radians.
    pub fn tilt(&self) -> f64 {
        let r = self.rotation();
        r[2][0].atan2(r[0][0].hypot(r[1][0]))
    }

    /// The pose projected onto the plane: centre (x, y) and heading of the middle beam — the
    /// 2D mount a scan matcher works with, exact for a level scan.
    pub fn planar(&self) -> Pose2 {
        let o = self.origin();
        Pose2::new(o[0], o[1], self.yaw())
    }

    /// Whether the scan plane is level within `tolerance` radians (and upright: not rolled).
    pub fn is_level(&self, tolerance: f64) -> bool {
        let r = self.rotation();
        // The plane's normal (column 2) must point up within the tolerance.
        r[2][2] >= tolerance.cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chain_swings_the_laser_about_the_tilt_axis() {
        let head = HeadGeometry::THESIS;
        let tilt = 30f64.to_radians();
        let laser = head.laser_on_base(HeadAngles {
            pan: std::f64::consts::FRAC_PI_2,
            tilt,
        });
        // Panned to the left, the offset lies along +y; tilted, it rises on a circle.
        let ahead = 0.045 * tilt.cos() - 0.008 * tilt.sin();
        let up = 0.045 * tilt.sin() + 0.008 * tilt.cos();
        let o = laser.origin();
        assert!(o[0].abs() < 1e-12 && (o[1] - ahead).abs() < 1e-12);
        assert!((o[2] - (1.042 + up)).abs() < 1e-12);
        assert!((laser.tilt() - tilt).abs() < 1e-12);
        assert!((laser.yaw() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // The middle beam at 2 m rises by 2 sin 30° = 1 m above the laser.
        let p = laser.point(0.0, 2.0);
        assert!((p[2] - o[2] - 1.0).abs() < 1e-12, "{p:?}");
        assert!(!laser.is_level(1e-3));
        // Rebuilt from what scans.jsonl records, it is the same pose.
        let again = LaserPose::from_planar(laser.planar(), o[2], laser.tilt());
        let (a, b) = (laser.point(0.3, 4.0), again.point(0.3, 4.0));
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-12), "{a:?} {b:?}");
        assert!(head.laser_on_base(HeadAngles::default()).is_level(1e-9));
    }

    #[test]
    fn beams_sweep_counter_clockwise_from_the_right() {
        let laser = LaserMount::Fixed {
            pose: Pose2::new(0.1, 0.0, 0.0),
            z: 0.3,
        }
        .laser_on_base(None)
        .unwrap();
        let right = laser.point(-std::f64::consts::FRAC_PI_2, 1.0);
        assert!((right[0] - 0.1).abs() < 1e-12 && (right[1] + 1.0).abs() < 1e-12);
        let world = laser.on(Pose2::new(2.0, 3.0, std::f64::consts::PI));
        let ahead = world.point(0.0, 1.0);
        assert!((ahead[0] - (2.0 - 1.1)).abs() < 1e-12 && (ahead[1] - 3.0).abs() < 1e-12);
        assert!((ahead[2] - 0.3).abs() < 1e-12);
        assert_eq!(
            LaserMount::Head(HeadGeometry::THESIS).laser_on_base(None),
            None
        );
    }

    #[test]
    fn reported_positions_and_clicks_become_angles() {
        let head = HeadGeometry::THESIS;
        let a = head.angles(127, 500, 31, -250);
        assert!((a.pan - 127.5 * std::f64::consts::TAU / 254.0).abs() < 1e-12);
        assert!((a.tilt + 0.25 * 0.65f64.to_radians()).abs() < 1e-12);
    }
}
