//! A scripted tour: send each step's command, follow motions to their end, and pair laser scans
//! with the odometry pose at the scan's timestamp.
//!
//! The tour talks only to the hardware contract, so the same code drives the twin and the real
//! robot. It never reads a clock: time comes from the stamps of the status reports and scans, and
//! passes when the tour blocks on the devices (a wait, a scan read with a timeout, a status round
//! trip).
//!
//! Two pacings, because of how the base firmware counts (thesis App. A):
//!
//! - [`Pacing::StopAndGo`] (the default, and how the thesis drove its robot): after a motion
//!   command the tour waits with the firmware's `w` until both motors are off, reads the counters
//!   once at rest, and keeps the first scan measured after the robot has settled. The counters are
//!   exact this way (less the wheels' coast after the brake, which the firmware never counts).
//! - [`Pacing::Polling`]: the tour polls `l` while the robot moves and keeps every scan, with the
//!   odometry interpolated to the scan's stamp from a FIFO of status reports. Each status reply
//!   keeps the firmware's main loop busy while it is sent (18 ms at 9600 bps); above about 13
//!   counts per tick the 8-bit encoder accumulators saturate meanwhile and counts are lost, so the
//!   robot overshoots and the odometry falls short. Use it with a slow ramp (`k5 12 50`).

use crate::control::navigate::{
    Decision, NavConfig, NavOutcome, Progress, Surroundings, explore_decision, goto_decision,
};
use crate::control::script::{SCENE_TILTS, Step, StepError};
use crate::drive_geometry::DriveGeometry;
use crate::geometry::Pose2;
use crate::hardware::{
    DriveBase, DriveCommand, DriveStatus, DriveWait, HardwareError, Laser, LaserScan, PAN_MAX,
    PanTilt, PanTiltPosition, SonarRing, TILT_MAX,
};
use crate::odometry::{Odometer, PoseHistory};
use crate::protocol::base::DriveLine;
use crate::time::Stamp;
use core::time::Duration;
use std::collections::VecDeque;

/// How the tour waits for motions and which scans it keeps.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Pacing {
    /// Wait for each motion with `w`, read the counters at rest, keep one scan measured at least
    /// `settle` after the motors stopped.
    StopAndGo {
        /// Time for the wheels to stop coasting after the brake.
        settle: Duration,
    },
    /// Poll the counters while moving, waiting at most `period` for a scan between polls; keep
    /// every scan.
    Polling {
        /// Longest wait for a scan before the base is polled again.
        period: Duration,
    },
}

/// How a tour paces itself.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TourConfig {
    /// How motions are awaited and which scans are kept.
    pub pacing: Pacing,
    /// Longest wait for a scan before the base is polled again while pausing.
    pub poll: Duration,
    /// A motion that has not ended after this long (robot time) fails the tour; so does a laser
    /// that sends nothing for this long.
    pub motion_timeout: Duration,
    /// How `goto` and `explore` steps drive, and what the robot senses them with.
    pub navigation: NavConfig,
}

impl TourConfig {
    /// The default tour, polling the base every `period` at most while moving and keeping
    /// every scan.
    pub fn polling(period: Duration) -> Self {
        TourConfig {
            pacing: Pacing::Polling { period },
            ..TourConfig::default()
        }
    }
}

impl Default for TourConfig {
    fn default() -> Self {
        TourConfig {
            pacing: Pacing::StopAndGo {
                settle: Duration::from_millis(100),
            },
            poll: Duration::from_millis(50),
            motion_timeout: Duration::from_secs(120),
            navigation: NavConfig::default(),
        }
    }
}

