//! `map.svg`: the world, the true path, the odometry path, and the scans drawn from both, so the
//! drift shows at a glance.

use super::summary::estimate_errors;
use crate::config::{Material, WorldDescription};
use crate::record::RunRecord;
use crate::world::{PointKind, WorldMap};
use robot::Pose2;
use std::fmt::Write as _;
use std::path::Path;

/// Pixels per metre.
const SCALE: f64 = 60.0;
/// Margin around the world, metres.
const MARGIN: f64 = 0.6;
/// Most scan points drawn per projection (the rest are thinned out evenly).
const MAX_POINTS: usize = 60_000;
/// Width of one legend column, pixels.
const LEGEND_COLUMN: f64 = 280.0;
/// The colour a point of `kind` is drawn in.
pub(super) const fn point_colour(kind: PointKind) -> &'static str {
    match kind {
        PointKind::Surface => "#1f3b73",
        PointKind::Floor => "#2ca25f",
        PointKind::Ghost => "#e0115f",
    }
}

/// The colour a wall of `material` is drawn in.
pub(super) fn wall_colour(material: Material) -> &'static str {
    match material {
        Material::Matte => "#c9c9c9",
        Material::Black => "#8c8c8c",
        Material::Glass => "#8ec9f0",
        Material::Metal => "#b3a6c9",
    }
}

/// The legend's entries.
const LEGEND: [(&str, &str); 6] = [
    ("#1a9850", "true path"),
    ("#d73027", "odometry"),
    (
        point_colour(PointKind::Surface),
        "scans placed at the true pose",
    ),
    ("#f08a24", "scans placed at odometry"),
    (point_colour(PointKind::Ghost), "ghosts: no surface there"),
    ("#c9c9c9", "walls (blue glass, violet metal)"),
];
/// The legend's entries for the scan-matching estimate, shown when the run localised.
const ESTIMATE_LEGEND: [(&str, &str); 2] = [
    ("#6a3d9a", "scan-matching estimate"),
    ("#b07cd8", "scans placed at the estimate"),
];
/// The legend's entry for floor hits, shown when a tilted laser made some.
const FLOOR_LEGEND: (&str, &str) = (point_colour(PointKind::Floor), "floor hits (tilted laser)");

/// Writes the map picture.
pub fn write_map_svg(
    path: &Path,
    record: &RunRecord,
    world: &WorldDescription,
) -> std::io::Result<()> {
    std::fs::write(path, render(record, world))
}

struct Frame {
    min: [f64; 2],
    max: [f64; 2],
}

impl Frame {
    fn x(&self, x: f64) -> f64 {
        (x - self.min[0] + MARGIN) * SCALE
    }
    fn y(&self, y: f64) -> f64 {
        (self.max[1] + MARGIN - y) * SCALE
    }
    /// Whether the world point `(x, y)` falls inside the drawing (the world and its margin).
    fn inside(&self, x: f64, y: f64) -> bool {
        (self.min[0] - MARGIN..=self.max[0] + MARGIN).contains(&x)
            && (self.min[1] - MARGIN..=self.max[1] + MARGIN).contains(&y)
    }
}

