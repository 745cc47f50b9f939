//! The 3D model of a run, and `twin reconstruct`.
//!
//! The same code builds the model of a run in memory (`twin run` on the twin, `twin drive` on
//! the real robot) and of a finished run's folder (`twin reconstruct DIR`, from `scans.jsonl`,
//! `estimate.tum` and — on the twin — `truth.tum`): the scenes' scans, each put in 3D by the
//! robot crate's reconstruction, placed three ways:
//!
//! - **estimate**: where the 2D localisation of the level scans puts each station (thesis
//!   §5.3.3), when the run localised;
//! - **odometry**: where the odometry puts it;
//! - **truth**: where the twin's robot really stood (twin runs only).
//!
//! Given the world, each model is scored against the true surfaces ([`crate::world::score`]), and
//! the mesh's validity rule is swept to show what it trades.

use crate::config::WorldDescription;
use crate::output::{ReadError, ScanLine, read_scan_lines, read_tum};
use crate::record::{PlacedModel, Placement, Reconstruction, RuleTrial};
use crate::world::WorldMap;
use crate::world::score::{nearest_surfaces, phantom_area, score_with};
use robot::control::SceneTag;
use robot::hardware::LaserScan;
use robot::localization::Placed;
use robot::mount::LaserPose;
use robot::reconstruction::{
    EstimatePlacement, MeshOptions, MeshRule, Model, Scene, SceneError, SceneScan,
};
use robot::{Pose2, Stamp};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One scan of a scene, with what placing it needs.
#[derive(Clone, Debug)]
pub struct SceneInput {
    /// The scene and station it belongs to.
    pub tag: SceneTag,
    /// The scan, as the robot received it.
    pub scan: LaserScan,
    /// The laser's pose on the base at the scan's stamp (`None`: the head's angles were unknown).
    pub laser: Option<LaserPose>,
    /// The odometry at the scan's stamp.
    pub odometry: Pose2,
    /// The true pose of the base at the scan's stamp, on the twin.
    pub truth: Option<Pose2>,
}

impl SceneInput {
    /// A tour's scan as a scene's input, if it was taken for a scene: its laser pose on the
    /// base from `mount` and the head's angles it carries.
    pub fn of(
        scan: &LaserScan,
        odometry: Pose2,
        scene: Option<SceneTag>,
        mount: &robot::mount::LaserMount,
        truth: Option<Pose2>,
    ) -> Option<SceneInput> {
        Some(SceneInput {
            tag: scene?,
            scan: scan.clone(),
            laser: mount.laser_on_base(scan.head),
            odometry,
            truth,
        })
    }
}

/// The rules the sweep tries: the thesis's rule from 50 to 400 mm, and the proposed rule at
/// several steepest incidences.
pub fn sweep_rules() -> Vec<MeshRule> {
    let mut rules: Vec<MeshRule> = (1..=8)
        .map(|k| MeshRule::thesis_with_max(0.05 * k as f32))
        .collect();
    rules.extend([70.0, 75.0, 80.0, 85.0].map(|deg| MeshRule::Incidence {
        max_incidence_deg: deg,
        noise_m: 0.03,
        max_edge_m: 1.0,
    }));
    rules
}

