//! The `twin run` job: a scenario's script, driven through the hardware contract by the robot
//! crate's tour, with the twin's ground truth recorded beside every scan.

use super::reconstruct::{SceneInput, reconstruct};
use crate::config::scenario::SonarSettings;
use crate::config::{ConfigError, Scenario};
use crate::output::ScanStream;
use crate::record::DecisionRecord;
use crate::record::{LocalisationRecord, RunRecord, ScanRecord, SonarRecord};
use crate::twin::sim_robot::{GroundTruth, SimError, SimRobot};
use robot::control::{Fix, TourConfig, TourError, TourEvent, TourObserver, run_tour};
use robot::hardware::{
    DriveBase, DriveWait, Laser, LaserScan, PanTilt, PanTiltPosition, PanTiltStatus, SonarCommand,
    SonarRing,
};
use robot::localization::{LevelLocaliser, MapConfig};
use robot::replay::Taped;

use robot::Stamp;
use std::time::{Duration, Instant};

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario cannot be set up.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The tour failed on the twin.
    #[error("{scenario}: {source}")]
    Tour {
        /// The scenario's name.
        scenario: String,
        /// What went wrong.
        #[source]
        source: TourError<SimError>,
    },
    /// The scenes' scans cannot be made into a 3D model.
    #[error("{scenario}: 3D reconstruction: {source}")]
    Reconstruction {
        /// The scenario's name.
        scenario: String,
        /// What went wrong.
        #[source]
        source: robot::reconstruction::SceneError,
    },
}

/// How a run is made.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Replaces the scenario's seed.
    pub seed: Option<u64>,
    /// Replaces the scenario's tour pacing.
    pub tour: Option<TourConfig>,
    /// Publishes the run live, paced to the wall clock.
    pub live: Option<Live>,
    /// Builds `map.pgm`'s grid, `scans.jsonl`'s lines and the tape's JSON on a thread of their
    /// own as the scans and exchanges come ([`ScanStream`]), into [`RunRecord::streamed`]: they
    /// are ready when the simulation ends (`twin run` does; runs whose files are not written
    /// need not).
    pub stream: bool,
    /// Steps rapier at every step, even where the robot glides clear of every wall: the
    /// reference the glide is tested against (the same files to the byte).
    pub physics_every_step: bool,
}

/// A run published live (`twin run --live`): its topics on a Foxglove WebSocket server, the
/// simulation held back to `speed` × real time so a viewer sees the robot move.
#[derive(Clone)]
pub struct Live {
    /// The server.
    pub server: std::sync::Arc<super::live::LiveServer>,
    /// Simulated seconds per wall-clock second.
    pub speed: f64,
    /// The twin's true pose at each scan's stamp, noted by the run as the scan comes back
    /// (the tour holds the robot meanwhile) and taken when the scan is published.
    pub truths: std::sync::Arc<std::sync::Mutex<std::collections::BTreeMap<Stamp, robot::Pose2>>>,
}

impl Live {
    /// Publishes on `server` at `speed` × real time.
    pub fn new(server: std::sync::Arc<super::live::LiveServer>, speed: f64) -> Self {
        Live {
            server,
            speed,
            truths: Default::default(),
        }
    }
}

impl std::fmt::Debug for Live {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Live({}, {}x)", self.server.addr(), self.speed)
    }
}

impl Live {
    /// Publishes one scan's topics (and the estimates placed since the last call), after
    /// waiting until the wall clock has caught up with the scan's stamp.
    fn publish(
        &self,
        started: Instant,
        scan: &robot::hardware::LaserScan,
        odometry: robot::Pose2,
        scenario: &Scenario,
        estimates: &[robot::localization::Placed],
    ) {
        use crate::output::{RecordedScan, estimate_msg, scan_topics};
        use robot::logs::ros2::Encoded;
        let due = Duration::from_secs_f64(scan.stamp.secs_f64() / self.speed);
        if let Some(wait) = due.checked_sub(started.elapsed()) {
            std::thread::sleep(wait);
        }
        let truth = {
            let mut truths = self.truths.lock().unwrap_or_else(|e| e.into_inner());
            let truth = truths.get(&scan.stamp).copied();
            // Scans come in order: what is older is of no more use.
            *truths = truths.split_off(&scan.stamp);
            truth
        };
        let recorded = RecordedScan {
            scan,
            odometry,
            truth,
            after: None,
        };
        let scan_time = crate::output::scan_period_s(&scenario.robot.laser);
        for (topic, msg) in scan_topics(&recorded, &scenario.robot.mount(), scan_time) {
            self.server.publish(topic, scan.stamp, &msg);
        }
        for p in estimates {
            self.server.publish(
                "/estimate",
                p.stamp,
                &Encoded::of(&estimate_msg(p.stamp, p.estimate)),
            );
        }
    }