/// What a tour reports to its observer as it goes.
#[derive(Debug)]
pub enum TourEvent<'a> {
    /// Step `index` (0-based) of `total` is about to be carried out.
    StepStarted {
        /// Index of the step.
        index: usize,
        /// Number of steps.
        total: usize,
        /// The step.
        step: &'a Step,
    },
    /// A scan, with the odometry pose interpolated to its stamp.
    Scan {
        /// The scan.
        scan: &'a LaserScan,
        /// Odometry at `scan.stamp`, in the tour's starting frame.
        odometry: Pose2,
        /// The 3D scene the scan belongs to, if a `scene` or `survey` step took it.
        scene: Option<SceneTag>,
    },
    /// A `goto` or `explore` step decided what to do next (or that it is over).
    Decision {
        /// When, the stamp of the last status report.
        stamp: Stamp,
        /// Where the robot believed it was (map frame): the estimate carried forward by
        /// odometry, or the odometry alone when nothing localises.
        estimate: Pose2,
        /// The odometry then.
        odometry: Pose2,
        /// The goal of a `goto` step, map frame (none when exploring).
        goal: Option<[f64; 2]>,
        /// What it decided.
        decision: &'a Decision,
    },
}

/// Where the localisation last placed the robot: what a navigating step steers by.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Fix {
    /// The estimate at the last placed scan, map frame.
    pub estimate: Pose2,
    /// The odometry at that scan.
    pub odometry: Pose2,
    /// Scan matches not trusted in a row up to that scan (0 when the last one was trusted).
    pub untrusted: usize,
}

/// What watches a tour: it gets the tour's events and, for the steps that navigate, tells
/// where the localisation has placed the robot. A closure taking [`TourEvent`]s is an observer
/// that does not localise (navigation then steers by odometry).
pub trait TourObserver {
    /// One event of the tour.
    fn event(&mut self, event: TourEvent<'_>);

    /// The localisation's latest fix, if it localises.
    fn fix(&self) -> Option<Fix> {
        None
    }
}

impl<F: FnMut(TourEvent<'_>)> TourObserver for F {
    fn event(&mut self, event: TourEvent<'_>) {
        self(event)
    }
}

/// Which 3D scene a scan belongs to, and where it was taken.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct SceneTag {
    /// The scene's number in the tour, from 0.
    pub scene: usize,
    /// The station's number, from 0: scenes taken without the base moving in between share it.
    pub station: usize,
}

/// Why a tour stopped.
#[derive(Debug, thiserror::Error)]
pub enum TourError<E: HardwareError> {
    /// The hardware failed.
    #[error("step {index} `{step}`: {source}")]
    Hardware {
        /// Index of the step (0-based).
        index: usize,
        /// The step, as written.
        step: String,
        /// The backend's error.
        #[source]
        source: E,
    },
    /// The step cannot be carried out on this robot.
    #[error("step {index} `{step}`: {source}")]
    Step {
        /// Index of the step (0-based).
        index: usize,
        /// The step, as written.
        step: String,
        /// Why.
        #[source]
        source: StepError,
    },
    /// A motion did not end in time, or the laser sent nothing.
    #[error("step {index} `{step}`: the motion had not ended, or no scan came, after {timeout:?}")]
    Stuck {
        /// Index of the step (0-based).
        index: usize,
        /// The step, as written.
        step: String,
        /// The limit that was exceeded.
        timeout: Duration,
    },
}

/// What a finished tour did.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TourReport {
    /// Steps carried out.
    pub steps: usize,
    /// Scans handed to the observer.
    pub scans: usize,
    /// 3D scenes taken.
    pub scenes: usize,
    /// The odometry pose at the end.
    pub final_odometry: Pose2,
    /// The stamp of the last status report.
    pub end: Stamp,
    /// Motions that ended short of their target with the motors left on, stopped with `p`
    /// (see [`STALL`]).
    pub stalled: usize,
    /// `goto` and `explore` steps that did what they were asked.
    pub navigated: usize,
    /// `goto` and `explore` steps that stopped short (blocked, no way, lost, out of decisions).
    pub navigation_failures: usize,
}

