//! The files a run can write while it goes on: a thread of its own takes each scan as the tour
//! keeps it, and each exchange through the hardware contract as the tape notes it, and builds
//! `map.pgm`'s occupancy grid, `scans.jsonl`'s lines, `run.mcap` (but for what follows the run's
//! events), `truth.tum`, `odometry.tum` and `map.svg`'s scan points, so they are ready when the
//! simulation ends instead of starting then. The same bytes, to the last one, as those built
//! from the run's record afterwards: the same items reach the same builders in the same order,
//! and what depends on the twin's truth is kept only if each kept scan's truth, noted as the
//! scan came back, is the one the record holds.

use super::grid::grid_pose;
use super::mcap::{McapStream, RecordedScan};
use super::scans::{ScanLine, push_scan_line};
use super::tum::{TUM_HEADER, write_tum_line};
use crate::config::Scenario;
use crate::devices::laser::LaserFrame;
use crate::record::{RunRecord, ScanDots, Streamed};
use crate::world::WorldMap;
use robot::control::SceneTag;
use robot::hardware::LaserScan;
use robot::localization::{GridBuilder, GridConfig, RangeScan};
use robot::logs::mcap::Recorder;
use robot::mount::LaserMount;
use robot::replay::Exchange;
use robot::{Pose2, Stamp};
use std::io::Cursor;
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
    /// The twin's true pose and laser frame at a scan's stamp, as the scan came back: what the
    /// scan is drawn from in `map.svg`, if the tour keeps it.
    Truth(Stamp, Pose2, LaserFrame),
    /// The run is over.
    End,
}

/// Items handed over at once. Each hand-over wakes the builder, a system call on the
/// simulation's thread: 128 items make about 63 in the polled lab tour (892 scans, 5,445
/// exchanges), where 32 made 250 and cost the simulation 1–2 ms more (the README's *Whole
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
    builder: std::thread::JoinHandle<Built>,
}

/// What the builder made of the items: the files' parts, and what each kept scan was drawn and
/// recorded with.
#[derive(Debug)]
struct Built {
    grid: GridBuilder,
    scan_lines: Vec<u8>,
    /// Exchanges handed over.
    exchanges: usize,
    /// Given up (`None`) at the first kept scan whose truth was not noted.
    dots: Option<ScanDots>,
    recording: Option<McapStream<Cursor<Vec<u8>>>>,
    /// `truth.tum` and `odometry.tum`.
    tum: [Vec<u8>; 2],
    /// The sonar transducers in the recording's `/tf_static`.
    transducers: Vec<Pose2>,
    /// Each kept scan's place among the exchanges, true pose and laser frame, as drawn.
    noted: Vec<(usize, Pose2, LaserFrame)>,
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

    /// The true pose and laser frame at the stamp of a scan that just came back.
    pub fn truth(&self, stamp: Stamp, truth: Pose2, frame: LaserFrame) {
        self.0.hand(Item::Truth(stamp, truth, frame));
    }
}