    /// Announces the run's topics and publishes its static transforms (the run does it before
    /// its first step; calling it earlier lets a client subscribe before the run starts).
    pub fn announce(&self, scenario: &Scenario) {
        use crate::output::{estimate_msg, static_transforms};
        use robot::logs::ros2::Encoded;
        let statics = Encoded::of(&static_transforms(&scenario.robot.mount(), &[]));
        self.server.publish("/tf_static", Stamp::ZERO, &statics);
        let estimate = Encoded::of(&estimate_msg(Stamp::ZERO, robot::Pose2::IDENTITY));
        let empty = crate::output::no_scan();
        // `twin run --live` runs the twin: its truth is published too.
        let example = crate::output::RecordedScan {
            scan: &empty,
            odometry: robot::Pose2::IDENTITY,
            truth: Some(robot::Pose2::IDENTITY),
            after: None,
        };
        for (topic, msg) in crate::output::scan_topics(&example, &scenario.robot.mount(), 0.0) {
            self.server.advertise(topic, &msg);
        }
        if scenario.localisation.is_some() {
            self.server.advertise("/estimate", &estimate);
        }
    }
}

/// A scan the tour kept, with the odometry at its stamp and its scene.
pub type Kept = (LaserScan, robot::Pose2, Option<robot::control::SceneTag>);

/// What the controller did through the contract, on any backend: the part of a run that a
/// replay repeats.
#[derive(Debug)]
pub struct Controlled {
    /// The scans the tour kept, with the odometry at their stamp and their scene.
    pub kept: Vec<Kept>,
    /// The localisation, when the scenario asks for it.
    pub localisation: Option<LocalisationRecord>,
    /// The tour's report.
    pub report: robot::control::TourReport,
    /// The pan-tilt's status once at the scenario's position.
    pub pan_tilt: Option<PanTiltStatus>,
    /// The sonar ring's report at the end, when the scenario fires it.
    pub echoes: Option<robot::hardware::SonarEchoes>,
    /// What the navigating steps (`goto`, `explore`) decided, in order.
    pub decisions: Vec<DecisionRecord>,
}

/// The scenario's controller on `robot`: the head to its position, the sonar started, the
/// tour with the localiser fed scan by scan (and the live view, if any), the ring read at the
/// end. `ready` waits for what the backend needs before the head moves (the twin's power-up
/// homing; nothing on a replay). The same calls in the same order on every backend, so a
/// recording of them replays.
pub fn control<R>(
    robot: &mut R,
    scenario: &Scenario,
    options: &RunOptions,
    mut stream: Option<&mut ScanStream>,
    ready: impl FnOnce(&mut R) -> Result<(), R::Error>,
    mut progress: impl FnMut(usize, usize),
) -> Result<Controlled, TourError<R::Error>>
where
    R: DriveBase + Laser + PanTilt + SonarRing,
{
    let started = Instant::now();
    let pan_tilt = match scenario.pan_tilt {
        Some(target) => {
            ready(robot).map_err(|e| hardware_error("(pan-tilt)", e))?;
            Some(position_head(robot, target)?)
        }
        None => None,
    };
    if let Some(sonar) = &scenario.sonar {
        start_sonar(robot, sonar).map_err(|e| hardware_error("(sonar)", e))?;
    }
    let mut kept = Vec::new();
    let mut localiser = scenario.localisation.map(|settings| {
        let config = MapConfig {
            keyframe_distance_m: settings.keyframe_distance_m,
            keyframe_angle_rad: settings.keyframe_angle_rad,
            require_converged: !settings.use_untrusted,
            ..MapConfig::default()
        };
        LevelLocaliser::new(settings.matcher, scenario.robot.mount(), config)
    });
    if let Some(live) = &options.live {
        live.announce(scenario);
    }
    let mut localising = 0.0;
    let mut decisions = Vec::new();
    let mut gridded = 0;
    let watcher = Watcher {
        scenario,
        live: options.live.as_ref(),
        started,
        progress: &mut progress,
        localiser: localiser.as_mut(),
        localising: &mut localising,
        published_estimates: 0,
        kept: &mut kept,
        decisions: &mut decisions,
        stream: stream.as_deref_mut(),
        gridded: &mut gridded,
    };
    let report = run_tour(
        robot,
        scenario.robot.geometry(),
        scenario.world.start,
        &scenario.steps,
        options.tour.as_ref().unwrap_or(&scenario.tour),
        watcher,
    )?;
    let echoes = match &scenario.sonar {
        Some(settings) => {
            Some(read_sonar_ring(robot, settings).map_err(|e| hardware_error("(sonar)", e))?)
        }
        None => None,
    };
    progress(report.steps, report.steps);
    let localisation = localiser.map(|localiser| {
        let matcher = localiser.kind();
        let (placed, map) = localiser.finish();
        if let Some(stream) = stream {
            grid_placed(stream, &placed[gridded.min(placed.len())..], &kept);
        }
        LocalisationRecord {
            matcher,
            placed,
            map,
            wall_seconds: localising,
        }
    });
    Ok(Controlled {
        kept,
        localisation,
        report,
        pan_tilt,
        echoes,
        decisions,
    })
}

