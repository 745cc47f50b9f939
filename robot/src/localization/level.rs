//! The 2D localisation of a robot whose laser may tilt: only level scans enter the map.
//!
//! A scan matcher compares planar scans, so a scan whose plane is tilted (a 3D sweep, a scene)
//! would be read as walls where there is floor. [`LevelLocaliser`] asks the laser's mount where
//! each scan was taken: a scan whose plane is level within a tolerance is matched from that pose
//! on the base (a head panned to the side is a laser mounted sideways), any other scan is left to
//! the 3D reconstruction, and so is a scan taken while the head's angles were unknown.

use super::map::{MapBuilder, MapConfig, Placed};
use super::matcher::MatcherKind;
use super::scan::RangeScan;
use crate::control::SceneTag;
use crate::geometry::Pose2;
use crate::hardware::LaserScan;
use crate::mount::LaserMount;

/// How far from level a scan plane may be and still be matched in 2D: half a tilt position of
/// the thesis's head (0.65° per position).
pub const LEVEL_TOLERANCE_RAD: f64 = 0.3 * std::f64::consts::PI / 180.0;

/// A [`MapBuilder`] fed with the level scans of a run.
#[derive(Debug)]
pub struct LevelLocaliser {
    kind: MatcherKind,
    builder: MapBuilder,
    mount: LaserMount,
    tolerance: f64,
    skipped: usize,
}

impl LevelLocaliser {
    /// Localises with `kind` in the odometry's frame (see [`MapBuilder::in_odometry_frame`]);
    /// `config.mount` is ignored: each scan's mount comes from `mount` and the scan's head angles.
    pub fn new(kind: MatcherKind, mount: LaserMount, config: MapConfig) -> Self {
        LevelLocaliser {
            kind,
            builder: MapBuilder::in_odometry_frame(kind.build(), config),
            mount,
            tolerance: LEVEL_TOLERANCE_RAD,
            skipped: 0,
        }
    }

    /// The matcher in use.
    pub fn kind(&self) -> MatcherKind {
        self.kind
    }

    /// The laser's pose on the base for `scan` in the plane, if its scan plane is level.
    pub fn level_mount(mount: &LaserMount, scan: &LaserScan, tolerance: f64) -> Option<Pose2> {
        let laser = mount.laser_on_base(scan.head)?;
        laser.is_level(tolerance).then(|| laser.planar())
    }

    /// A scan of a tour with the odometry at its stamp; returns whether it entered the map:
    /// whether it was level and not taken for a 3D scene (the robot stands still while a
    /// scene is taken, and the station's level scan has already localised it).
    pub fn push(&mut self, scan: &LaserScan, odometry: Pose2, scene: Option<SceneTag>) -> bool {
        if scene.is_some() {
            self.skipped += 1;
            return false;
        }
        match Self::level_mount(&self.mount, scan, self.tolerance) {
            Some(mount) => {
                self.builder.push_odometry(scan.stamp, odometry);
                self.builder.push_scan_from(RangeScan::from(scan), mount);
                true
            }
            None => {
                self.skipped += 1;
                false
            }
        }
    }

    /// The scans placed so far, in order (the last ones wait for odometry past their stamp).
    pub fn placed(&self) -> &[Placed] {
        self.builder.placed()
    }

    /// Scans left out: tilted, taken for a scene, or with the head's angles unknown.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// Places the scans still waiting for odometry and returns what was placed and the point map.
    pub fn finish(mut self) -> (Vec<Placed>, Vec<[f64; 2]>) {
        self.builder.finish();
        (
            self.builder.placed().to_vec(),
            self.builder.map_points().to_vec(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::HeadAngles;
    use crate::mount::HeadGeometry;
    use crate::time::Stamp;

    #[test]
    fn tilted_and_unknown_scans_stay_out_of_the_2d_map() {
        let mount = LaserMount::Head(HeadGeometry::THESIS);
        let mut loc = LevelLocaliser::new(MatcherKind::Lorentz, mount, MapConfig::default());
        let mut scan = LaserScan::sick_lms_half_degree(Stamp::from_millis(10), vec![2000; 361]);
        assert!(!loc.push(&scan, Pose2::IDENTITY, None), "head unknown");
        scan.head = Some(HeadAngles {
            pan: 0.0,
            tilt: 5f64.to_radians(),
        });
        assert!(!loc.push(&scan, Pose2::IDENTITY, None), "tilted");
        scan.head = Some(HeadAngles {
            pan: 1.0,
            tilt: 0.001,
        });
        let tag = SceneTag {
            scene: 0,
            station: 0,
        };
        assert!(
            !loc.push(&scan, Pose2::IDENTITY, Some(tag)),
            "a scene's scan"
        );
        assert!(loc.push(&scan, Pose2::IDENTITY, None), "level, panned");
        let panned = LevelLocaliser::level_mount(&mount, &scan, LEVEL_TOLERANCE_RAD).unwrap();
        assert!((panned.theta - 1.0).abs() < 1e-9);
        assert_eq!(loc.skipped(), 3);
        let (placed, _) = loc.finish();
        assert_eq!(placed.len(), 1);
    }
}
