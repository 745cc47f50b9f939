//! The files a run can write while it goes on: a thread of its own takes each scan as the tour
//! keeps it and builds `map.pgm`'s occupancy grid and `scans.jsonl`'s lines, so they are ready
//! when the simulation ends instead of starting then. The same bytes, to the last one, as the
//! files written from the run's record afterwards: the same scans reach the same builders in the
//! same order.

use super::grid::grid_pose;
use super::scans::{ScanLine, push_scan_line};
use crate::record::Streamed;
use robot::Pose2;
use robot::control::SceneTag;
use robot::hardware::LaserScan;
use robot::localization::{GridBuilder, GridConfig, RangeScan};
use robot::mount::LaserMount;

/// What the run hands over.
#[derive(Debug)]
enum Item {
    /// A scan the tour kept, with the odometry at its stamp and its scene: a line of
    /// `scans.jsonl`.
    Kept(LaserScan, Pose2, Option<SceneTag>),
    /// A level scan seen from the laser pose in the map: into the grid.
    Grid(Pose2, LaserScan),
}

/// Items handed over at once, so the run wakes the builder a few dozen times, not at every
/// scan.
const BATCH: usize = 32;

/// The builder of a run's streamed files, on its own thread.
#[derive(Debug)]
pub struct ScanStream {
    mount: LaserMount,
    batch: Vec<Item>,
    feed: std::sync::mpsc::Sender<Vec<Item>>,
    builder: std::thread::JoinHandle<Streamed>,
}

impl ScanStream {
    /// Starts the builder for a laser on `mount`.
    pub fn start(mount: LaserMount) -> Self {
        let (feed, batches) = std::sync::mpsc::channel::<Vec<Item>>();
        let on_thread = mount.clone();
        let builder = std::thread::spawn(move || {
            let mut grid = GridBuilder::new(GridConfig::default());
            let mut scan_lines = Vec::new();
            for item in batches.into_iter().flatten() {
                match item {
                    Item::Kept(scan, odometry, scene) => push_scan_line(
                        &mut scan_lines,
                        &ScanLine::new(&scan, odometry, &on_thread, scene),
                    ),
                    Item::Grid(laser, scan) => {
                        grid.push(laser, &RangeScan::from(&scan));
                    }
                }
            }
            Streamed {
                grid: grid.finish(),
                scan_lines,
            }
        });
        ScanStream {
            mount,
            batch: Vec::with_capacity(BATCH),
            feed,
            builder,
        }
    }

    /// A scan the tour kept, with the odometry at its stamp and its scene, in the order kept.
    pub fn kept(&mut self, scan: &LaserScan, odometry: Pose2, scene: Option<SceneTag>) {
        self.hand(Item::Kept(scan.clone(), odometry, scene));
    }

    /// A scan for the grid, its base at `base` in the map frame, if its plane was level (the
    /// rule of the grid written afterwards).
    pub fn grid(&mut self, scan: &LaserScan, base: Pose2) {
        if let Some(laser) = grid_pose(&self.mount, scan, base) {
            self.hand(Item::Grid(laser, scan.clone()));
        }
    }

    fn hand(&mut self, item: Item) {
        self.batch.push(item);
        if self.batch.len() == BATCH {
            self.hand_over();
        }
    }

    /// Sends the batch to the builder. It only stops when the feed closes (or when it
    /// panicked, which [`ScanStream::finish`] tells), so a send cannot fail before.
    fn hand_over(&mut self) {
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        let _ = self.feed.send(batch);
    }

    /// Everything built from the scans handed over, once the builder is done.
    pub fn finish(mut self) -> Streamed {
        self.hand_over();
        drop(self.feed);
        self.builder
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
}
