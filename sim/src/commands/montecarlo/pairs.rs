//! Scan pairs with known truth, for testing and measuring the matchers: two scans of the twin's
//! laser from two base poses, and the true pose of the second laser frame in the first.

use crate::config::Outliers;
use crate::config::{RobotDescription, WorldDescription};
use crate::devices::laser::LaserModel;
use crate::rng::SimRng;
use crate::world::WorldMap;
use rand::RngExt;
use robot::localization::RangeScan;
use robot::{Pose2, Stamp};

/// Random draws for a start pose before a study is declared impossible.
pub const MAX_DRAWS: u32 = 100_000;
/// Two scans and the truth between them.
#[derive(Clone, Debug)]
pub struct ScanPair {
    /// The scan from the first pose.
    pub reference: RangeScan,
    /// The scan from the second pose.
    pub current: RangeScan,
    /// The pose of the second laser frame in the first: what a matcher should answer.
    pub truth: Pose2,
}

/// Makes scan pairs in a world with a robot's (level) laser.
#[derive(Clone)]
pub struct PairMaker {
    map: WorldMap,
    laser: LaserModel,
    bounds: ([f64; 2], [f64; 2]),
}

impl PairMaker {
    /// The robot's laser, with its own range noise and the given outliers, in `world`.
    pub fn new(world: &WorldDescription, robot: &RobotDescription, outliers: Outliers) -> Self {
        let laser = LaserModel::new(
            &robot.laser,
            robot.laser_mount(),
            robot.laser.sigma_m.get(),
            outliers,
        );
        PairMaker {
            map: WorldMap::new(world),
            laser,
            bounds: world.bounds(),
        }
    }

    /// The world's map.
    pub fn map(&self) -> &WorldMap {
        &self.map
    }

    /// One scan from a base pose.
    pub fn scan(&self, base: Pose2, rng: &mut SimRng) -> RangeScan {
        let frame = self.laser.frame_on(base);
        RangeScan::from(&self.laser.scan(&self.map, None, frame, Stamp::ZERO, rng))
    }

    /// Scans from `first` and `second` (base poses in the world).
    pub fn pair(&self, first: Pose2, second: Pose2, rng: &mut SimRng) -> ScanPair {
        let mount = self.laser.mount();
        ScanPair {
            reference: self.scan(first, rng),
            current: self.scan(second, rng),
            truth: first.compose(&mount).relative(&second.compose(&mount)),
        }
    }

    /// Whether walls surround `point` on all four sides (it is inside the building).
    pub fn enclosed(&self, point: [f64; 2]) -> bool {
        [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]
            .iter()
            .all(|&dir| self.map.cast_level(point, 0.3, dir, 100.0).is_some())
    }

    /// A random base pose inside the building at least `clearance` metres from every wall, any
    /// heading; an error after [`MAX_DRAWS`] draws without one (no place is that clear).
    pub fn free_pose(&self, clearance: f64, rng: &mut SimRng) -> Result<Pose2, String> {
        let ([x0, y0], [x1, y1]) = self.bounds;
        for _ in 0..MAX_DRAWS {
            let p = Pose2::new(
                x0 + (x1 - x0) * rng.random::<f64>(),
                y0 + (y1 - y0) * rng.random::<f64>(),
                (rng.random::<f64>() * 2.0 - 1.0) * std::f64::consts::PI,
            );
            if self.map.clearance([p.x, p.y]) > clearance && self.enclosed([p.x, p.y]) {
                return Ok(p);
            }
        }
        Err(format!(
            "no start pose inside the building {clearance} m from every wall in {MAX_DRAWS} random draws: lower the study's clearance_m"
        ))
    }
}