/// The scenario's observer of the tour: feeds the localiser (and the live view), keeps the
/// scans and the navigating steps' decisions, and tells those steps the localiser's fix.
struct Watcher<'a, P> {
    scenario: &'a Scenario,
    live: Option<&'a Live>,
    started: Instant,
    progress: &'a mut P,
    localiser: Option<&'a mut LevelLocaliser>,
    localising: &'a mut f64,
    published_estimates: usize,
    kept: &'a mut Vec<Kept>,
    decisions: &'a mut Vec<DecisionRecord>,
    /// The files built as the scans come, if any, and how many placed scans their grid was
    /// given.
    stream: Option<&'a mut ScanStream>,
    gridded: &'a mut usize,
}

/// Gives `stream`'s grid the scans of `placed`, each at its estimate (its scan found in `kept`
/// by its stamp): the grid of a run that localises.
fn grid_placed(stream: &mut ScanStream, placed: &[robot::localization::Placed], kept: &[Kept]) {
    for p in placed {
        if let Ok(i) = kept.binary_search_by_key(&p.stamp, |k| k.0.stamp) {
            stream.grid(&kept[i].0, p.estimate);
        }
    }
}

impl<P: FnMut(usize, usize)> TourObserver for Watcher<'_, P> {
    fn event(&mut self, event: TourEvent<'_>) {
        match event {
            TourEvent::StepStarted { index, total, .. } => (self.progress)(index, total),
            TourEvent::Scan {
                scan,
                odometry,
                scene,
            } => {
                if let Some(localiser) = &mut self.localiser {
                    let clock = Instant::now();
                    localiser.push(scan, odometry, scene);
                    *self.localising += clock.elapsed().as_secs_f64();
                }
                if let Some(live) = self.live {
                    let placed = self.localiser.as_ref().map_or(&[][..], |l| l.placed());
                    live.publish(
                        self.started,
                        scan,
                        odometry,
                        self.scenario,
                        &placed[self.published_estimates.min(placed.len())..],
                    );
                    self.published_estimates = placed.len();
                }
                self.kept.push((scan.clone(), odometry, scene));
                if let Some(stream) = self.stream.as_deref_mut() {
                    stream.kept(scan, odometry, scene);
                    match &self.localiser {
                        Some(localiser) => {
                            let placed = localiser.placed();
                            let new = &placed[(*self.gridded).min(placed.len())..];
                            grid_placed(stream, new, self.kept);
                            *self.gridded = placed.len();
                        }
                        None if scene.is_none() => stream.grid(scan, odometry),
                        None => {}
                    }
                }
            }
            TourEvent::Decision {
                stamp,
                estimate,
                odometry,
                goal,
                decision,
            } => {
                let pose = |p: robot::Pose2| [p.x, p.y, p.theta];
                self.decisions.push(DecisionRecord {
                    t: stamp.secs_f64(),
                    estimate: pose(estimate),
                    odometry: pose(odometry),
                    goal,
                    decision: *decision,
                });
            }
        }
    }

    fn fix(&self) -> Option<Fix> {
        let placed = self.localiser.as_ref()?.placed();
        let last = placed.last()?;
        Some(Fix {
            estimate: last.estimate,
            odometry: last.odometry,
            untrusted: placed.iter().rev().take_while(|p| !p.trusted).count(),
        })
    }
}