impl ScanStream {
    /// Starts the builder for `scenario`'s run in the world of `map`, whose robot's sonar
    /// `transducers` (if it fires them) are in the recording.
    pub fn start(scenario: &Scenario, map: Arc<WorldMap>, transducers: Vec<Pose2>) -> Self {
        let (feed, batches) = std::sync::mpsc::channel::<Vec<Item>>();
        let (hand_back, back) = std::sync::mpsc::channel::<Vec<Item>>();
        let mount = scenario.robot.mount();
        let dots = super::new_scan_dots(&scenario.world, map);
        let scan_time_s = super::scan_period_s(&scenario.robot.laser);
        let builder = std::thread::spawn(move || {
            let mut built = Built {
                grid: GridBuilder::new(GridConfig::default()),
                scan_lines: Vec::new(),
                exchanges: 0,
                dots: Some(dots),
                recording: Recorder::new(Cursor::new(Vec::new()))
                    .and_then(|rec| McapStream::start(rec, mount, scan_time_s, &transducers))
                    .ok(),
                tum: [TUM_HEADER.to_vec(), TUM_HEADER.to_vec()],
                transducers,
                noted: Vec::new(),
            };
            // The truths noted and not yet matched with a kept scan, oldest first.
            let mut truths = std::collections::VecDeque::new();
            'batches: for batch in batches {
                let mut ended = false;
                for item in &batch {
                    match item {
                        Item::Kept(scan, odometry, scene) => {
                            built.kept(&mount, scan, *odometry, *scene, &mut truths);
                        }
                        Item::Truth(at, truth, frame) => truths.push_back((*at, *truth, *frame)),
                        Item::Grid(laser, scan) => {
                            built.grid.push(*laser, &RangeScan::from(scan));
                        }
                        Item::Tape(exchange) => built.exchange(exchange),
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
            built
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
    /// still held elsewhere hands nothing more to it), for `record`, the run's record (which
    /// learns where its scans came among the exchanges): the recording is ended with the rest of
    /// the record. The scan points and the recording are kept only if every kept scan was drawn
    /// and recorded from the very truth the record holds.
    pub fn finish(self, record: &mut RunRecord, scenario: &Scenario) -> Streamed {
        {
            let mut feed = self.feed.0.lock().unwrap_or_else(|e| e.into_inner());
            feed.items.push(Item::End);
            Feed::hand_over(&mut feed);
        }
        let built = self
            .builder
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        let same = built.noted.len() == record.scans.len()
            && built
                .noted
                .iter()
                .zip(&record.scans)
                .all(|(&(_, truth, frame), r)| truth == r.truth && frame == r.frame);
        if same {
            for (&(after, ..), r) in built.noted.iter().zip(&mut record.scans) {
                r.after_exchanges = Some(after);
            }
        }
        let transducers = record.sonar.as_ref().map_or(&[][..], |s| &s.transducers);
        let run_mcap = built
            .recording
            .filter(|m| {
                same && m.written() == (record.scans.len(), record.tape.len())
                    && built.transducers == transducers
            })
            .and_then(|m| m.finish(&super::recording(record, scenario)).ok())
            .map(Cursor::into_inner);
        Streamed {
            grid: built.grid,
            scan_lines: built.scan_lines,
            dots: built.dots.filter(|_| same),
            run_mcap,
            tum: same.then_some(built.tum),
        }
    }
}

impl Built {
    /// An exchange of the tape, into the recording.
    fn exchange(&mut self, exchange: &Exchange) {
        self.exchanges += 1;
        if let Some(recording) = &mut self.recording
            && recording.exchange(exchange).is_err()
        {
            // Written afterwards, whole.
            self.recording = None;
        }
    }

    /// A kept scan: its line of `scans.jsonl`, its points and its topics, drawn and recorded
    /// from the truth noted at its stamp (the older truths dropped).
    fn kept(
        &mut self,
        mount: &LaserMount,
        scan: &LaserScan,
        odometry: Pose2,
        scene: Option<SceneTag>,
        truths: &mut std::collections::VecDeque<(Stamp, Pose2, LaserFrame)>,
    ) {
        push_scan_line(
            &mut self.scan_lines,
            &ScanLine::new(scan, odometry, mount, scene),
        );
        while truths.front().is_some_and(|t| t.0 < scan.stamp) {
            truths.pop_front();
        }
        let Some(&(_, truth, frame)) = truths.front().filter(|t| t.0 == scan.stamp) else {
            // Not drawn nor recorded from the truth: both are made afterwards.
            self.dots = None;
            self.recording = None;
            return;
        };
        let after = self.exchanges;
        self.noted.push((after, truth, frame));
        if let Some(dots) = &mut self.dots {
            dots.add(scan, &frame, truth, odometry);
        }
        for (tum, pose) in self.tum.iter_mut().zip([truth, odometry]) {
            write_tum_line(tum, scan.stamp, pose).expect("a vector takes every byte");
        }
        let recorded = RecordedScan {
            scan,
            odometry,
            truth: Some(truth),
            after: Some(after),
        };
        if let Some(recording) = &mut self.recording
            && recording.scan(&recorded).is_err()
        {
            self.recording = None;
        }
    }
}
