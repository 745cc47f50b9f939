//! Scenario files: a world, a robot, a seed, noise settings and a command script.
//!
//! ```toml
//! name = "lab-tour"
//! world = "../worlds/lab.toml"          # paths are relative to this file
//! robot = "robots/pioneer-3dx.toml"
//! seed = 2007
//!
//! [noise]                               # every key optional
//! slip_sigma_sqrt_m = 0.003             # per-wheel slip: σ of 3 mm after 1 m of travel
//! wheel_diameter_ratio_error = 0.004    # true D_right / D_left − 1 (Borenstein's E_d − 1)
//! wheel_scale_error = 0.002             # true mean diameter / nominal − 1
//! track_error = 0.01                    # true track / nominal − 1
//! laser_sigma_m = 0.01                  # overrides the robot's laser σ
//! outliers = "thesis-2pct"              # none, thesis-2pct, thesis-20pct, indoor, or a table
//!                                       # { uniform = 0.02, short = 0.0, dropout = 0.01 }
//!
//! [script]
//! repeat = 2                            # run the steps this many times
//! steps = ["k5 30 50", "move 0.5", "turn 25", "a535", "pause 1"]
//!
//! [sonar]                               # optional: fire the sonar ring during the run
//! fire = true                           # `s1` before the script; one ring reading at the end
//! sequence = [0, 1, 2, 3]               # `S`: firing order (default all 16, 0 first)
//! echo_ms = 50                          # `s2 Te Tr`: echo window and relax time
//! relax_ms = 20
//!
//! [pan_tilt]                            # optional, robots with a pan-tilt: where the head goes
//! pan = 0                               # before the script (`g`, `e`; default pan 0, the
//! tilt = 20                             # robot's level tilt position)
//!
//! [tour]                                # optional; how the controller paces itself
//! pacing = "stop-and-go"                # or "polling" (see robot::control::tour)
//! settle_s = 0.1                        # stop-and-go: wait after the motors stop
//! poll_s = 0.05                         # polling: longest wait for a scan between polls
//!
//! [navigation]                          # optional: how `goto X Y` and `explore S` steps drive
//! margin_m = 0.12                       # clearance kept from anything seen
//! step_m = 0.6                          # longest move before looking again
//! tolerance_m = 0.15                    # a goal is reached within this
//! wall_distance_m = 0.45                # explore: the wall kept on the right this far
//! use_sonar = true                      # hear the ring's echoes too (when [sonar] fires it)
//! method = "histogram"                  # or "direct": the baseline with no way round
//!
//! [localisation]                        # optional: chain the scans into a map while running
//! matcher = "lorentz"                   # ls, lorentz, lorentz-lines, mbicp or pl-icp
//! keyframe_distance_m = 0.0             # match each scan to the last one moved this far from
//! keyframe_angle_deg = 0.0              # (0: to the previous scan, as the thesis does)
//! use_untrusted = false                 # true: use every match, even one not flagged converged
//! ```

use super::checks::{Check, CheckFile, parse_checks};
use super::error::{ConfigError, Source, resolve};
use super::robot_file::RobotDescription;
use super::values::{
    NonNegative, Positive, RelativeError, Seconds, SecondsOrZero, Sigma, UnitInterval,
};
use super::world::{StartFile, WorldDescription};
use crate::config::Outliers;
use core::time::Duration;
use robot::control::{NavConfig, Pacing, SonarLayout, Step, TourConfig};
use robot::localization::UnknownMatcher;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// How far the twin departs from the robot's nominal description.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct NoiseSettings {
    /// Per-wheel random slip: each wheel's ground travel gets Gaussian noise of variance
    /// `σ² · |travel|`, so after 1 m the standard deviation is σ metres. Units: √m.
    pub slip_sigma_sqrt_m: f64,
    /// True ratio of right to left wheel diameter, minus one (Borenstein's `E_d − 1`).
    pub wheel_diameter_ratio_error: f64,
    /// True mean wheel diameter over the nominal one, minus one.
    pub wheel_scale_error: f64,
    /// True track over the nominal one, minus one (Borenstein's `E_b − 1`).
    pub track_error: f64,
    /// Standard deviation of the laser's range noise, metres.
    pub laser_sigma_m: f64,
    /// Random laser outliers.
    pub outliers: Outliers,
}

impl NoiseSettings {
    /// No slip, no mismatch, no range noise: the twin does exactly what the description says.
    pub const NONE: NoiseSettings = NoiseSettings {
        slip_sigma_sqrt_m: 0.0,
        wheel_diameter_ratio_error: 0.0,
        wheel_scale_error: 0.0,
        track_error: 0.0,
        laser_sigma_m: 0.0,
        outliers: Outliers::NONE,
    };