/// Runs a scenario to its end. `progress(done, total)` is called before each step.
pub fn run_scenario(
    scenario: &Scenario,
    options: &RunOptions,
    progress: impl FnMut(usize, usize),
) -> Result<RunRecord, RunError> {
    let started = Instant::now();
    let mut scenario = scenario.clone();
    if let Some(seed) = options.seed {
        scenario.seed = seed;
    }
    let mut robot = SimRobot::from_scenario(&scenario)?;
    robot.twin_mut().set_gliding(!options.physics_every_step);
    let mut taped = Taped::new(robot);
    let mut stream = options.stream.then(|| {
        let twin = taped.inner().twin();
        // The ring's transducers, when the run fires it (its reading is then recorded).
        let transducers = match (&scenario.sonar, twin.sonar()) {
            (Some(_), Some(ring)) => (0..ring.len()).filter_map(|k| ring.transducer(k)).collect(),
            _ => Vec::new(),
        };
        ScanStream::start(&scenario, std::sync::Arc::clone(twin.map()), transducers)
    });
    // The tape's exchanges to the stream, as they are noted; and for the live view, the truth
    // at each scan, noted as the scan comes back.
    let tape = stream.as_ref().map(ScanStream::tape_feed);
    let truths = options
        .live
        .as_ref()
        .map(|live| std::sync::Arc::clone(&live.truths));
    if tape.is_some() || truths.is_some() {
        taped = taped.with_hook(move |twin: &SimRobot, exchange| {
            if let Some(tape) = &tape {
                tape.exchange(exchange);
            }
            if let robot::replay::Answer::Scan { scan: Some(scan) } = &exchange.answer {
                let (truth, frame) = truth_at(twin, scan.stamp);
                if let Some(tape) = &tape {
                    tape.truth(scan.stamp, truth, frame);
                }
                if let Some(truths) = &truths {
                    truths
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .insert(scan.stamp, truth);
                }
            }
        });
    }
    let controlled = control(
        &mut taped,
        &scenario,
        options,
        stream.as_mut(),
        |r| r.inner_mut().wait_pan_tilt_ready(),
        progress,
    )
    .map_err(|source| RunError::Tour {
        scenario: scenario.name.clone(),
        source,
    })?;
    let (robot, tape) = taped.into_parts();
    let Controlled {
        kept,
        localisation,
        report,
        pan_tilt,
        echoes,
        decisions,
    } = controlled;
    let sonar = echoes.map(|echoes| {
        let model = robot
            .twin()
            .sonar()
            .expect("the scenario checked the robot has a ring");
        SonarRecord {
            truth: robot.true_pose(),
            transducers: (0..model.len())
                .filter_map(|k| model.transducer(k))
                .collect(),
            cone: model.cone(),
            echoes,
        }
    });
    // Scans are delivered after they were measured: the twin has simulated past every stamp.
    let scans: Vec<ScanRecord> = kept
        .into_iter()
        .map(|(scan, odometry, scene)| {
            let (truth, frame) = truth_at(&robot, scan.stamp);
            ScanRecord {
                scan,
                odometry,
                truth,
                frame,
                scene,
                after_exchanges: None,
            }
        })
        .collect();
    // The 3D models of the scenes, placed by the estimate, the odometry and the truth.
    let mount = scenario.robot.mount();
    let inputs: Vec<SceneInput> = scans
        .iter()
        .filter_map(|r: &ScanRecord| {
            SceneInput::of(&r.scan, r.odometry, r.scene, &mount, Some(r.truth))
        })
        .collect();
    let world_map = std::sync::Arc::clone(robot.twin().map());
    let reconstruction = reconstruct(
        &inputs,
        localisation.as_ref().map(|l| l.placed.as_slice()),
        &scenario.reconstruction.mesh,
        (!inputs.is_empty()).then_some(&*world_map),
        scenario.reconstruction.sweep,
    )
    .map_err(|source| RunError::Reconstruction {
        scenario: scenario.name.clone(),
        source,
    })?;
    let twin = robot.twin();
    let wall_seconds = started.elapsed().as_secs_f64();
    let mut record = RunRecord {
        scenario: scenario.name.clone(),
        seed: scenario.seed,
        scans,
        steps: report.steps,
        end: twin.now(),
        wall_seconds,
        distance_m: twin.distance_travelled(),
        collisions: twin.collisions(),
        stalled_motions: report.stalled,
        final_truth: twin.true_pose(),
        final_odometry: report.final_odometry,
        true_path: twin.true_path().collect(),
        battery_charge: twin.battery_charge(),
        sonar,
        pan_tilt,
        localisation,
        reconstruction,
        tape,
        decisions,
        streamed: None,
        world_map,
    };
    record.streamed = stream.map(|stream| stream.finish(&mut record, &scenario));
    Ok(record)
}

