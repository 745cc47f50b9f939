//! The files of a 3D reconstruction: the model as PLY, its figures as `reconstruction.json`, its
//! picture as `model.png`, and a short report for the terminal.

use super::ply::write_ply;
use super::render::{Picture, write_model_png};
use crate::record::{Placement, Reconstruction, RuleTrial};
use crate::world::WorldMap;
use crate::world::score::Accuracy;
use robot::reconstruction::{MeshRule, Model, SceneStats};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The thesis's counts for its one scene of the LIC (§5.3.1): valid and possible.
pub const THESIS_TRIANGLES: (usize, usize) = (59_924, 71_280);
/// The thesis's quadrilaterals.
pub const THESIS_QUADS: (usize, usize) = (29_785, 35_640);

/// `reconstruction.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ReconstructionFile {
    /// How the scenes were meshed.
    pub rule: String,
    /// Beams left out at each end of every scan.
    pub trim_beams: usize,
    /// The model in `model.ply`: placed by `estimate` if the run localised, else `odometry`.
    pub main_placement: Placement,
    /// Each scene of the main model.
    pub scenes: Vec<SceneFile>,
    /// Valid quadrilaterals and triangles over all scenes, with how many the grids offer.
    pub totals: Totals,
    /// The thesis's one scene (§5.3.1), for comparison.
    pub thesis: Totals,
    /// The accuracy of each model against the truth, when the world was known.
    pub accuracy: Vec<PlacementAccuracy>,
    /// The validity rule swept on the best-placed model, when the world was known.
    pub rule_sweep: Vec<RuleTrial>,
}

/// One scene's figures.
#[derive(Clone, Debug, Serialize)]
pub struct SceneFile {
    /// The scene's number.
    pub scene: usize,
    /// Its station.
    pub station: usize,
    /// The head's pan, degrees.
    pub pan_deg: f64,
    /// Where the base was placed, `[x, y, theta]`.
    pub base: [f64; 3],
    /// Scans in the scene.
    pub scans: usize,
    /// Readings that returned.
    pub points: usize,
    /// Valid quadrilaterals and possible.
    pub quads: (usize, usize),
    /// Valid triangles and possible.
    pub triangles: (usize, usize),
}

impl SceneFile {
    fn of(s: &SceneStats) -> Self {
        SceneFile {
            scene: s.tag.scene,
            station: s.tag.station,
            pan_deg: s.pan.to_degrees(),
            base: [s.base.x, s.base.y, s.base.theta],
            scans: s.scans,
            points: s.points,
            quads: s.quads,
            triangles: s.triangles,
        }
    }
}

/// Valid polygons over possible ones.
#[derive(Clone, Debug, Serialize)]
pub struct Totals {
    /// Valid quadrilaterals and possible.
    pub quads: (usize, usize),
    /// Valid triangles and possible.
    pub triangles: (usize, usize),
    /// Valid share of quadrilaterals.
    pub quads_share: f64,
    /// Valid share of triangles.
    pub triangles_share: f64,
}

impl Totals {
    fn new(quads: (usize, usize), triangles: (usize, usize)) -> Self {
        let share = |(a, b): (usize, usize)| a as f64 / b.max(1) as f64;
        Totals {
            quads,
            triangles,
            quads_share: share(quads),
            triangles_share: share(triangles),
        }
    }

    fn of(model: &Model) -> Self {
        let (quads, triangles) = model.counts();
        Totals::new(quads, triangles)
    }
}

/// One model's accuracy.
#[derive(Clone, Debug, Serialize)]
pub struct PlacementAccuracy {
    /// How its scenes were placed.
    pub placement: Placement,
    /// Its figures.
    #[serde(flatten)]
    pub accuracy: Accuracy,
}

/// The contents of `reconstruction.json`.
pub fn reconstruction_file(recon: &Reconstruction) -> ReconstructionFile {
    let main = recon.main();
    ReconstructionFile {
        rule: recon.options.rule.to_string(),
        trim_beams: recon.options.trim_beams,
        main_placement: main.placement,
        scenes: main.model.scenes.iter().map(SceneFile::of).collect(),
        totals: Totals::of(&main.model),
        thesis: Totals::new(THESIS_QUADS, THESIS_TRIANGLES),
        accuracy: recon
            .models
            .iter()
            .filter_map(|m| {
                Some(PlacementAccuracy {
                    placement: m.placement,
                    accuracy: m.accuracy.clone()?,
                })
            })
            .collect(),
        rule_sweep: recon.sweep.clone(),
    }
}