    /// The defaults of a scenario without a `[noise]` table: 3 mm/√m of slip per wheel (a
    /// heading random walk of about 0.7°/√m on a Pioneer), no mismatch, and the robot's own
    /// laser noise.
    pub fn defaults_for(robot: &RobotDescription) -> Self {
        NoiseSettings {
            slip_sigma_sqrt_m: 0.003,
            laser_sigma_m: robot.laser.sigma_m.get(),
            ..NoiseSettings::NONE
        }
    }
}

/// How a scenario fires the sonar ring.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SonarSettings {
    /// The firing sequence (`S`).
    pub sequence: Vec<u8>,
    /// Echo window after each shot, ms (`s2 Te`).
    pub echo_ms: u16,
    /// Pause before the next shot, ms (`s2 Tr`).
    pub relax_ms: u16,
}

impl SonarSettings {
    /// Time for the ring to fire its whole sequence: each shot takes the fire tick, the echo
    /// window, the relax time and the step to the next.
    pub fn cycle(&self) -> Duration {
        let ms =
            self.sequence.len() as u64 * (u64::from(self.echo_ms) + u64::from(self.relax_ms) + 3);
        Duration::from_millis(ms)
    }
}

/// Localisation during a run: which matcher chains the scans into a map (`[localisation]`).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LocalisationSettings {
    /// The matcher.
    pub matcher: robot::localization::MatcherKind,
    /// A scan becomes the next reference after this much travel, metres (0: every scan).
    pub keyframe_distance_m: f64,
    /// … or this much turn, radians (0: every scan).
    pub keyframe_angle_rad: f64,
    /// Use every match, as the thesis did, even one whose quality is not trusted (by default
    /// such a match falls back to odometry and is counted).
    pub use_untrusted: bool,
}

/// How a run's 3D scenes are meshed and scored (`[reconstruction]`).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct ReconstructionSettings {
    /// The mesh's validity rule and trimming.
    pub mesh: robot::reconstruction::MeshOptions,
    /// Also try the validity rules of the sweep (50…400 mm, the incidence rule) and report
    /// what each trades in `reconstruction.json`.
    pub sweep: bool,
}

/// A validated scenario with its world and robot loaded.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Short name (used for the default output folder).
    pub name: String,
    /// What the scenario shows.
    pub description: String,
    /// The world.
    pub world: WorldDescription,
    /// The robot.
    pub robot: RobotDescription,
    /// Master seed; every random stream of the twin derives from it.
    pub seed: u64,
    /// Noise and mismatch.
    pub noise: NoiseSettings,
    /// The script, with its repeats expanded.
    pub steps: Vec<Step>,
    /// How the controller paces the script.
    pub tour: TourConfig,
    /// Whether and how the sonar ring fires.
    pub sonar: Option<SonarSettings>,
    /// Where the pan-tilt head goes before the script, on a robot with a pan-tilt.
    pub pan_tilt: Option<robot::hardware::PanTiltPosition>,
    /// The scan matcher the run localises with, if any.
    pub localisation: Option<LocalisationSettings>,
    /// How the 3D scenes of `scene` and `survey` steps are meshed and scored
    /// (`[reconstruction]`).
    pub reconstruction: ReconstructionSettings,
    /// What the run must show (`[[check]]`).
    pub checks: Vec<Check>,
    /// The file it was read from.
    pub path: PathBuf,
}