/// The twin's true pose of the base and frame of the laser at `stamp` (its pose now, for a
/// stamp it has not simulated).
fn truth_at(robot: &SimRobot, stamp: Stamp) -> (robot::Pose2, crate::devices::laser::LaserFrame) {
    let truth = robot
        .true_pose_at(stamp)
        .unwrap_or_else(|| robot.true_pose());
    let frame = robot
        .laser_frame_at(stamp)
        .unwrap_or_else(|| robot.twin().laser().frame_on(truth));
    (truth, frame)
}

/// Ticks between two status polls while the head moves.
const HEAD_POLL_MS: u16 = 50;
/// Longest a head move may take, in polls (a full pan turn takes about 8 s).
const HEAD_POLL_LIMIT: u32 = 1200;

/// Moves the head to `target` and waits until both motors are off.
fn position_head<R: PanTilt>(
    robot: &mut R,
    target: PanTiltPosition,
) -> Result<PanTiltStatus, TourError<R::Error>> {
    let status = robot
        .move_pan_tilt_to(target, HEAD_POLL_MS, HEAD_POLL_LIMIT)
        .map_err(|e| hardware_error("(pan-tilt)", e))?;
    if status.idle() {
        Ok(status)
    } else {
        Err(TourError::Stuck {
            index: 0,
            step: format!(
                "(pan-tilt) g{} / e{}: head still moving",
                target.pan, target.tilt
            ),
            timeout: crate::twin::TICK * (u32::from(HEAD_POLL_MS) * HEAD_POLL_LIMIT),
        })
    }
}

fn start_sonar<R: SonarRing>(robot: &mut R, settings: &SonarSettings) -> Result<(), R::Error> {
    robot.sonar(SonarCommand::Sequence(settings.sequence.clone()))?;
    robot.sonar(SonarCommand::Timing {
        echo_ms: settings.echo_ms,
        relax_ms: settings.relax_ms,
    })?;
    robot.sonar(SonarCommand::Firing(true))
}

/// Waits for the ring to fire its whole sequence, then reads it.
fn read_sonar_ring<R: DriveBase + SonarRing>(
    robot: &mut R,
    settings: &SonarSettings,
) -> Result<robot::hardware::SonarEchoes, R::Error> {
    // Each shot takes the fire tick, the echo window, the relax time and the step to the next.
    let cycle = settings.sequence.len() as u32
        * (u32::from(settings.echo_ms) + u32::from(settings.relax_ms) + 3);
    robot.wait_drive(DriveWait::sleep(cycle.min(u32::from(u16::MAX)) as u16))?;
    robot.sonar_echoes()
}

fn hardware_error<E: robot::hardware::HardwareError>(step: &str, source: E) -> TourError<E> {
    TourError::Hardware {
        index: 0,
        step: step.into(),
        source,
    }
}