/// A motion whose counters have not moved for this long (robot time) while the firmware still
/// reports its motors on has ended short of its target. The firmware (App. A) brakes from the
/// point where the distance left equals the distance it took to accelerate, one speed step every
/// `k_ms_inc`, down to zero; the motors are switched off only when both wheels have passed
/// `clicks_stop`. When the ramp reaches zero speed a few counts short — which the timing of the
/// main loop decides, and answering `l` polls while moving shifts that timing — the wheels stand
/// still with the motors on for ever. The tour then stops them with `p`, as a driver would.
pub const STALL: Duration = Duration::from_millis(500);

/// Readings nearer than this to a neighbour's are corroborated, metres.
const NEIGHBOUR_M: f64 = 0.1;

/// The readings of `scan` (beam, range) that a neighbouring beam corroborates: a surface returns
/// several adjacent beams, a random outlier (dust, a short reading) one. A controller that
/// braked for every lone reading would stop for nothing a few times a minute.
fn corroborated(scan: &LaserScan) -> impl Iterator<Item = (usize, f64)> + '_ {
    let point = |k: usize| {
        let r = scan.range_m(k)?;
        let a = scan.angle(k);
        Some((r * a.cos(), r * a.sin(), r))
    };
    (0..scan.len()).filter_map(move |k| {
        let (x, y, r) = point(k)?;
        let near = |j: Option<usize>| {
            j.and_then(point)
                .is_some_and(|(u, v, _)| (u - x).hypot(v - y) <= NEIGHBOUR_M)
        };
        (near(k.checked_sub(1)) || near(Some(k + 1).filter(|&j| j < scan.len()))).then_some((k, r))
    })
}

/// Turns smaller than this are not worth a motion, radians (half a degree).
const TURN_DEADBAND: f64 = 0.5 * core::f64::consts::PI / 180.0;

/// What a navigating step is after.
#[derive(Copy, Clone, Debug)]
enum Task {
    /// A goal, map frame, metres.
    Goto([f64; 2]),
    /// Wall following for this long.
    Explore(Duration),
}

impl Task {
    /// How long the step may take (explore), or no limit (goto: its decisions are counted).
    fn duration(&self) -> Duration {
        match self {
            Task::Goto(_) => Duration::MAX,
            Task::Explore(d) => *d,
        }
    }

    /// Distance from `pose` to the goal (0 when exploring).
    fn distance(&self, pose: Pose2) -> f64 {
        match self {
            Task::Goto(g) => (g[0] - pose.x).hypot(g[1] - pose.y),
            Task::Explore(_) => 0.0,
        }
    }
}

/// Watches a motion's counters for a stall.
#[derive(Default)]
struct Still {
    /// The counters last seen and since when they have not changed.
    since: Option<((u32, u32), Stamp)>,
}

impl Still {
    /// Whether the counters in `status` have not moved for [`STALL`] with the motors on, once
    /// the motion has begun (a slow ramp may take a while to move the wheels at all).
    fn stalled(&mut self, status: &DriveStatus) -> bool {
        let counts = (status.left_counts, status.right_counts);
        if counts == (0, 0) {
            return false;
        }
        match self.since {
            Some((seen, at)) if seen == counts => status.stamp.saturating_since(at) >= STALL,
            _ => {
                self.since = Some((counts, status.stamp));
                false
            }
        }
    }
}

