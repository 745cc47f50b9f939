//! `map.svg`: the world, the true path, the odometry path, and the scans drawn from both, so the
//! drift shows at a glance; a grid in metres, a scale bar and a legend of exactly what is drawn.

pub(super) use super::figure::xml_escape;
use super::figure::{Layers, Plan, Swatch, open_svg};
use super::summary::estimate_errors;
use crate::config::{Material, WorldDescription};
use crate::record::RunRecord;
use crate::record::dots::{DotLayer, Drawn, ScanDots, cell_of, cells_within, push_move};
use crate::world::PointKind;
use robot::Pose2;
use std::fmt::Write as _;
use std::path::Path;

/// Pixels per metre.
const SCALE: f64 = 60.0;
/// Margin around what the picture frames, metres.
const MARGIN: f64 = 0.6;
/// Margin around the plan view, pixels.
const PAD: f64 = 12.0;
/// Half-pixel cells a metre: each scan point is drawn on one, each cell once.
const CELLS_PER_M: f64 = 2.0 * SCALE;
/// Most points of the estimate's map drawn (the rest are thinned out evenly).
const MAX_POINTS: usize = 60_000;
/// Width of one legend column, pixels.
const LEGEND_COLUMN: f64 = 300.0;
/// The colour a point of `kind` is drawn in.
pub(super) const fn point_colour(kind: PointKind) -> &'static str {
    match kind {
        PointKind::Surface => "#1f3b73",
        PointKind::Floor => "#a6761d",
        PointKind::Ghost => "#e0115f",
    }
}

/// The colour a wall of `material` is drawn in.
pub(super) fn wall_colour(material: Material) -> &'static str {
    match material {
        Material::Matte => "#c9c9c9",
        Material::Black => "#3c3c3c",
        Material::Glass => "#8ec9f0",
        Material::Metal => "#b3a6c9",
    }
}

/// The legend key and label of a wall of `material`.
pub(super) fn wall_legend(material: Material) -> (&'static str, &'static str) {
    match material {
        Material::Matte => ("wall-matte", "walls"),
        Material::Black => ("wall-black", "black surfaces (no laser return)"),
        Material::Glass => ("wall-glass", "glass"),
        Material::Metal => ("wall-metal", "metal (mirrors the laser)"),
    }
}

/// The walls of `world` in `plan`, one layer per material.
pub(super) fn draw_walls(layers: &mut Layers, plan: &Plan, world: &WorldDescription, width: f64) {
    for material in [
        Material::Matte,
        Material::Black,
        Material::Glass,
        Material::Metal,
    ] {
        let colour = wall_colour(material);
        let mut body = String::new();
        for wall in world.walls.iter().filter(|w| w.material == material) {
            let d = path_data(
                wall.points.iter().map(|p| {
                    let (x, y) = plan.clamped(p[0], p[1]);
                    (x, y)
                }),
                wall.closed,
            );
            let _ = write!(
                body,
                r#"<path d="{d}" stroke="{colour}" stroke-width="{width}" fill="none" stroke-linejoin="round"/>"#
            );
        }
        let (key, label) = wall_legend(material);
        layers.add(key, label, Swatch::Line(colour, width, None), &body);
    }
}

const TRUTH: &str = "#1a9850";
const ODOMETRY: &str = "#d73027";
const DRIFTED: &str = "#f08a24";
const ESTIMATE: &str = "#6a3d9a";
const ESTIMATE_SCANS: &str = "#b07cd8";

/// Writes the map picture.
/// Writes the map picture of `record` in `world` (`map` is that world's map).
pub fn write_map_svg(
    path: &Path,
    record: &RunRecord,
    world: &WorldDescription,
    dots: &ScanDots,
) -> std::io::Result<()> {
    robot::logs::write_file(path, render(record, world, dots))
}

