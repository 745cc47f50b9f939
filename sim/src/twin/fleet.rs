//! Many robots in one world, stepping together: each a whole twin — base firmware, motors,
//! physics against the world's walls, laser and sonar — with its own noise streams (robot `k`
//! draws from the stream `robot/k` of the fleet's seed), all advanced one [`STEP`] at a time over
//! the machine's cores.
//!
//! Each robot meets the other robots' bodies as they stood at the start of the step (a snapshot
//! taken before it, so a robot's step reads nothing another writes during it): its laser sees
//! them on every leg, and those within reach stand in its physics as immovable discs, so two
//! robots that drive into each other stop each other as a wall would (and count the collision).
//! The fleet gives the same bits on one thread or many.
//!
//! What the fleet does not do yet: the sonar rings do not hear other robots, and a robot pushed
//! by another feels it as a wall, not as a body it could shove.
//!
//! [`STEP`]: super::STEP

use super::Twin;
use crate::config::{ConfigError, NoiseSettings, RobotDescription, WorldDescription};
use crate::devices::laser::beam::Disc;
use rayon::prelude::*;
use robot::Pose2;
use std::sync::Arc;

/// Up to `n` starting poses on a grid `spacing` metres wide over `world`, row by row from its
/// lower-left corner, where a robot of `radius` metres stands clear of every wall by a margin of
/// 0.1 m (fewer when the world has no room for `n`).
pub fn grid_starts(world: &WorldDescription, n: usize, spacing: f64, radius: f64) -> Vec<Pose2> {
    let map = crate::world::WorldMap::new(world);
    let (min, max) = world.bounds();
    let mut starts = Vec::new();
    let mut y = min[1] + spacing / 2.0;
    while y < max[1] && starts.len() < n {
        let mut x = min[0] + spacing / 2.0;
        while x < max[0] && starts.len() < n {
            if map.clearance([x, y]) > radius + 0.1 {
                starts.push(Pose2::new(x, y, 0.7 * starts.len() as f64));
            }
            x += spacing;
        }
        y += spacing;
    }
    starts
}

/// Robots in one world, stepping together.
pub struct Fleet {
    robots: Vec<Twin>,
}

impl Fleet {
    /// One robot described by `robot` at each of `starts` in `world`, with the noise `noise`
    /// and the fleet's `seed`. Fails as [`Twin::new`] does, naming the robot's start.
    pub fn new(
        world: &WorldDescription,
        robot: &RobotDescription,
        noise: &NoiseSettings,
        seed: u64,
        starts: &[Pose2],
    ) -> Result<Fleet, ConfigError> {
        let map = Arc::new(crate::world::WorldMap::new(world));
        let robots = starts
            .iter()
            .enumerate()
            .map(|(k, &start)| {
                let mut world = world.clone();
                world.start = start;
                let seed = Self::robot_seed(seed, k);
                Twin::in_map(&world, Arc::clone(&map), robot, noise, seed).map_err(|mut e| {
                    e.message = format!(
                        "robot {k} at ({:.2}, {:.2}): {}",
                        start.x, start.y, e.message
                    );
                    e
                })
            })
            .collect::<Result<Vec<Twin>, ConfigError>>()?;
        Ok(Fleet { robots })
    }

    /// The seed robot `k` of a fleet seeded `seed` runs with.
    pub fn robot_seed(seed: u64, k: usize) -> u64 {
        crate::rng::stream_seed(seed, &format!("robot/{k}"))
    }

    /// Number of robots.
    pub fn len(&self) -> usize {
        self.robots.len()
    }

    /// Whether the fleet has no robot.
    pub fn is_empty(&self) -> bool {
        self.robots.is_empty()
    }

    /// The robots.
    pub fn robots(&self) -> &[Twin] {
        &self.robots
    }

    /// The robots, to command them.
    pub fn robots_mut(&mut self) -> &mut [Twin] {
        &mut self.robots
    }

    /// Advances every robot by one step, then lets `after` act on each (read its scans, send it
    /// commands), robots spread over the threads of the current rayon pool.
    ///
    /// Each robot meets the others' bodies where they stood at the start of the step.
    pub fn step(&mut self, after: impl Fn(usize, &mut Twin) + Sync) {
        let bodies: Arc<Vec<Disc>> = Arc::new(self.robots.iter().map(Twin::body_disc).collect());
        self.robots
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, twin)| {
                twin.set_other_robots(Arc::clone(&bodies), k);
                twin.step();
                after(k, twin);
            });
    }
}