impl Scenario {
    /// Reads a scenario and the world and robot it names.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        let source = Source::read(path.as_ref())?;
        let file: ScenarioFile = source.parse()?;
        let mut world = load_named(&source, &file.world, "world", |p| WorldDescription::load(p))?;
        if let Some(start) = &file.start {
            // Put the robot elsewhere in the same world, by the world's own rule; the twin
            // checks it is clear of walls.
            world.start = world
                .check_start(start)
                .map_err(|message| source.error_in_file(Some("start".into()), message))?;
        }
        let robot = load_named(&source, &file.robot, "robot", |p| RobotDescription::load(p))?;
        let mut noise = NoiseSettings::defaults_for(&robot);
        if let Some(n) = &file.noise {
            n.apply(&mut noise, &source)?;
        }
        let mut once = Vec::with_capacity(file.script.steps.len());
        for (i, text) in file.script.steps.iter().enumerate() {
            let step = text
                .get_ref()
                .parse::<Step>()
                .and_then(|step| step.to_line(&robot.geometry()).map(|_| step))
                .map_err(|e| e.to_string())
                .and_then(|step| {
                    if step.uses_head() && robot.pan_tilt.is_none() {
                        Err(format!(
                            "the robot `{}` has no pan-tilt unit for `{step}`",
                            robot.name
                        ))
                    } else {
                        Ok(step)
                    }
                })
                .map_err(|e| source.error(text.span(), Some(format!("script.steps[{i}]")), e))?;
            once.push(step);
        }
        let repeat = *file.script.repeat.get_ref();
        if !(1..=10_000).contains(&repeat) {
            return Err(source.error(
                file.script.repeat.span(),
                Some("script.repeat".into()),
                format!("expected 1..=10000 repetitions, found {repeat}"),
            ));
        }
        let steps: Vec<Step> = (0..repeat).flat_map(|_| once.iter().copied()).collect();
        let mut tour = TourConfig::default();
        if let Some(t) = &file.tour {
            let poll = Duration::from_secs_f64(t.poll_s.map_or(0.05, Seconds::get));
            tour.poll = poll;
            tour.pacing = match t.pacing.as_ref().map(|p| p.get_ref().as_str()) {
                None | Some("stop-and-go") => Pacing::StopAndGo {
                    settle: Duration::from_secs_f64(t.settle_s.map_or(0.1, SecondsOrZero::get)),
                },
                Some("polling") => Pacing::Polling { period: poll },
                Some(other) => {
                    let span = t.pacing.as_ref().map_or(0..0, |p| p.span());
                    return Err(source.error(
                        span,
                        Some("tour.pacing".into()),
                        format!(
                            "unknown pacing {other:?}: expected \"stop-and-go\" or \"polling\""
                        ),
                    ));
                }
            };
        }
        let sonar = match &file.sonar {
            Some(f) if f.fire => {
                if robot.sonar.is_none() {
                    return Err(source.error_in_file(
                        Some("sonar.fire".into()),
                        format!("the robot `{}` has no sonar ring", robot.name),
                    ));
                }
                let settings = SonarSettings {
                    sequence: f.sequence.clone().unwrap_or_else(|| (0..16).collect()),
                    echo_ms: f.echo_ms.unwrap_or(50),
                    relax_ms: f.relax_ms.unwrap_or(20),
                };
                let check = [
                    robot::hardware::SonarCommand::Sequence(settings.sequence.clone()),
                    robot::hardware::SonarCommand::Timing {
                        echo_ms: settings.echo_ms,
                        relax_ms: settings.relax_ms,
                    },
                ];
                for command in check {
                    command
                        .validate()
                        .map_err(|e| source.error_in_file(Some("sonar".into()), e.to_string()))?;
                }
                Some(settings)
            }
            _ => None,
        };
        tour.navigation = navigation(&robot, sonar.as_ref(), file.navigation.as_ref());
        if let Some(method) = file.navigation.as_ref().and_then(|n| n.method.as_ref()) {
            tour.navigation.method = method.get_ref().parse().map_err(|e: String| {
                source.error(method.span(), Some("navigation.method".into()), e)
            })?;
        }
        let pan_tilt = match (&robot.pan_tilt, &file.pan_tilt) {
            (None, None) => None,
            (None, Some(_)) => {
                return Err(source.error_in_file(
                    Some("pan_tilt".into()),
                    format!("the robot `{}` has no pan-tilt unit", robot.name),
                ));
            }
            (Some(unit), f) => {
                let pan = f.as_ref().and_then(|f| f.pan).unwrap_or(0);
                let tilt = f
                    .as_ref()
                    .and_then(|f| f.tilt)
                    .unwrap_or(unit.level_position);
                for (field, value, max) in [
                    ("pan_tilt.pan", pan, robot::hardware::PAN_MAX),
                    ("pan_tilt.tilt", tilt, robot::hardware::TILT_MAX),
                ] {
                    if value > u16::from(max) {
                        return Err(source.error_in_file(
                            Some(field.into()),
                            format!("expected a position 0..={max}, found {value}"),
                        ));
                    }
                }
                let position = robot::hardware::PanTiltPosition {
                    pan: pan as u8,
                    tilt: tilt as u8,
                };
                Some(position)
            }
        };
        let localisation = match &file.localisation {
            None => None,
            Some(l) => Some(LocalisationSettings {
                matcher: l.matcher.get_ref().parse().map_err(|e: UnknownMatcher| {
                    source.error(
                        l.matcher.span(),
                        Some("localisation.matcher".into()),
                        e.to_string(),
                    )
                })?,
                keyframe_distance_m: l.keyframe_distance_m.map_or(0.0, NonNegative::get),
                keyframe_angle_rad: l.keyframe_angle_deg.map_or(0.0, |a| a.get().to_radians()),
                use_untrusted: l.use_untrusted.unwrap_or(false),
            }),
        };
        let reconstruction = match &file.reconstruction {
            None => ReconstructionSettings::default(),
            Some(r) => {
                let invalid = |field: &str, message: String| {
                    source.error_in_file(Some(format!("reconstruction.{field}")), message)
                };
                let max_mm = r.max_mm.map_or(200.0, Positive::get);
                if !(5.0..=10_000.0).contains(&max_mm) {
                    return Err(invalid(
                        "max_mm",
                        format!("expected 5 to 10000 millimetres, found {max_mm}"),
                    ));
                }
                let rule = match r.rule.as_deref().unwrap_or("thesis") {
                    "thesis" => {
                        robot::reconstruction::MeshRule::thesis_with_max((max_mm * 1e-3) as f32)
                    }
                    "incidence" if r.max_mm.is_none() => robot::reconstruction::MeshRule::INCIDENCE,
                    "incidence" => {
                        return Err(invalid(
                            "max_mm",
                            "only the thesis rule takes max_mm".into(),
                        ));
                    }
                    other => {
                        return Err(invalid(
                            "rule",
                            format!("unknown rule {other:?}: expected \"thesis\" or \"incidence\""),
                        ));
                    }
                };
                let trim_beams = r.trim_beams.unwrap_or(0);
                if trim_beams > 180 {
                    return Err(invalid(
                        "trim_beams",
                        format!("expected at most 180 beams, found {trim_beams}"),
                    ));
                }
                ReconstructionSettings {
                    mesh: robot::reconstruction::MeshOptions {
                        rule,
                        trim_beams: usize::from(trim_beams),
                    },
                    sweep: r.sweep.unwrap_or(false),
                }
            }
        };
        let checks = parse_checks(
            &file.check,
            &source,
            localisation.is_some(),
            sonar.is_some(),
            steps
                .iter()
                .any(|s| matches!(s, Step::Scene { .. } | Step::Survey { .. })),
            (
                steps.iter().any(|s| matches!(s, Step::Goto { .. })),
                steps
                    .iter()
                    .any(|s| matches!(s, Step::Goto { .. } | Step::Explore { .. })),
            ),
        )?;
        Ok(Scenario {
            name: file.name,
            description: file.description,
            world,
            robot,
            seed: file.seed,
            noise,
            steps,
            tour,
            sonar,
            checks,
            pan_tilt,
            localisation,
            reconstruction,
            path: source.path.clone(),
        })
    }
}