fn render(record: &RunRecord, world: &WorldDescription) -> String {
    let (mut min, mut max) = world.bounds();
    for (_, p) in &record.true_path {
        min = [min[0].min(p.x), min[1].min(p.y)];
        max = [max[0].max(p.x), max[1].max(p.y)];
    }
    let f = Frame { min, max };
    let map = WorldMap::new(world);
    let points = classify_points(record, &map);
    let mut legend = LEGEND.to_vec();
    if !points.floor.is_empty() {
        legend.push(FLOOR_LEGEND);
    }
    if record.localisation.is_some() {
        legend.extend(ESTIMATE_LEGEND);
    }
    let width = ((max[0] - min[0] + 2.0 * MARGIN) * SCALE).max(LEGEND_COLUMN + 24.0);
    let columns = (((width - 24.0) / LEGEND_COLUMN).floor() as usize).clamp(1, 3);
    let legend_rows = legend.len().div_ceil(columns);
    let legend_height = 20.0 * legend_rows as f64 + 68.0;
    let height = (max[1] - min[1] + 2.0 * MARGIN) * SCALE + legend_height;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);

    // Walls.
    for wall in &world.walls {
        let colour = wall_colour(wall.material);
        let w = if wall.material == Material::Black {
            6.0
        } else {
            5.0
        };
        let d = path_data(
            wall.points.iter().map(|p| (f.x(p[0]), f.y(p[1]))),
            wall.closed,
        );
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{colour}" stroke-width="{w}" fill="none" stroke-linejoin="round"><title>{}</title></path>"#,
            wall.material.name()
        );
    }

    // Scans drawn from the true pose (what is there, with the laser's noise) and from odometry.
    // A point where there is no surface — a mirror image off glass or metal, or an outlier — is
    // a ghost, drawn apart; so are the floor hits of a tilted laser.
    // Points beyond the drawing (mirror images far behind glass) are counted, not drawn.
    let beyond = std::cell::Cell::new(0usize);
    let dots = |points: &mut dyn Iterator<Item = [f64; 3]>| {
        let mut d = String::new();
        for p in points {
            if f.inside(p[0], p[1]) {
                let _ = write!(d, "M{:.1} {:.1}h0", f.x(p[0]), f.y(p[1]));
            } else {
                beyond.set(beyond.get() + 1);
            }
        }
        d
    };
    for (d, colour, label) in [
        (
            dots(&mut points.drifted.iter().copied()),
            "#f08a24",
            "scans at odometry",
        ),
        (
            dots(&mut points.seen.iter().copied()),
            point_colour(PointKind::Surface),
            "scans at true pose",
        ),
        (
            dots(&mut points.floor.iter().copied()),
            FLOOR_LEGEND.0,
            FLOOR_LEGEND.1,
        ),
        (
            dots(&mut points.ghosts.iter().copied()),
            point_colour(PointKind::Ghost),
            "ghosts: no surface there",
        ),
    ] {
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{colour}" stroke-width="2" stroke-linecap="round" fill="none"><title>{label}</title></path>"#
        );
    }

    // The scan-matching estimate's map.
    if let Some(loc) = &record.localisation {
        let stride = loc.map.len().div_ceil(MAX_POINTS).max(1);
        let d = dots(&mut loc.map.iter().step_by(stride).map(|p| [p[0], p[1], 0.0]));
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{}" stroke-width="2" stroke-linecap="round" fill="none" opacity="0.8"><title>scans placed at the estimate</title></path>"#,
            ESTIMATE_LEGEND[1].0
        );
    }

    // The sonar ring's last reading: a wedge per transducer out to its echo.
    if let Some(sonar) = &record.sonar {
        draw_sonar(&mut s, &f, sonar);
    }

    // Paths.
    let step = record.true_path.len().div_ceil(8000).max(1);
    let truth: Vec<Pose2> = record
        .true_path
        .iter()
        .step_by(step)
        .map(|(_, p)| *p)
        .collect();
    let odometry: Vec<Pose2> = std::iter::once(world.start)
        .chain(record.scans.iter().map(|r| r.odometry))
        .chain(std::iter::once(record.final_odometry))
        .collect();
    let estimate: Vec<Pose2> = record
        .localisation
        .iter()
        .flat_map(|l| l.placed.iter().map(|p| p.estimate))
        .collect();
    for (poses, colour, dash, label) in [
        (&truth, "#1a9850", "", "true path"),
        (
            &odometry,
            "#d73027",
            r#" stroke-dasharray="6 4""#,
            "odometry",
        ),
        (
            &estimate,
            ESTIMATE_LEGEND[0].0,
            r#" stroke-dasharray="2 3""#,
            "scan-matching estimate",
        ),
    ] {
        let d = path_data(poses.iter().map(|p| (f.x(p.x), f.y(p.y))), false);
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{colour}" stroke-width="2"{dash} fill="none"><title>{label}</title></path>"#
        );
    }
    for (p, colour) in [
        (record.final_truth, "#1a9850"),
        (record.final_odometry, "#d73027"),
    ] {
        let (hx, hy) = p.transform_point(0.3, 0.0);
        let _ = writeln!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="6" fill="none" stroke="{colour}" stroke-width="2"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="2"/>"#,
            f.x(p.x),
            f.y(p.y),
            f.x(p.x),
            f.y(p.y),
            f.x(hx),
            f.y(hy)
        );
    }

    // Legend, figures and scale bar.
    let top = height - legend_height + 8.0;
    for (i, (colour, label)) in legend.iter().enumerate() {
        let x = 12.0 + LEGEND_COLUMN * (i % columns) as f64;
        let y = top + 20.0 * (i / columns) as f64;
        let _ = writeln!(
            s,
            r#"<rect x="{x:.0}" y="{y:.0}" width="18" height="6" fill="{colour}"/><text x="{:.0}" y="{:.0}">{label}</text>"#,
            x + 24.0,
            y + 7.0
        );
    }
    let figures_y = top + 20.0 * legend_rows as f64 + 6.0;
    let _ = writeln!(
        s,
        r#"<text x="12" y="{figures_y:.0}">{}: {} scans, {:.1} m in {:.1} s, seed {}{}</text>"#,
        xml_escape(&record.scenario),
        record.scans.len(),
        record.distance_m,
        record.sim_seconds(),
        record.seed,
        match beyond.get() {
            0 => String::new(),
            n => format!("; {n} points beyond the frame (ghosts) not drawn"),
        }
    );
    let _ = writeln!(
        s,
        r#"<text x="12" y="{:.0}">final odometry error {:.3} m, {:.2}°</text>"#,
        figures_y + 18.0,
        record.final_odometry_error_m(),
        record.final_odometry_error_deg(),
    );
    if let Some(loc) = &record.localisation {
        let (final_m, final_deg, rms_m, rms_deg) = estimate_errors(record, loc);
        let _ = writeln!(
            s,
            r#"<text x="12" y="{:.0}">estimate ({}): final error {final_m:.3} m, {final_deg:.2}°; RMS {rms_m:.3} m, {rms_deg:.2}°</text>"#,
            figures_y + 36.0,
            loc.matcher,
        );
    }
    let bar_x = width - 12.0 - SCALE;
    let bar_y = figures_y + 14.0;
    let _ = writeln!(
        s,
        r#"<line x1="{bar_x:.0}" y1="{bar_y:.0}" x2="{:.0}" y2="{bar_y:.0}" stroke="black" stroke-width="3"/><text x="{:.0}" y="{:.0}">1 m</text>"#,
        bar_x + SCALE,
        bar_x + SCALE / 2.0 - 10.0,
        bar_y - 6.0
    );
    s.push_str("</svg>\n");
    s
}