/// Runs `steps` on `robot`, starting the odometry at `start`, and reports to `observer`.
pub fn run_tour<R, F>(
    robot: &mut R,
    geometry: DriveGeometry,
    start: Pose2,
    steps: &[Step],
    config: &TourConfig,
    mut observer: F,
) -> Result<TourReport, TourError<R::Error>>
where
    R: DriveBase + Laser + PanTilt + SonarRing,
    F: TourObserver,
{
    let mut tour = Tour {
        geometry,
        config: *config,
        odometer: Odometer::new(geometry, start),
        history: PoseHistory::new(4096),
        pending: VecDeque::new(),
        last_status: None,
        scans: 0,
        scenes: 0,
        stalled: 0,
        station: None,
        stations: 0,
        navigated: 0,
        navigation_failures: 0,
        surroundings: None,
    };
    for (index, step) in steps.iter().enumerate() {
        observer.event(TourEvent::StepStarted {
            index,
            total: steps.len(),
            step,
        });
        tour.carry_out(robot, step, &mut observer)
            .map_err(|e| e.at(index, step))?;
    }
    tour.finish(robot, &mut observer)
        .map_err(|e| e.at(steps.len(), &Step::Pause { seconds: 0.0 }))?;
    Ok(TourReport {
        steps: steps.len(),
        scans: tour.scans,
        scenes: tour.scenes,
        final_odometry: tour.odometer.pose(),
        end: tour.last_status.map_or(Stamp::ZERO, |s| s.stamp),
        stalled: tour.stalled,
        navigated: tour.navigated,
        navigation_failures: tour.navigation_failures,
    })
}

/// A failure inside a step, before the step's index is known.
enum Failure<E> {
    Hardware(E),
    Step(StepError),
    Stuck(Duration),
}

impl<E: HardwareError> Failure<E> {
    fn at(self, index: usize, step: &Step) -> TourError<E> {
        let step = step.to_string();
        match self {
            Failure::Hardware(source) => TourError::Hardware {
                index,
                step,
                source,
            },
            Failure::Step(source) => TourError::Step {
                index,
                step,
                source,
            },
            Failure::Stuck(timeout) => TourError::Stuck {
                index,
                step,
                timeout,
            },
        }
    }
}

struct Tour {
    geometry: DriveGeometry,
    config: TourConfig,
    odometer: Odometer,
    history: PoseHistory,
    /// Scans received but not yet bracketed by a status report.
    pending: VecDeque<LaserScan>,
    last_status: Option<DriveStatus>,
    scans: usize,
    /// Scenes taken so far.
    scenes: usize,
    /// The station of the last scene, while the base has not moved since.
    station: Option<usize>,
    /// Stations so far.
    stations: usize,
    /// Motions stopped short with `p`.
    stalled: usize,
    /// Navigating steps that succeeded.
    navigated: usize,
    /// Navigating steps that stopped short.
    navigation_failures: usize,
    /// What a navigating step has seen, while one runs.
    surroundings: Option<Surroundings>,
}

impl Tour {
    fn carry_out<R, F>(
        &mut self,
        robot: &mut R,
        step: &Step,
        observer: &mut F,
    ) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser + PanTilt + SonarRing,
        F: TourObserver,
    {
        match step.to_line(&self.geometry).map_err(Failure::Step)? {
            Some(DriveLine::Command(command)) => {
                let motion = command.resets_counters();
                if motion {
                    // The firmware clears its counters on a motion command: read them first.
                    self.poll_status(robot, observer)?;
                }
                robot.drive(command).map_err(Failure::Hardware)?;
                self.odometer.commanded(&command);
                if motion || matches!(command, DriveCommand::WheelSpeeds { .. }) {
                    // The base moves: the next scene is taken at a new station.
                    self.station = None;
                }
                if motion {
                    match self.config.pacing {
                        Pacing::StopAndGo { settle } => {
                            self.stop_and_go(robot, settle, observer)?
                        }
                        Pacing::Polling { period } => {
                            self.follow_motion(robot, period, observer)?
                        }
                    }
                }
            }
            Some(DriveLine::Wait(wait)) => {
                robot.wait_drive(wait).map_err(Failure::Hardware)?;
                self.poll_status(robot, observer)?;
            }
            None => match *step {
                Step::Pause { seconds } => {
                    let from = self.poll_status(robot, observer)?.stamp;
                    let until = from + Duration::from_secs_f64(seconds);
                    while self.service(robot, self.config.poll, observer)?.stamp < until {}
                }
                Step::Head { pan, tilt } => {
                    self.move_head(robot, PanTiltPosition { pan, tilt })?;
                }
                Step::Sweep {
                    pan,
                    from,
                    to,
                    step,
                } => {
                    let settle = self.settle();
                    for tilt in Step::sweep_tilts(from, to, step) {
                        let stopped = self.move_head(robot, PanTiltPosition { pan, tilt })?;
                        self.scan_at_rest(robot, stopped, settle, None, observer)?;
                    }
                }
                Step::Scene { pan, from, to } => {
                    self.scenes_at(robot, &[pan], (from, to), observer)?;
                }
                Step::Survey { pans } => {
                    self.scenes_at(robot, &pans, SCENE_TILTS, observer)?;
                }
                Step::Goto { x, y } => {
                    self.navigate(robot, Task::Goto([x, y]), observer)?;
                }
                Step::Explore { seconds } => {
                    self.navigate(
                        robot,
                        Task::Explore(Duration::from_secs_f64(seconds)),
                        observer,
                    )?;
                }
                _ => unreachable!("only pauses and head steps send no drive line"),
            },
        }
        Ok(())
    }