/// Builds and scores the 3D models of the scene scans `inputs` (in the order taken); `placed`
/// are the level scans the localisation placed, `world` the truth to score against, `sweep`
/// whether to try the other validity rules too. `None` when no scan belongs to a scene.
pub fn reconstruct(
    inputs: &[SceneInput],
    placed: Option<&[Placed]>,
    options: &MeshOptions,
    world: Option<&WorldMap>,
    sweep: bool,
) -> Result<Option<Reconstruction>, SceneError> {
    if inputs.is_empty() {
        return Ok(None);
    }
    let started = Instant::now();
    let estimate = placed.filter(|p| !p.is_empty()).map(EstimatePlacement::new);
    let mut placements = Vec::new();
    if estimate.is_some() {
        placements.push(Placement::Estimate);
    }
    placements.push(Placement::Odometry);
    if inputs.iter().all(|i| i.truth.is_some()) {
        placements.push(Placement::Truth);
    }
    let mut scenes_by = Vec::new();
    for &placement in &placements {
        let rows: Vec<(SceneTag, SceneScan<'_>)> = inputs
            .iter()
            .map(|i| {
                let base = match placement {
                    Placement::Estimate => estimate
                        .and_then(|e| e.at(i.scan.stamp, i.odometry))
                        .unwrap_or(i.odometry),
                    Placement::Odometry => i.odometry,
                    Placement::Truth => i.truth.unwrap_or(i.odometry),
                };
                (
                    i.tag,
                    SceneScan {
                        scan: &i.scan,
                        base,
                        laser: i.laser,
                    },
                )
            })
            .collect();
        scenes_by.push((placement, Scene::group(&rows)?));
    }
    let models: Vec<PlacedModel> = scenes_by
        .iter()
        .map(|(placement, scenes)| PlacedModel {
            placement: *placement,
            model: Model::build(scenes, options),
            accuracy: None,
        })
        .collect();
    let build_seconds = started.elapsed().as_secs_f64();
    let mut recon = Reconstruction {
        options: *options,
        models,
        sweep: Vec::new(),
        build_seconds,
        score_seconds: 0.0,
    };
    if let Some(map) = world {
        let started = Instant::now();
        for placed in &mut recon.models {
            let nearest = nearest_surfaces(&placed.model, map);
            placed.accuracy = Some(score_with(&placed.model, map, &nearest));
            let best = if placements.contains(&Placement::Truth) {
                Placement::Truth
            } else {
                Placement::Estimate
            };
            if sweep && placed.placement == best {
                let scenes = &scenes_by
                    .iter()
                    .find(|(p, _)| *p == best)
                    .expect("every placement has its scenes")
                    .1;
                recon.sweep = sweep_rules()
                    .iter()
                    .map(|rule| {
                        let trial_options = MeshOptions {
                            rule: *rule,
                            ..*options
                        };
                        let model = Model::build(scenes, &trial_options);
                        let (_, (valid, of)) = model.counts();
                        let area = phantom_area(&model, map, &nearest);
                        RuleTrial {
                            rule: rule.to_string(),
                            valid_share: valid as f64 / of.max(1) as f64,
                            mesh_area_m2: area.mesh_m2,
                            phantom_area_m2: area.phantom_m2,
                            bridge_area_m2: area.bridge_m2,
                            true_area_m2: area.mesh_m2 - area.phantom_m2,
                        }
                    })
                    .collect();
            }
        }
        recon.score_seconds = started.elapsed().as_secs_f64();
    }
    Ok(Some(recon))
}

/// Why a run's folder cannot be reconstructed.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// A file of the folder cannot be read or is malformed.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The folder holds no scan of a 3D scene.
    #[error(
        "{}: no scan of a 3D scene in scans.jsonl (a run whose script has `scene` or `survey` steps writes them)",
        .0.display()
    )]
    NoScenes(PathBuf),
    /// The scenes cannot be built.
    #[error("{}: {source}", path.display())]
    Scene {
        /// The scans file.
        path: PathBuf,
        /// Why.
        #[source]
        source: SceneError,
    },
}

/// What a run's folder holds for its reconstruction.
#[derive(Clone, Debug)]
pub struct RunFolder {
    /// The scene scans, in order.
    pub inputs: Vec<SceneInput>,
    /// The level scans as the localisation placed them (from `estimate.tum`), if it localised.
    pub placed: Option<Vec<Placed>>,
}

/// Reads `scans.jsonl`, and `estimate.tum` and `truth.tum` where present, from a run's folder.
pub fn read_run_folder(dir: &Path) -> Result<RunFolder, FolderError> {
    let scans_path = dir.join("scans.jsonl");
    let lines = read_scan_lines(&scans_path)?;
    let optional_tum = |name: &str| -> Result<Option<Vec<(Stamp, Pose2)>>, FolderError> {
        let path = dir.join(name);
        if path.exists() {
            Ok(Some(read_tum(&path)?))
        } else {
            Ok(None)
        }
    };
    let estimate = optional_tum("estimate.tum")?;
    let truth = optional_tum("truth.tum")?;
    let stamp = |line: &ScanLine| Stamp((line.t * 1e9).round() as u64);
    let odometry =
        |line: &ScanLine| Pose2::new(line.odometry[0], line.odometry[1], line.odometry[2]);
    // The estimate's rows are the level scans': their odometry is on the scans' lines.
    let placed = estimate.map(|rows| {
        rows.iter()
            .filter_map(|&(t, estimate)| {
                let i = lines.partition_point(|l| stamp(l) < t);
                let line = lines.get(i).filter(|l| stamp(l) == t)?;
                Some(Placed {
                    stamp: t,
                    estimate,
                    odometry: odometry(line),
                    matched: None,
                    reference: None,
                    trusted: true,
                    held_across: false,
                    mount: line
                        .laser_mount
                        .map_or(Pose2::IDENTITY, |[x, y, theta]| Pose2::new(x, y, theta)),
                })
            })
            .collect::<Vec<_>>()
    });
    let true_at = |t: Stamp| {
        truth.as_ref().and_then(|rows| {
            let i = rows.partition_point(|(s, _)| *s < t);
            rows.get(i).filter(|(s, _)| *s == t).map(|(_, p)| *p)
        })
    };
    let inputs: Vec<SceneInput> = lines
        .iter()
        .filter_map(|line| {
            let tag = SceneTag {
                scene: line.scene?,
                station: line.station.unwrap_or(0),
            };
            let laser = match (line.laser_mount, line.laser_z, line.laser_tilt) {
                (Some(m), Some(z), Some(tilt)) => Some(LaserPose::from_planar(
                    Pose2::new(m[0], m[1], m[2]),
                    z,
                    tilt,
                )),
                _ => None,
            };
            let t = stamp(line);
            Some(SceneInput {
                tag,
                scan: line.to_scan(t),
                laser,
                odometry: odometry(line),
                truth: true_at(t),
            })
        })
        .collect();
    if inputs.is_empty() {
        return Err(FolderError::NoScenes(scans_path));
    }
    Ok(RunFolder { inputs, placed })
}