/// Loads the file a scenario names; an unreadable file is reported at the scenario's line.
pub(crate) fn load_named<T>(
    source: &Source,
    name: &Spanned<String>,
    field: &str,
    load: impl Fn(&Path) -> Result<T, ConfigError>,
) -> Result<T, ConfigError> {
    let path = resolve(&source.path, name.get_ref());
    load(&path).map_err(|e| {
        if e.line.is_none() && e.path == path {
            source.error(
                name.span(),
                Some(field.into()),
                format!("{}: {}", path.display(), e.message),
            )
        } else {
            e
        }
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: String,
    #[serde(default)]
    description: String,
    world: Spanned<String>,
    start: Option<StartFile>,
    robot: Spanned<String>,
    seed: u64,
    noise: Option<NoiseFile>,
    script: ScriptFile,
    tour: Option<TourFile>,
    sonar: Option<SonarFile>,
    pan_tilt: Option<PanTiltFile>,
    localisation: Option<LocalisationFile>,
    navigation: Option<NavigationFile>,
    reconstruction: Option<ReconstructionFile>,
    #[serde(default)]
    check: Vec<Spanned<CheckFile>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NavigationFile {
    margin_m: Option<NonNegative>,
    step_m: Option<Positive>,
    tolerance_m: Option<Positive>,
    wall_distance_m: Option<Positive>,
    use_sonar: Option<bool>,
    method: Option<Spanned<String>>,
}

/// How the robot's `goto` and `explore` steps drive: its footprint, its laser's mount, the ring
/// when the scenario fires it, and the scenario's `[navigation]` table.
fn navigation(
    robot: &RobotDescription,
    sonar: Option<&SonarSettings>,
    file: Option<&NavigationFile>,
) -> NavConfig {
    let body = &robot.body;
    let mut config = NavConfig::new(body.radius_m.get(), body.center_x_m.get(), robot.mount());
    let use_sonar = file.and_then(|f| f.use_sonar).unwrap_or(true);
    config.sonar = match (&robot.sonar, sonar) {
        (Some(ring), Some(settings)) if use_sonar => Some(SonarLayout {
            count: ring.count,
            ring_radius_m: ring.ring_radius_m.get(),
            center_x_m: ring.center_x_m.get(),
            cone_rad: ring.cone_deg.get().to_radians(),
            speed_of_sound: robot::hardware::SPEED_OF_SOUND,
            max_range_m: 5.0f64.min(ring.max_range_m.get()),
            cycle: settings.cycle(),
        }),
        _ => None,
    };
    if let Some(f) = file {
        if let Some(v) = f.margin_m {
            config.margin_m = v.get();
        }
        if let Some(v) = f.step_m {
            config.step_m = v.get();
        }
        if let Some(v) = f.tolerance_m {
            config.tolerance_m = v.get();
        }
        if let Some(v) = f.wall_distance_m {
            config.wall_distance_m = v.get();
        }
    }
    config
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LocalisationFile {
    matcher: Spanned<String>,
    keyframe_distance_m: Option<NonNegative>,
    keyframe_angle_deg: Option<NonNegative>,
    use_untrusted: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReconstructionFile {
    rule: Option<String>,
    max_mm: Option<Positive>,
    trim_beams: Option<u16>,
    sweep: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PanTiltFile {
    pan: Option<u16>,
    tilt: Option<u16>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SonarFile {
    fire: bool,
    sequence: Option<Vec<u8>>,
    echo_ms: Option<u16>,
    relax_ms: Option<u16>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TourFile {
    pacing: Option<Spanned<String>>,
    settle_s: Option<SecondsOrZero>,
    poll_s: Option<Seconds>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct NoiseFile {
    slip_sigma_sqrt_m: Option<Sigma>,
    wheel_diameter_ratio_error: Option<RelativeError>,
    wheel_scale_error: Option<RelativeError>,
    track_error: Option<RelativeError>,
    laser_sigma_m: Option<Sigma>,
    outliers: Option<Spanned<OutliersFile>>,
}

impl NoiseFile {
    /// Overrides the settings this table names.
    pub(crate) fn apply(
        &self,
        noise: &mut NoiseSettings,
        source: &Source,
    ) -> Result<(), ConfigError> {
        let set = |target: &mut f64, value: Option<f64>| {
            if let Some(v) = value {
                *target = v;
            }
        };
        set(
            &mut noise.slip_sigma_sqrt_m,
            self.slip_sigma_sqrt_m.map(Sigma::get),
        );
        set(
            &mut noise.wheel_diameter_ratio_error,
            self.wheel_diameter_ratio_error.map(RelativeError::get),
        );
        set(
            &mut noise.wheel_scale_error,
            self.wheel_scale_error.map(RelativeError::get),
        );
        set(
            &mut noise.track_error,
            self.track_error.map(RelativeError::get),
        );
        set(&mut noise.laser_sigma_m, self.laser_sigma_m.map(Sigma::get));
        let Some(o) = &self.outliers else {
            return Ok(());
        };
        let invalid =
            |message: String| source.error(o.span(), Some("noise.outliers".into()), message);
        noise.outliers = match o.get_ref() {
            OutliersFile::Preset(name) => Outliers::preset(name).ok_or_else(|| {
                let names: Vec<&str> = Outliers::PRESETS.iter().map(|(n, _)| *n).collect();
                invalid(format!(
                    "unknown outlier preset {name:?}: expected one of {}, or a table {{ uniform, short, dropout }}",
                    names.join(", ")
                ))
            })?,
            OutliersFile::Rates { uniform, short, dropout } => {
                let rates = Outliers {
                    uniform: uniform.map_or(0.0, UnitInterval::get),
                    short: short.map_or(0.0, UnitInterval::get),
                    dropout: dropout.map_or(0.0, UnitInterval::get),
                };
                if rates.uniform + rates.short + rates.dropout > 1.0 {
                    return Err(invalid("the outlier rates add up to more than 1".into()));
                }
                rates
            }
        };
        Ok(())
    }
}

#[derive(Deserialize)]
#[serde(untagged)]
enum OutliersFile {
    Preset(String),
    Rates {
        uniform: Option<UnitInterval>,
        short: Option<UnitInterval>,
        dropout: Option<UnitInterval>,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScriptFile {
    #[serde(default = "once")]
    repeat: Spanned<u32>,
    steps: Vec<Spanned<String>>,
}

fn once() -> Spanned<u32> {
    Spanned::new(0..0, 1)
}