/// `twin run`: run a scenario headless, as fast as possible, and write trajectories, scans, a
/// summary and a map picture; evaluate its checks and fail if one is out of bounds.
#[derive(Clone, Debug, clap::Args)]
pub struct RunArgs {
    /// The scenario file (e.g. scenarios/lab-tour.toml).
    pub scenario: std::path::PathBuf,
    /// Output folder [default: out/SCENARIO-NAME].
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
    /// Seed replacing the scenario's.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Publish the run live over the Foxglove WebSocket protocol on this address (e.g.
    /// 127.0.0.1:8765), paced to the wall clock × --speed.
    #[arg(long, value_name = "ADDR")]
    pub live: Option<String>,
    /// With --live: simulated seconds per wall-clock second.
    #[arg(long, default_value_t = 1.0, requires = "live")]
    pub speed: f64,
    /// Run the scenario's controller and localisation on a recording instead of the twin: the
    /// hardware contract answered from FILE's tape (a run.mcap of twin run or twin drive).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["live", "seed"])]
    pub replay: Option<std::path::PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `twin run --replay`: the controller on the recording, the outputs of a drive.
fn replay_main(
    args: &RunArgs,
    scenario: &Scenario,
    file: &std::path::Path,
) -> Result<(), super::CommandError> {
    use super::CommandError;
    let name = file.display().to_string();
    let bytes = std::fs::read(file).map_err(|source| CommandError::Read {
        path: file.to_path_buf(),
        source,
    })?;
    let tape = robot::logs::mcap::read_tape(&bytes, &name)?;
    let exchanges = tape.len();
    let bar = super::step_bar(args.quiet, scenario.steps.len());
    bar.set_prefix(format!("replay {}", scenario.name));
    let record =
        super::replay::replay_scenario(scenario, tape, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let dir = args.out.clone().unwrap_or_else(|| {
        std::path::PathBuf::from("out").join(format!("{}-replay", scenario.name))
    });
    let files = super::drive::write_drive(&record, scenario, &[], &dir)
        .map_err(CommandError::write(&dir))?;
    if !args.quiet {
        say!(
            "{}: replayed {exchanges} exchanges of {name}: {} steps, {} scans",
            record.scenario,
            record.steps,
            record.scans.len()
        );
        record.say_estimate();
        say!("wrote {}", dir.display());
        for f in &files {
            say!("  {}", f.display());
        }
    }
    Ok(())
}

/// Runs `twin run`.
pub fn main(args: RunArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    let scenario = Scenario::load(&args.scenario)?;
    if let Some(file) = &args.replay {
        return replay_main(&args, &scenario, file);
    }
    let bar = super::step_bar(args.quiet, scenario.steps.len());
    bar.set_prefix(scenario.name.clone());
    if !(args.speed > 0.0 && args.speed <= 1e6) {
        return Err(CommandError::option(
            "--speed",
            "must be above 0 and at most 1e6",
            args.speed,
        ));
    }
    let live = match &args.live {
        Some(addr) => {
            let server = super::live::LiveServer::start(addr)?;
            eprintln!(
                "live: ws://{} (Foxglove: Open connection → Foxglove WebSocket), {}x real time",
                server.addr(),
                args.speed
            );
            Some(Live::new(std::sync::Arc::new(server), args.speed))
        }
        None => None,
    };
    let options = RunOptions {
        seed: args.seed,
        live: live.clone(),
        stream: true,
        ..RunOptions::default()
    };
    let record = run_scenario(&scenario, &options, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    drop(options);
    if let Some(live) = live {
        // The queued messages go out before the connections close.
        if let Ok(server) = std::sync::Arc::try_unwrap(live.server) {
            server.stop();
        }
    }
    let dir = args
        .out
        .unwrap_or_else(|| std::path::PathBuf::from("out").join(&scenario.name));
    let written =
        crate::output::write_all(&record, &scenario, &dir).map_err(CommandError::write(&dir))?;
    if !args.quiet {
        say!(
            "{}: {:.1} s simulated in {:.3} s ({:.0}x real time), {} scans, {:.2} m driven",
            record.scenario,
            record.sim_seconds(),
            record.wall_seconds,
            record.real_time_factor(),
            record.scans.len(),
            record.distance_m
        );
        say!(
            "final odometry error {:.3} m, {:.2} deg; {} collision(s); seed {}",
            record.final_odometry_error_m(),
            record.final_odometry_error_deg(),
            record.collisions,
            record.seed
        );
        if let Some(loc) = &record.localisation {
            let (final_m, final_deg, rms_m, rms_deg) = crate::output::estimate_errors(&record, loc);
            say!(
                "estimate ({}): final error {final_m:.3} m, {final_deg:.2} deg; RMS {rms_m:.3} m, {rms_deg:.2} deg",
                loc.matcher
            );
        }
        if let Some(recon) = &record.reconstruction {
            say!(
                "{}",
                crate::output::reconstruction_report(recon).trim_end_matches('\n')
            );
        }
        say!("wrote {}", written.dir.display());
        for f in &written.files {
            say!("  {}", f.display());
        }
    }
    let report = super::check::evaluate(&scenario, &record);
    if !report.outcomes.is_empty() && (!args.quiet || !report.passed()) {
        say!("{}", report.to_string().trim_end_matches('\n'));
    }
    let failed = report.failures().count();
    // The record is large (every scan, every exchange of the tape) and the process ends here:
    // its memory goes back with the process, not piece by piece.
    std::mem::forget(record);
    if failed > 0 {
        return Err(CommandError::ChecksFailed {
            path: args.scenario,
            failed,
            total: report.outcomes.len(),
        });
    }
    Ok(())
}