/// `twin reconstruct`: rebuild the 3D model of a finished run from its output folder
/// (`scans.jsonl` and the poses) — a twin run's or a real robot's drive — write the model as
/// PLY, its figures and its picture; with the world, score it against the truth.
#[derive(Clone, Debug, clap::Args)]
pub struct ReconstructArgs {
    /// The run's output folder (e.g. out/survey-lab).
    pub dir: PathBuf,
    /// The world file the run took place in: score the model against its surfaces.
    #[arg(long)]
    pub world: Option<PathBuf>,
    /// The mesh's validity rule: thesis ([5 mm, --max-mm]) or incidence (the proposed rule).
    #[arg(long, default_value = "thesis")]
    pub rule: RuleName,
    /// The thesis rule's longest distance, millimetres.
    #[arg(long, default_value_t = 200.0)]
    pub max_mm: f64,
    /// Beams left out at each end of every scan (App. D.2's `epuntos`).
    #[arg(long, default_value_t = 0)]
    pub trim: usize,
    /// Also try the validity rules of the sweep (the thesis's from 50 to 400 mm, the incidence
    /// rule at 70–85°) and report what each trades (needs --world).
    #[arg(long)]
    pub sweep: bool,
    /// Where to write [default: the run's folder].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The validity rules a command line can name.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum RuleName {
    /// App. D's: every distance from the first vertex within [5 mm, --max-mm].
    Thesis,
    /// The proposed rule: no edge running along the beams (surfaces up to 80° from head-on).
    Incidence,
}

impl ReconstructArgs {
    /// The meshing options the arguments ask for.
    pub fn options(&self) -> Result<MeshOptions, super::CommandError> {
        if !(self.max_mm.is_finite() && self.max_mm >= 5.0 && self.max_mm <= 10_000.0) {
            return Err(super::CommandError::option(
                "--max-mm",
                "must be between 5 and 10000 millimetres",
                self.max_mm,
            ));
        }
        if self.trim > 180 {
            return Err(super::CommandError::option(
                "--trim",
                "must be at most 180 beams",
                self.trim,
            ));
        }
        Ok(MeshOptions {
            rule: match self.rule {
                RuleName::Thesis => MeshRule::thesis_with_max((self.max_mm * 1e-3) as f32),
                RuleName::Incidence => MeshRule::INCIDENCE,
            },
            trim_beams: self.trim,
        })
    }
}

/// Runs `twin reconstruct`.
pub fn main(args: ReconstructArgs) -> Result<(), super::CommandError> {
    use super::CommandError;
    let options = args.options()?;
    if args.sweep && args.world.is_none() {
        return Err(CommandError::option(
            "--sweep",
            "needs --world (the phantom area is measured against the true surfaces)",
            "no world",
        ));
    }
    let world = match &args.world {
        Some(path) => Some(WorldDescription::load(path)?),
        None => None,
    };
    let folder = read_run_folder(&args.dir)?;
    let map = world.as_ref().map(WorldMap::new);
    let recon = reconstruct(
        &folder.inputs,
        folder.placed.as_deref(),
        &options,
        map.as_ref(),
        args.sweep,
    )
    .map_err(|source| FolderError::Scene {
        path: args.dir.join("scans.jsonl"),
        source,
    })?
    .ok_or_else(|| FolderError::NoScenes(args.dir.join("scans.jsonl")))?;
    let out = args.out.clone().unwrap_or_else(|| args.dir.clone());
    let title = args
        .dir
        .file_name()
        .map_or("run".into(), |n| n.to_string_lossy().into_owned());
    let files = crate::output::write_reconstruction(&out, &recon, &title, map.as_ref()).map_err(
        |source| CommandError::Write {
            dir: out.clone(),
            source,
        },
    )?;
    if !args.quiet {
        say!(
            "{}",
            crate::output::reconstruction_report(&recon).trim_end_matches('\n')
        );
        say!("wrote {}", out.display());
        for f in &files {
            say!("  {}", f.display());
        }
    }
    Ok(())
}
