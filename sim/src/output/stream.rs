//! The files a run can write while it goes on: a thread of its own takes each scan as the tour
//! keeps it, and each exchange through the hardware contract as the tape notes it, and builds
//! `map.pgm`'s occupancy grid, `scans.jsonl`'s lines and the tape's JSON for `run.mcap`, so they
//! are ready when the simulation ends instead of starting then. The same bytes, to the last one,
//! as those built from the run's record afterwards: the same items reach the same builders in
//! the same order.

use super::grid::grid_pose;
use super::scans::{ScanLine, push_scan_line};
use crate::record::Streamed;
use robot::Pose2;
use robot::control::SceneTag;
use robot::hardware::LaserScan;
use robot::localization::{GridBuilder, GridConfig, RangeScan};
use robot::mount::LaserMount;
use robot::replay::Exchange;
use std::sync::mpsc::{Receiver, Sender};
use std::sync::{Arc, Mutex};

/// What the run hands over.
#[derive(Debug)]
enum Item {
    /// A scan the tour kept, with the odometry at its stamp and its scene: a line of
    /// `scans.jsonl`.
    Kept(LaserScan, Pose2, Option<SceneTag>),
    /// A level scan seen from the laser pose in the map: into the grid.
    Grid(Pose2, LaserScan),
    /// An exchange the tape noted: its JSON.
    Tape(Box<Exchange>),
    /// The run is over.
    End,
}

/// Items handed over at once. Each hand-over wakes the builder, a system call on the
/// simulation's thread: 128 items make about 55 in the polled lab tour (892 scans, 5,445
/// exchanges), where 32 made 220 and cost the simulation 1–2 ms more (the README's *Whole
/// process against simulation*). The builder's last batch, after the simulation, is at most
/// this long.
const BATCH: usize = 128;

/// Where the run's items go: the batch being filled and the builder's end of the channel,
/// shared by the tour's observer and the tape's hook (both on the simulation's thread, one after
/// the other, so the items keep the order they happened in).
#[derive(Clone, Debug)]
struct Feed(Arc<Mutex<Pending>>);

/// The items not yet handed over, the channel to the builder, and the batches it handed back.
///
/// The builder reads the items where they are and hands each batch back whole, and the
/// simulation's thread, which allocated them, frees them: a block freed by another thread takes
/// the allocator's lock that this thread's own allocations wait on. Freed by the builder, the
/// batches had the simulation wait on that lock 46 times in the polled lab tour (`strace -f`),
/// 5 times since; the process's context switches fell from 210–283 to 136–145.
#[derive(Debug)]
struct Pending {
    items: Vec<Item>,
    to_builder: Sender<Vec<Item>>,
    back: Receiver<Vec<Item>>,
}

impl Feed {
    fn hand(&self, item: Item) {
        let mut feed = self.0.lock().unwrap_or_else(|e| e.into_inner());
        feed.items.push(item);
        if feed.items.len() >= BATCH {
            Self::hand_over(&mut feed);
        }
    }

    /// Sends the batch to the builder, in a batch it handed back if there is one (emptied
    /// here). It only stops at [`Item::End`] (or when it panicked, which
    /// [`ScanStream::finish`] tells), so a send cannot fail before.
    fn hand_over(feed: &mut Pending) {
        let mut next = None;
        while let Ok(mut done) = feed.back.try_recv() {
            done.clear();
            next.get_or_insert(done);
        }
        let next = next.unwrap_or_else(|| Vec::with_capacity(BATCH));
        let batch = std::mem::replace(&mut feed.items, next);
        let _ = feed.to_builder.send(batch);
    }
}

/// The builder of a run's streamed files, on its own thread.
#[derive(Debug)]
pub struct ScanStream {
    mount: LaserMount,
    feed: Feed,
    builder: std::thread::JoinHandle<Streamed>,
}

/// The tape's side of a [`ScanStream`]: give it each exchange as the tape notes it
/// (`robot::replay::Taped::with_hook`).
#[derive(Clone, Debug)]
pub struct TapeFeed(Feed);

impl TapeFeed {
    /// An exchange the tape noted, in the tape's order.
    pub fn exchange(&self, exchange: &Exchange) {
        self.0.hand(Item::Tape(Box::new(exchange.clone())));
    }
}

impl ScanStream {
    /// Starts the builder for a laser on `mount`.
    pub fn start(mount: LaserMount) -> Self {
        let (feed, batches) = std::sync::mpsc::channel::<Vec<Item>>();
        let (hand_back, back) = std::sync::mpsc::channel::<Vec<Item>>();
        let on_thread = mount;
        let builder = std::thread::spawn(move || {
            let mut grid = GridBuilder::new(GridConfig::default());
            let (mut scan_lines, mut tape_json) = (Vec::new(), Vec::new());
            'batches: for batch in batches {
                let mut ended = false;
                for item in &batch {
                    match item {
                        Item::Kept(scan, odometry, scene) => push_scan_line(
                            &mut scan_lines,
                            &ScanLine::new(scan, *odometry, &on_thread, *scene),
                        ),
                        Item::Grid(laser, scan) => {
                            grid.push(*laser, &RangeScan::from(scan));
                        }
                        Item::Tape(exchange) => {
                            tape_json.push(super::mcap::tape_json(exchange));
                        }
                        Item::End => {
                            ended = true;
                            break;
                        }
                    }
                }
                // Freed by the thread that allocated it (see `Pending`), unless it is gone.
                if hand_back.send(batch).is_err() || ended {
                    break 'batches;
                }
            }
            Streamed {
                grid,
                scan_lines,
                tape_json,
            }
        });
        ScanStream {
            mount,
            feed: Feed(Arc::new(Mutex::new(Pending {
                items: Vec::with_capacity(BATCH),
                to_builder: feed,
                back,
            }))),
            builder,
        }
    }

    /// The feed for the tape's hook.
    pub fn tape_feed(&self) -> TapeFeed {
        TapeFeed(self.feed.clone())
    }

    /// A scan the tour kept, with the odometry at its stamp and its scene, in the order kept.
    pub fn kept(&mut self, scan: &LaserScan, odometry: Pose2, scene: Option<SceneTag>) {
        self.feed.hand(Item::Kept(scan.clone(), odometry, scene));
    }

    /// A scan for the grid, its base at `base` in the map frame, if its plane was level (the
    /// rule of the grid written afterwards).
    pub fn grid(&mut self, scan: &LaserScan, base: Pose2) {
        if let Some(laser) = grid_pose(&self.mount, scan, base) {
            self.feed.hand(Item::Grid(laser, scan.clone()));
        }
    }

    /// Everything built from the items handed over, once the builder is done (a tape feed
    /// still held elsewhere hands nothing more to it).
    pub fn finish(self) -> Streamed {
        {
            let mut feed = self.feed.0.lock().unwrap_or_else(|e| e.into_inner());
            feed.items.push(Item::End);
            Feed::hand_over(&mut feed);
        }
        self.builder
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
}