    /// A level scan of the station, then one scene per pan, each a scan at rest at every tilt
    /// from `tilts.0` to `tilts.1`; the head then goes back where it was.
    fn scenes_at<R, F>(
        &mut self,
        robot: &mut R,
        pans: &[u8],
        tilts: (u8, u8),
        observer: &mut F,
    ) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser + PanTilt,
        F: TourObserver,
    {
        let settle = self.settle();
        let before = robot.pan_tilt_status().map_err(Failure::Hardware)?;
        // The station scan, with the head as it was (level, for the 2D localisation).
        self.scan_at_rest(robot, before.stamp, settle, None, observer)?;
        let station = match self.station {
            Some(s) => s,
            None => {
                let next = self.stations;
                self.stations += 1;
                self.station = Some(next);
                next
            }
        };
        for &pan in pans {
            let tag = SceneTag {
                scene: self.scenes,
                station,
            };
            self.scenes += 1;
            for tilt in Step::sweep_tilts(tilts.0, tilts.1, 1) {
                let stopped = self.move_head(robot, PanTiltPosition { pan, tilt })?;
                self.scan_at_rest(robot, stopped, settle, Some(tag), observer)?;
            }
        }
        let clamp = |v: i16, max: u8| v.clamp(0, i16::from(max)) as u8;
        self.move_head(
            robot,
            PanTiltPosition {
                pan: clamp(before.pan, PAN_MAX),
                tilt: clamp(before.tilt, TILT_MAX),
            },
        )?;
        Ok(())
    }

    /// How long after a stop a scan is taken at rest.
    fn settle(&self) -> Duration {
        match self.config.pacing {
            Pacing::StopAndGo { settle } => settle,
            Pacing::Polling { .. } => Duration::from_millis(100),
        }
    }

    /// Moves the head and waits until both its motors are off; returns when they were seen off.
    fn move_head<R>(
        &mut self,
        robot: &mut R,
        target: PanTiltPosition,
    ) -> Result<Stamp, Failure<R::Error>>
    where
        R: PanTilt,
    {
        // Polls every 50 firmware ticks; a full pan turn takes about 8 s.
        let polls = (self.config.motion_timeout.as_millis() / 50).max(1) as u32;
        let status = robot
            .move_pan_tilt_to(target, 50, polls)
            .map_err(Failure::Hardware)?;
        if !status.idle() {
            return Err(Failure::Stuck(self.config.motion_timeout));
        }
        Ok(status.stamp)
    }

