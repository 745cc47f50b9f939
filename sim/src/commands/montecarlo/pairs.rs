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
    /// On how many of the four sides walls must surround a pose for it to be inside: as many
    /// as surround the world's start (four in a closed building; three in a corridor whose
    /// ends are open, as the L-corridor's of Aparicio 2011).
    sides: usize,
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
        let map = WorldMap::new(world);
        let sides = walled_sides(&map, [world.start.x, world.start.y]).max(1);
        PairMaker {
            map,
            laser,
            bounds: world.bounds(),
            sides,
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

    /// Whether walls surround `point` on as many sides as they surround the world's start: on
    /// all four in a closed building (it is inside the building).
    pub fn enclosed(&self, point: [f64; 2]) -> bool {
        walled_sides(&self.map, point) >= self.sides
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
            "no start pose inside the building {clearance} m from every wall in {MAX_DRAWS} random draws"
        ))
    }
}

/// On how many of the four sides (along ±x and ±y) a wall lies within 100 m of `point`.
fn walled_sides(map: &WorldMap, point: [f64; 2]) -> usize {
    [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]
        .iter()
        .filter(|&&dir| map.cast_level(point, 0.3, dir, 100.0).is_some())
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn maker(world: &str) -> PairMaker {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let world = WorldDescription::load(root.join("worlds").join(world)).unwrap();
        let robot = RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml")).unwrap();
        PairMaker::new(&world, &robot, Outliers::NONE)
    }

    /// Inside is as walled as the world's start: all four sides in the closed lab, three in
    /// the L-corridor, whose ends are open. A pose in either leg of the L is inside, one in
    /// the open square the L bends around is not, nor is one beyond the lab's walls; and
    /// start poses can be drawn in both.
    #[test]
    fn inside_is_as_walled_as_the_start() {
        let corridor = maker("l-corridor.toml");
        assert!(corridor.enclosed([0.6, 0.0]));
        assert!(corridor.enclosed([6.0, 4.0]));
        assert!(!corridor.enclosed([3.0, 3.0]));
        let lab = maker("lab.toml");
        assert_eq!(lab.sides, 4);
        let ([x0, y0], _) = lab.bounds;
        assert!(!lab.enclosed([x0 - 1.0, y0 - 1.0]));
        let mut rng = crate::rng::stream(7, "pairs test");
        for maker in [&corridor, &lab] {
            let pose = maker.free_pose(0.4, &mut rng).unwrap();
            assert!(maker.enclosed([pose.x, pose.y]));
            assert!(maker.map.clearance([pose.x, pose.y]) > 0.4);
        }
    }
}