fn render(record: &RunRecord, world: &WorldDescription, dots: &ScanDots) -> String {
    let odometry: Vec<Pose2> =
        std::iter::once(record.true_path.first().map_or(world.start, |p| p.1))
            .chain(record.scans.iter().map(|r| r.odometry))
            .chain(std::iter::once(record.final_odometry))
            .collect();
    let estimate: Vec<Pose2> = record
        .localisation
        .iter()
        .flat_map(|l| l.placed.iter().map(|p| p.estimate))
        .collect();
    // The frame holds the world and every path, end markers included; scan points beyond it
    // (mirror images far behind glass, scans placed by a drifted odometry) are marked at its edge.
    let (mut min, mut max) = world.bounds();
    let truth_poses = record.true_path.iter().map(|(_, p)| p);
    for p in truth_poses.chain(&odometry).chain(&estimate) {
        if p.x.is_finite() && p.y.is_finite() && p.x.abs() < 1e5 && p.y.abs() < 1e5 {
            min = [min[0].min(p.x - 0.4), min[1].min(p.y - 0.4)];
            max = [max[0].max(p.x + 0.4), max[1].max(p.y + 0.4)];
        }
    }
    // The left and top edges on the scan points' lattice (a cell's dot then sits on a whole
    // half pixel), outside the margin.
    let plan = Plan {
        min: [
            ((min[0] - MARGIN) * CELLS_PER_M).floor() / CELLS_PER_M,
            min[1] - MARGIN,
        ],
        max: [
            max[0] + MARGIN,
            ((max[1] + MARGIN) * CELLS_PER_M).ceil() / CELLS_PER_M,
        ],
        origin: [PAD + Plan::LEFT, PAD + Plan::ABOVE],
        scale: SCALE,
    };
    let mut layers = Layers::default();
    layers.plain(&plan.grid());
    draw_walls(&mut layers, &plan, world, 5.0);

    // Scans drawn from the true pose (what is there, with the laser's noise) and from odometry.
    // A point where there is no surface — a mirror image off glass or metal, or an outlier — is
    // a ghost, drawn apart; so are the floor hits of a tilted laser.
    let mut beyond = (String::new(), 0usize);
    let drifted = framed(&plan, &dots.drifted, DRIFTED, &mut beyond);
    let seen = framed(
        &plan,
        &dots.seen,
        point_colour(PointKind::Surface),
        &mut beyond,
    );
    let floor = framed(
        &plan,
        &dots.floor,
        point_colour(PointKind::Floor),
        &mut beyond,
    );
    let ghosts = framed(
        &plan,
        &dots.ghosts,
        point_colour(PointKind::Ghost),
        &mut beyond,
    );
    for _ in 0..dots.unplaced {
        mark_beyond(&plan, f64::NAN, f64::NAN, &mut beyond);
    }
    let mut placed = DotLayer::default();
    if let Some(loc) = &record.localisation {
        let mut drawn = Drawn::new(
            cells_within(plan.min[0], plan.max[0], CELLS_PER_M),
            cells_within(plan.min[1], plan.max[1], CELLS_PER_M),
        );
        let stride = loc.map.len().div_ceil(MAX_POINTS).max(1);
        for p in loc.map.iter().step_by(stride) {
            match cell_of(p[0], p[1], CELLS_PER_M) {
                Some(cell) => {
                    if let Some(inside) = drawn.insert(cell) {
                        placed.push(cell, inside);
                    }
                }
                None => mark_beyond(&plan, p[0], p[1], &mut beyond),
            }
        }
    }
    let estimated = framed(&plan, &placed, ESTIMATE_SCANS, &mut beyond);
    let (beyond, beyond_count) = beyond;
    layers.add(
        "scans-odometry",
        "scans placed at odometry",
        Swatch::Dots(DRIFTED),
        &drifted,
    );
    layers.add(
        "scans-truth",
        "scans placed at the true pose",
        Swatch::Dots(point_colour(PointKind::Surface)),
        &seen,
    );
    layers.add(
        "floor",
        "floor hits (tilted laser)",
        Swatch::Dots(point_colour(PointKind::Floor)),
        &floor,
    );
    layers.add(
        "ghosts",
        "ghosts: no surface there",
        Swatch::Dots(point_colour(PointKind::Ghost)),
        &ghosts,
    );
    layers.add(
        "scans-estimate",
        "scans placed at the estimate",
        Swatch::Dots(ESTIMATE_SCANS),
        &estimated,
    );
    layers.add_beyond(beyond_count, "point", "the frame", &beyond, 3.0);

    // The sonar ring's last reading: a wedge per transducer out to its echo.
    if let Some(sonar) = &record.sonar {
        layers.add(
            "sonar",
            "sonar: last ring reading (dashed: no echo)",
            Swatch::Area("#9b59b6", "#7d3c98"),
            &draw_sonar(&plan, sonar),
        );
    }

    // Paths.
    let step = record.true_path.len().div_ceil(8000).max(1);
    let truth: Vec<Pose2> = record
        .true_path
        .iter()
        .step_by(step)
        .map(|(_, p)| *p)
        .collect();
    for (poses, colour, dash, key, label) in [
        (&truth, TRUTH, None, "path-truth", "true path"),
        (
            &odometry,
            ODOMETRY,
            Some("6 4"),
            "path-odometry",
            "odometry",
        ),
        (
            &estimate,
            ESTIMATE,
            Some("2 3"),
            "path-estimate",
            "scan-matching estimate",
        ),
    ] {
        if poses.is_empty() {
            continue;
        }
        let d = path_data(poses.iter().map(|p| plan.clamped(p.x, p.y)), false);
        let dash_attr = dash.map_or(String::new(), |d| format!(r#" stroke-dasharray="{d}""#));
        layers.add(
            key,
            label,
            Swatch::Line(colour, 2.0, dash),
            &format!(
                r#"<path d="{d}" stroke="{colour}" stroke-width="2"{dash_attr} fill="none"/>"#
            ),
        );
    }
    let start = record.true_path.first().map_or(world.start, |p| p.1);
    let (sx, sy) = plan.clamped(start.x, start.y);
    layers.add(
        "start",
        "start",
        Swatch::Square("black"),
        &format!(
            r#"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="black"/>"#,
            sx - 5.0,
            sy - 5.0
        ),
    );
    // The goals of `goto` steps, each drawn once, whether reached or not.
    let mut goals = String::new();
    let mut drawn: Vec<[f64; 2]> = Vec::new();
    for g in record.decisions.iter().filter_map(|d| d.goal) {
        if drawn.contains(&g) {
            continue;
        }
        drawn.push(g);
        let (gx, gy) = plan.clamped(g[0], g[1]);
        // A square, as its legend swatch.
        let _ = write!(
            goals,
            r##"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="#e377c2" stroke="black"/>"##,
            gx - 5.0,
            gy - 5.0
        );
    }
    layers.add(
        "goals",
        "goals of goto steps",
        Swatch::Square("#e377c2"),
        &goals,
    );
    for (p, colour, key, label) in [
        (record.final_truth, TRUTH, "end-truth", "end, true pose"),
        (
            record.final_odometry,
            ODOMETRY,
            "end-odometry",
            "end, by odometry",
        ),
    ] {
        let (x, y) = plan.clamped(p.x, p.y);
        let (hx, hy) = p.transform_point(0.3, 0.0);
        let (hx, hy) = plan.clamped(hx, hy);
        layers.add(
            key,
            label,
            Swatch::Pose(colour),
            &format!(
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="6" fill="none" stroke="{colour}" stroke-width="2"/><line x1="{x:.1}" y1="{y:.1}" x2="{hx:.1}" y2="{hy:.1}" stroke="{colour}" stroke-width="2"/>"#
            ),
        );
    }

    // Legend, figures and scale bar below the plan.
    let column = layers.column_width(LEGEND_COLUMN);
    let width = (plan.origin[0] + plan.width() + PAD).max(column + 2.0 * PAD);
    let columns = (((width - 2.0 * PAD) / column).floor() as usize).clamp(1, 3);
    let legend_top = plan.origin[1] + plan.height() + Plan::BELOW + 12.0;
    let figures_y = legend_top + 20.0 * layers.rows(columns) as f64 + 10.0;
    let figures_lines = 2 + usize::from(record.localisation.is_some());
    let bar_y = figures_y + 18.0 * figures_lines as f64 + 8.0;
    let height = bar_y + 12.0;
    let mut s = open_svg(width, height, 13);
    s.reserve(layers.body().len() + 4096 * (1 + layers.rows(columns)));
    s.push_str(layers.body());
    s.push_str(&layers.legend(PAD, legend_top, columns, column));
    let _ = writeln!(
        s,
        r#"<text x="{PAD}" y="{figures_y:.0}">{}: {} scan{}, {:.1} m in {:.1} s, seed {}</text>"#,
        xml_escape(&record.scenario),
        record.scans.len(),
        if record.scans.len() == 1 { "" } else { "s" },
        record.distance_m,
        record.sim_seconds(),
        record.seed,
    );
    let _ = writeln!(
        s,
        r#"<text x="{PAD}" y="{:.0}">final odometry error {:.3} m, {:.2}°</text>"#,
        figures_y + 18.0,
        record.final_odometry_error_m(),
        record.final_odometry_error_deg(),
    );
    if let Some(loc) = &record.localisation {
        let (final_m, final_deg, rms_m, rms_deg) = estimate_errors(record, loc);
        let _ = writeln!(
            s,
            r#"<text x="{PAD}" y="{:.0}">estimate ({}): final error {final_m:.3} m, {final_deg:.2}°; RMS {rms_m:.3} m, {rms_deg:.2}°</text>"#,
            figures_y + 36.0,
            loc.matcher,
        );
    }
    s.push_str(&plan.scale_bar(width - PAD - 4.0, bar_y));
    s.push_str("</svg>\n");
    s
}

/// `layer` in `plan`, in `colour` (nothing when it has no dot in the frame): its path data in
/// lattice units, placed by a transform, and its cells beyond the world's rectangle that the
/// frame holds; the others are marked at the frame's edge in `beyond`, and counted.
fn framed(plan: &Plan, layer: &DotLayer, colour: &str, beyond: &mut (String, usize)) -> String {
    // The frame's left and top edges lie on the lattice.
    let left = (plan.min[0] * CELLS_PER_M).round();
    let top = (plan.max[1] * CELLS_PER_M).round();
    let (columns, rows) = (
        cells_within(plan.min[0], plan.max[0], CELLS_PER_M),
        cells_within(plan.min[1], plan.max[1], CELLS_PER_M),
    );
    let mut more = Vec::new();
    for &(i, j) in &layer.beyond {
        if columns.contains(&i) && rows.contains(&j) {
            push_move(&mut more, b'M', i, -j);
        } else {
            mark_beyond(plan, i as f64 / CELLS_PER_M, j as f64 / CELLS_PER_M, beyond);
        }
    }
    if layer.d.is_empty() && more.is_empty() {
        return String::new();
    }
    // Path data is ASCII (`push_move` writes nothing else).
    fn ascii(d: &[u8]) -> &str {
        std::str::from_utf8(d).expect("path data is ASCII")
    }
    let (d, more) = (ascii(&layer.d), ascii(&more));
    // A cell is half a pixel: its column `i` lies at `origin + (i − left) / 2`, its row `j`
    // (written as `−j`) at `origin + (top − j) / 2`; a dot 2 pixels wide is 4 cells.
    let open = format!(
        r#"<g color="{colour}" transform="translate({} {}) scale(0.5)"><path d=""#,
        plan.origin[0] - left / 2.0,
        plan.origin[1] + top / 2.0,
    );
    let close =
        r#"" stroke="currentColor" stroke-width="4" stroke-linecap="round" fill="none"/></g>"#;
    let mut body = String::with_capacity(open.len() + d.len() + more.len() + close.len());
    body.push_str(&open);
    body.push_str(d);
    body.push_str(more);
    body.push_str(close);
    body
}

/// Marks the point at `(x, y)` metres, beyond `plan`'s frame, at its edge.
fn mark_beyond(plan: &Plan, x: f64, y: f64, (marks, count): &mut (String, usize)) {
    let (x, y) = plan.clamped(x, y);
    marks.push('M');
    push_tenths(marks, x);
    marks.push(' ');
    push_tenths(marks, y);
    marks.push_str("h0");
    *count += 1;
}

/// The scans' points of `record` drawn after the run, as [`ScanStream`](super::ScanStream)
/// draws them while it goes on.
pub(super) fn scan_dots(record: &RunRecord, world: &WorldDescription) -> ScanDots {
    let mut dots = new_scan_dots(world, std::sync::Arc::clone(&record.world_map));
    for r in &record.scans {
        dots.add(&r.scan, &r.frame, r.truth, r.odometry);
    }
    dots
}

/// No scan points of `world` (its map: `map`) drawn yet, on the map picture's lattice.
pub fn new_scan_dots(
    world: &WorldDescription,
    map: std::sync::Arc<crate::world::WorldMap>,
) -> ScanDots {
    ScanDots::new(world, map, CELLS_PER_M, MARGIN)
}

/// Writes `n` in decimal, as `{}` does, without the formatter's machinery (a picture writes
/// hundreds of thousands of them).
fn push_whole(s: &mut String, n: u64) {
    s.push_str(itoa::Buffer::new().format(n));
}

/// Writes `x` as `format!("{x:.1}")` does, byte for byte, without the general float formatter
/// where the answer is plain: whole tenths counted in an integer, unless `x` is huge, not
/// finite, a negative that rounds to zero ("-0.0") or within a millionth of a tenth of a tie
/// (where the formatter's exact decimal rounding decides).
pub(super) fn push_tenths(s: &mut String, x: f64) {
    let t = x * 10.0;
    let r = t.round();
    let plain = t.abs() < 1e15 && (t - r).abs() < 0.5 - 1e-6 && !(r == 0.0 && x.is_sign_negative());
    if !plain {
        let _ = write!(s, "{x:.1}");
        return;
    }
    let tenths = r as i64;
    if tenths < 0 {
        s.push('-');
    }
    let n = tenths.unsigned_abs();
    push_whole(s, n / 10);
    s.push('.');
    s.push(char::from(b'0' + (n % 10) as u8));
}

/// The SVG path data through `points` (already in pixels), closed back to the first if
/// `closed`.
pub(super) fn path_data(points: impl IntoIterator<Item = (f64, f64)>, closed: bool) -> String {
    let mut d = String::new();
    for (i, (x, y)) in points.into_iter().enumerate() {
        d.push(if i == 0 { 'M' } else { 'L' });
        push_tenths(&mut d, x);
        d.push(' ');
        push_tenths(&mut d, y);
    }
    if closed {
        d.push('Z');
    }
    d
}

/// One wedge per transducer, from the transducer out to its echo; a dashed ray for no echo.
fn draw_sonar(plan: &Plan, sonar: &crate::record::SonarRecord) -> String {
    use robot::hardware::{SPEED_OF_SOUND, echo_distance_m};
    let mut s = String::new();
    let e = &sonar.echoes;
    for (i, &k) in e.sequence.iter().enumerate() {
        let Some(mount) = sonar.transducers.get(usize::from(k)) else {
            continue;
        };
        let at = sonar.truth.compose(mount);
        let (ax, ay) = plan.clamped(at.x, at.y);
        match echo_distance_m(e.times[i], SPEED_OF_SOUND) {
            Some(d) => {
                // A wedge: straight sides out to the echo, a polyline along the arc, all within
                // the frame.
                let half = sonar.cone / 2.0;
                let mut d_path = format!("M{ax:.1} {ay:.1}");
                for j in 0..=8 {
                    let a = -half + 2.0 * half * f64::from(j) / 8.0;
                    let (x, y) = at.transform_point(d * a.cos(), d * a.sin());
                    let (x, y) = plan.clamped(x, y);
                    let _ = write!(d_path, "L{x:.1} {y:.1}");
                }
                let _ = write!(
                    s,
                    r##"<path d="{d_path}Z" fill="#9b59b6" fill-opacity="0.18" stroke="#7d3c98" stroke-width="1.2"><title>sonar {k}: {d:.2} m</title></path>"##
                );
            }
            None => {
                let (x, y) = at.transform_point(0.6, 0.0);
                let (x, y) = plan.clamped(x, y);
                let _ = write!(
                    s,
                    r##"<line x1="{ax:.1}" y1="{ay:.1}" x2="{x:.1}" y2="{y:.1}" stroke="#7d3c98" stroke-width="1.2" stroke-dasharray="3 3"><title>sonar {k}: no echo</title></line>"##
                );
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn tenths_are_written_as_the_formatter_writes_them() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(7);
        let mut values = vec![
            0.0,
            -0.0,
            0.05,
            -0.05,
            0.25,
            -0.25,
            0.35,
            1.45,
            2.5,
            -0.04,
            -0.06,
            1e14,
            -1e14,
            1e16,
            123.45,
            9.95,
            -9.95,
            0.95,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for _ in 0..200_000 {
            let scale = [1.0, 10.0, 1000.0, 1e6][rng.random_range(0..4)];
            let x: f64 = (rng.random::<f64>() - 0.5) * scale;
            values.push(x);
            // Ties and near-ties in tenths and hundredths.
            values.push((x * 100.0).round() / 100.0);
            values.push((x * 20.0).round() / 20.0);
        }
        for x in values {
            let mut s = String::new();
            push_tenths(&mut s, x);
            assert_eq!(s, format!("{x:.1}"), "{x:e}");
        }
    }

    #[test]
    fn whole_numbers_are_written_as_the_formatter_writes_them() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut values: Vec<u64> = vec![0, 1, 9, 10, 19, 20, 99, 100, u64::MAX];
        values.extend((0..100_000).map(|_| rng.random::<u64>() >> rng.random_range(0..64)));
        for n in values {
            let mut s = String::new();
            push_whole(&mut s, n);
            assert_eq!(s, n.to_string());
        }
    }
}