/// The height above which nothing is drawn: just under the ceiling, found as the height most
/// readings stay below.
fn cut_height(model: &Model) -> f32 {
    let mut z: Vec<f32> = model.vertices.iter().map(|v| v[2]).collect();
    if z.is_empty() {
        return 2.0;
    }
    let k = ((z.len() - 1) as f64 * 0.995) as usize;
    let top = *z.select_nth_unstable_by(k, f32::total_cmp).1;
    (0.92 * top).clamp(0.5, 5.0)
}

/// Writes `model.ply` (the main model: vertices with normals and scene numbers, triangles),
/// `reconstruction.json` and `model.png` into `dir`; returns the files.
///
/// `world`, when known (the twin), draws the true walls under the top view.
pub fn write_reconstruction(
    dir: &Path,
    recon: &Reconstruction,
    title: &str,
    world: Option<&WorldMap>,
) -> std::io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let main = recon.main();
    let ply = dir.join("model.ply");
    write_ply(&ply, &main.model, false)?;
    let json = dir.join("reconstruction.json");
    let mut text = serde_json::to_string_pretty(&reconstruction_file(recon))?;
    text.push('\n');
    robot::logs::write_file(&json, text)?;
    let png = dir.join("model.png");
    let mut stations: Vec<(usize, robot::Pose2)> = Vec::new();
    for s in &main.model.scenes {
        if !stations.iter().any(|(n, _)| *n == s.tag.station) {
            stations.push((s.tag.station, s.base));
        }
    }
    let ((quads, of), (triangles, _)) = main.model.counts();
    let picture = Picture {
        title: format!(
            "{title}: 3D model placed by {}, {} scene(s) at {} station(s)",
            main.placement.name(),
            main.model.scenes.len(),
            stations.len()
        ),
        subtitle: format!(
            "{} points, {} valid triangles, {quads} of {of} quadrilaterals valid ({}); coloured by height",
            main.model.vertices.len(),
            triangles,
            recon.options.rule,
        ),
        model: &main.model,
        stations,
        cut_z: cut_height(&main.model),
        walls: world.map_or_else(Vec::new, |w| w.faces().iter().map(|f| (f.a, f.b)).collect()),
    };
    write_model_png(&png, &picture)?;
    Ok(vec![ply, json, png])
}

/// A few lines for the terminal: counts against the thesis's, and each model's accuracy.
pub fn reconstruction_report(recon: &Reconstruction) -> String {
    let mut out = String::new();
    let main = recon.main();
    let ((q, qo), (t, to)) = main.model.counts();
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    let _ = writeln!(
        out,
        "3D model: {} scene(s), {} points; valid triangles {t} of {to} ({:.1} %), quadrilaterals {q} of {qo} ({:.1} %) — thesis, one scene: {:.1} % and {:.1} %",
        main.model.scenes.len(),
        main.model.vertices.len(),
        pct(t, to),
        pct(q, qo),
        pct(THESIS_TRIANGLES.0, THESIS_TRIANGLES.1),
        pct(THESIS_QUADS.0, THESIS_QUADS.1),
    );
    for m in &recon.models {
        if let Some(a) = &m.accuracy {
            let _ = writeln!(
                out,
                "  placed by {:<8}: point error median {:.1} mm, p95 {:.1} mm, {:.1} % within 2 cm; phantom area {:.2} m² of {:.1} m²; coverage {:.1} %{}",
                m.placement.name(),
                a.median_m * 1e3,
                a.p95_m * 1e3,
                100.0 * a.within_2cm,
                a.phantom_area_m2,
                a.mesh_area_m2,
                100.0 * a.coverage,
                a.seam_m
                    .map_or(String::new(), |s| format!("; seam {:.1} mm", s * 1e3))
            );
        }
    }
    if matches!(recon.options.rule, MeshRule::Thesis { .. }) && !recon.sweep.is_empty() {
        let _ = writeln!(
            out,
            "  (the validity rule swept over {} variants: reconstruction.json)",
            recon.sweep.len()
        );
    }
    out
}