/// The scans' points in the world, sorted by what they hit.
#[derive(Default)]
struct ScanPoints {
    /// Placed at the true pose, on a surface.
    seen: Vec<[f64; 3]>,
    /// Placed at the true pose, on the floor.
    floor: Vec<[f64; 3]>,
    /// Placed at the true pose, far from every surface.
    ghosts: Vec<[f64; 3]>,
    /// Placed at the odometry pose.
    drifted: Vec<[f64; 3]>,
}

/// Every returned beam of the run (thinned to [`MAX_POINTS`]) as world points, from the laser's
/// true 3D frame and from where odometry puts it.
fn classify_points(record: &RunRecord, map: &WorldMap) -> ScanPoints {
    let total: usize = record.scans.iter().map(|r| r.scan.len()).sum();
    let stride = total.div_ceil(MAX_POINTS).max(1);
    let mut out = ScanPoints::default();
    let mut k = 0usize;
    for r in &record.scans {
        let at_odometry = r.frame.carried(r.truth, r.odometry);
        for i in 0..r.scan.len() {
            let Some(range) = r.scan.range_m(i) else {
                continue;
            };
            k += 1;
            if !k.is_multiple_of(stride) {
                continue;
            }
            let angle = r.scan.angle(i);
            let p = r.frame.point(angle, range);
            let target = match PointKind::of(map, p) {
                PointKind::Ghost => &mut out.ghosts,
                PointKind::Floor => &mut out.floor,
                PointKind::Surface => &mut out.seen,
            };
            target.push(p);
            out.drifted.push(at_odometry.point(angle, range));
        }
    }
    out
}

/// The SVG path data through `points` (already in pixels), closed back to the first if
/// `closed`.
pub(super) fn path_data(points: impl IntoIterator<Item = (f64, f64)>, closed: bool) -> String {
    let mut d = String::new();
    for (i, (x, y)) in points.into_iter().enumerate() {
        let _ = write!(d, "{}{x:.1} {y:.1}", if i == 0 { "M" } else { "L" });
    }
    if closed {
        d.push('Z');
    }
    d
}

/// Text safe inside SVG markup.
pub(super) fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// One wedge per transducer, from the transducer out to its echo; a dashed ray for no echo.
fn draw_sonar(s: &mut String, f: &Frame, sonar: &crate::record::SonarRecord) {
    use robot::hardware::{SPEED_OF_SOUND, echo_distance_m};
    let e = &sonar.echoes;
    for (i, &k) in e.sequence.iter().enumerate() {
        let Some(mount) = sonar.transducers.get(usize::from(k)) else {
            continue;
        };
        let at = sonar.truth.compose(mount);
        match echo_distance_m(e.times[i], SPEED_OF_SOUND) {
            Some(d) => {
                let half = sonar.cone / 2.0;
                let (x1, y1) = at.transform_point(d * half.cos(), -d * half.sin());
                let (x2, y2) = at.transform_point(d * half.cos(), d * half.sin());
                let r = d * SCALE;
                let _ = writeln!(
                    s,
                    r##"<path d="M{:.1} {:.1}L{:.1} {:.1}A{r:.1} {r:.1} 0 0 0 {:.1} {:.1}Z" fill="#9b59b6" fill-opacity="0.18" stroke="#7d3c98" stroke-width="1.2"><title>sonar {k}: {d:.2} m</title></path>"##,
                    f.x(at.x),
                    f.y(at.y),
                    f.x(x1),
                    f.y(y1),
                    f.x(x2),
                    f.y(y2)
                );
            }
            None => {
                let (x, y) = at.transform_point(0.6, 0.0);
                let _ = writeln!(
                    s,
                    r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#7d3c98" stroke-width="1.2" stroke-dasharray="3 3"><title>sonar {k}: no echo</title></line>"##,
                    f.x(at.x),
                    f.y(at.y),
                    f.x(x),
                    f.y(y)
                );
            }
        }
    }
}