    /// Hands over the first scan measured `settle` after the robot (or head) stopped at
    /// `stopped`, with the odometry at rest; scans measured before are skipped.
    fn scan_at_rest<R, F>(
        &mut self,
        robot: &mut R,
        stopped: Stamp,
        settle: Duration,
        scene: Option<SceneTag>,
        observer: &mut F,
    ) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        self.pending.clear();
        let scan = robot
            .read_scan_since(stopped + settle, self.config.motion_timeout)
            .map_err(Failure::Hardware)?
            .ok_or(Failure::Stuck(self.config.motion_timeout))?;
        self.scans += 1;
        observer.event(TourEvent::Scan {
            scan: &scan,
            odometry: self.odometer.pose(),
            scene,
        });
        if let Some(seen) = &mut self.surroundings {
            let navigation = &self.config.navigation;
            if let Some(laser) = navigation.mount.laser_on_base(scan.head)
                && laser.is_level(navigation.level_tolerance_rad)
            {
                let base = self.odometer.pose();
                let points = corroborated(&scan)
                    .map(|(k, r)| {
                        let p = laser.point(scan.angle(k), r);
                        let (x, y) = base.transform_point(p[0], p[1]);
                        [x, y]
                    })
                    .collect();
                seen.add_scan(points, navigation.memory);
            }
        }
        Ok(())
    }

    /// A `goto` or `explore` step: look at rest, decide, turn and move by the firmware's own
    /// motions, and again, until the step is over (see [`crate::control::navigate`]).
    fn navigate<R, F>(
        &mut self,
        robot: &mut R,
        task: Task,
        observer: &mut F,
    ) -> Result<NavOutcome, Failure<R::Error>>
    where
        R: DriveBase + Laser + SonarRing,
        F: TourObserver,
    {
        let config = self.config.navigation;
        self.surroundings = Some(Surroundings::default());
        let status = self.poll_status(robot, observer)?;
        let until = status.stamp + task.duration();
        self.look(robot, status.stamp, observer)?;
        let mut progress: Option<Progress> = None;
        let mut decisions = 0;
        let outcome = loop {
            let odometry = self.odometer.pose();
            let fix = observer.fix();
            let estimate = fix.map_or(odometry, |f| {
                f.estimate.compose(&f.odometry.relative(&odometry))
            });
            let around = self
                .surroundings
                .as_ref()
                .map(|s| s.around(odometry))
                .unwrap_or_default();
            let now = self.last_status.map_or(Stamp::ZERO, |s| s.stamp);
            let to_go = task.distance(estimate);
            let decision = match fix {
                Some(f) if f.untrusted >= config.lost_after => Decision::Done(NavOutcome::Lost {
                    untrusted: f.untrusted,
                }),
                // A goal's decisions are counted; exploring is bounded by its time.
                _ if decisions >= config.max_decisions && matches!(task, Task::Goto(_)) => {
                    Decision::Done(NavOutcome::OutOfDecisions { distance_m: to_go })
                }
                _ => match task {
                    Task::Goto(goal) => {
                        let stalled = progress
                            .get_or_insert_with(|| Progress::new(to_go))
                            .stalled(to_go, &config);
                        match goto_decision(estimate, goal, &around, &config) {
                            Decision::Motion { .. } if stalled => {
                                Decision::Done(NavOutcome::NoWay { distance_m: to_go })
                            }
                            d => d,
                        }
                    }
                    Task::Explore(_) if now >= until => Decision::Done(NavOutcome::Explored),
                    Task::Explore(_) => explore_decision(&around, &config),
                },
            };
            observer.event(TourEvent::Decision {
                stamp: now,
                estimate,
                odometry,
                goal: match task {
                    Task::Goto(goal) => Some(goal),
                    Task::Explore(_) => None,
                },
                decision: &decision,
            });
            decisions += 1;
            match decision {
                Decision::Done(outcome) => break outcome,
                Decision::Motion {
                    turn_rad,
                    advance_m,
                    ..
                } => {
                    let mut moved = false;
                    if turn_rad.abs() >= TURN_DEADBAND {
                        let step = Step::Turn {
                            degrees: turn_rad.to_degrees(),
                        };
                        moved |= self.sensed_motion(robot, &step, observer)?;
                    }
                    if advance_m >= config.min_step_m {
                        let step = Step::Move { metres: advance_m };
                        moved |= self.sensed_motion(robot, &step, observer)?;
                    }
                    if !moved {
                        // Too small to move: look again rather than decide on the same view.
                        let status = self.poll_status(robot, observer)?;
                        self.look(robot, status.stamp, observer)?;
                    }
                }
            }
        };
        self.surroundings = None;
        if outcome.succeeded() {
            self.navigated += 1;
        } else {
            self.navigation_failures += 1;
        }
        Ok(outcome)
    }

    /// One motion of a navigating step, stop-and-go whatever the tour's pacing, then a look at
    /// rest; whether a motion was sent.
    fn sensed_motion<R, F>(
        &mut self,
        robot: &mut R,
        step: &Step,
        observer: &mut F,
    ) -> Result<bool, Failure<R::Error>>
    where
        R: DriveBase + Laser + SonarRing,
        F: TourObserver,
    {
        let Some(DriveLine::Command(command)) =
            step.to_line(&self.geometry).map_err(Failure::Step)?
        else {
            return Ok(false);
        };
        self.poll_status(robot, observer)?;
        robot.drive(command).map_err(Failure::Hardware)?;
        self.odometer.commanded(&command);
        self.station = None;
        let stopped = self.wait_stopped(robot, observer)?;
        self.look(robot, stopped, observer)?;
        Ok(true)
    }

    /// At rest since `stopped`: a scan (to the observer and the surroundings) and, when the
    /// ring fires, a full cycle of the sonar heard from here.
    fn look<R, F>(
        &mut self,
        robot: &mut R,
        stopped: Stamp,
        observer: &mut F,
    ) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser + SonarRing,
        F: TourObserver,
    {
        let settle = self.settle();
        self.scan_at_rest(robot, stopped, settle, None, observer)?;
        let Some(ring) = self.config.navigation.sonar else {
            return Ok(());
        };
        let ms = (ring.cycle.as_secs_f64() * 1000.0 / 1.024).ceil();
        robot
            .wait_drive(DriveWait::sleep(ms.clamp(1.0, f64::from(u16::MAX)) as u16))
            .map_err(Failure::Hardware)?;
        let echoes = robot.sonar_echoes().map_err(Failure::Hardware)?;
        let base = self.odometer.pose();
        let mut points = Vec::new();
        for (i, &k) in echoes.sequence.iter().enumerate() {
            let fresh = echoes
                .measured
                .get(i)
                .copied()
                .flatten()
                .is_some_and(|t| t >= stopped);
            let range = echoes.distance_m(i, ring.speed_of_sound);
            if let (true, Some(range)) = (fresh, range)
                && range <= ring.max_range_m
                && k < ring.count
            {
                points.extend(ring.echo_points(k, range).map(|p| {
                    let (x, y) = base.transform_point(p[0], p[1]);
                    [x, y]
                }));
            }
        }
        if let Some(seen) = &mut self.surroundings {
            seen.add_sonar(points, self.config.navigation.memory);
        }
        self.poll_status(robot, observer)?;
        Ok(())
    }

    /// Waits with `w` until the motors are off, reads the counters, then keeps the first scan
    /// measured once the robot has settled; scans measured before are skipped.
    fn stop_and_go<R, F>(
        &mut self,
        robot: &mut R,
        settle: Duration,
        observer: &mut F,
    ) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        let stopped = self.wait_stopped(robot, observer)?;
        // Scans measured during the motion are of no use without odometry: skip them.
        self.scan_at_rest(robot, stopped, settle, None, observer)
    }

    /// Waits with `w` until the motors are off (stopping a stalled motion with `p`) and reads
    /// the counters; returns when they were seen off.
    fn wait_stopped<R, F>(
        &mut self,
        robot: &mut R,
        observer: &mut F,
    ) -> Result<Stamp, Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        // `w` waits at most 65535 ticks; a longer motion takes several waits.
        let wait_ms = self
            .config
            .motion_timeout
            .as_millis()
            .clamp(1, u128::from(u16::MAX)) as u16;
        let mut started: Option<Stamp> = None;
        let mut still = Still::default();
        let stopped = loop {
            robot
                .wait_drive(DriveWait::motors(wait_ms))
                .map_err(Failure::Hardware)?;
            let status = self.poll_status(robot, observer)?;
            if status.is_idle() {
                break status;
            }
            if still.stalled(&status) {
                break self.stop_short(robot, observer)?;
            }
            let t0 = *started.get_or_insert(status.stamp);
            if status.stamp.saturating_since(t0) > self.config.motion_timeout {
                return Err(Failure::Stuck(self.config.motion_timeout));
            }
        };
        Ok(stopped.stamp)
    }

    /// Reads scans and polls the base until both drive motors are off.
    fn follow_motion<R, F>(
        &mut self,
        robot: &mut R,
        period: Duration,
        observer: &mut F,
    ) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        let mut started: Option<Stamp> = None;
        let mut still = Still::default();
        loop {
            let status = self.service(robot, period, observer)?;
            if status.is_idle() {
                return Ok(());
            }
            if still.stalled(&status) {
                self.stop_short(robot, observer)?;
                return Ok(());
            }
            let t0 = *started.get_or_insert(status.stamp);
            if status.stamp.saturating_since(t0) > self.config.motion_timeout {
                return Err(Failure::Stuck(self.config.motion_timeout));
            }
        }
    }

    /// Stops a motion that ended short of its target (see [`STALL`]) with `p`, and reads the
    /// counters once more.
    fn stop_short<R, F>(
        &mut self,
        robot: &mut R,
        observer: &mut F,
    ) -> Result<DriveStatus, Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        robot.drive(DriveCommand::Stop).map_err(Failure::Hardware)?;
        self.odometer.commanded(&DriveCommand::Stop);
        self.stalled += 1;
        self.poll_status(robot, observer)
    }

    /// Waits for a scan (at most `period`), then polls the base.
    fn service<R, F>(
        &mut self,
        robot: &mut R,
        period: Duration,
        observer: &mut F,
    ) -> Result<DriveStatus, Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        if let Some(scan) = robot.read_scan(period).map_err(Failure::Hardware)? {
            self.pending.push_back(scan);
        }
        self.poll_status(robot, observer)
    }

    /// Polls the base, integrates odometry and hands over every scan now bracketed.
    fn poll_status<R, F>(
        &mut self,
        robot: &mut R,
        observer: &mut F,
    ) -> Result<DriveStatus, Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        let status = robot.drive_status().map_err(Failure::Hardware)?;
        let pose = self.odometer.observe(&status);
        self.history.push(status.stamp, pose);
        self.last_status = Some(status);
        self.emit_ready(observer, false);
        Ok(status)
    }

    /// Hands over the scans whose stamp the odometry history covers (or all, when finishing).
    fn emit_ready<F: TourObserver>(&mut self, observer: &mut F, all: bool) {
        while let Some(scan) = self.pending.front() {
            let odometry = match self.history.at(scan.stamp) {
                Some(pose) => pose,
                None => match self.history.latest() {
                    // Older than the history (only before the first poll) or, when finishing,
                    // newer than the last report while the robot stands still.
                    Some((t, pose)) if scan.stamp < t || all => pose,
                    _ => break,
                },
            };
            let scan = self.pending.pop_front().expect("front exists");
            self.scans += 1;
            observer.event(TourEvent::Scan {
                scan: &scan,
                odometry,
                scene: None,
            });
        }
    }

    /// Collects the scan still in flight and hands over everything pending.
    fn finish<R, F>(&mut self, robot: &mut R, observer: &mut F) -> Result<(), Failure<R::Error>>
    where
        R: DriveBase + Laser,
        F: TourObserver,
    {
        if matches!(self.config.pacing, Pacing::Polling { .. }) {
            self.service(robot, self.config.poll, observer)?;
        }
        self.emit_ready(observer, true);
        Ok(())
    }
}
