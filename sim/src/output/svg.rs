//! `map.svg`: the world, the true path, the odometry path, and the scans drawn from both, so the
//! drift shows at a glance; a grid in metres, a scale bar and a legend of exactly what is drawn.

pub(super) use super::figure::xml_escape;
use super::figure::{Layers, Plan, Swatch, open_svg};
use super::summary::estimate_errors;
use crate::config::{Material, WorldDescription};
use crate::devices::laser::LaserFrame;
use crate::record::RunRecord;
use crate::world::{PointKind, PointKinds, WorldMap};
use robot::Pose2;
use robot::hardware::LaserScan;
use std::fmt::Write as _;
use std::path::Path;

/// Pixels per metre.
const SCALE: f64 = 60.0;
/// Margin around what the picture frames, metres.
const MARGIN: f64 = 0.6;
/// Margin around the plan view, pixels.
const PAD: f64 = 12.0;
/// Most scan points drawn per projection (the rest are thinned out evenly).
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
    map: &WorldMap,
) -> std::io::Result<()> {
    robot::logs::write_file(path, render(record, world, map))
}

fn render(record: &RunRecord, world: &WorldDescription, map: &WorldMap) -> String {
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
    let plan = Plan {
        min: [min[0] - MARGIN, min[1] - MARGIN],
        max: [max[0] + MARGIN, max[1] + MARGIN],
        origin: [PAD + Plan::LEFT, PAD + Plan::ABOVE],
        scale: SCALE,
    };
    let mut layers = Layers::default();
    layers.plain(&plan.grid());
    draw_walls(&mut layers, &plan, world, 5.0);

    // Scans drawn from the true pose (what is there, with the laser's noise) and from odometry.
    // A point where there is no surface — a mirror image off glass or metal, or an outlier — is
    // a ghost, drawn apart; so are the floor hits of a tilted laser.
    let mut scans = ScanDots::new(&plan);
    draw_scan_points(record, map, &mut scans);
    let mut estimated = Dots::new(&plan);
    if let Some(loc) = &record.localisation {
        let stride = loc.map.len().div_ceil(MAX_POINTS).max(1);
        for p in loc.map.iter().step_by(stride) {
            estimated.add(p[0], p[1]);
        }
    }
    let mut beyond = String::new();
    let mut beyond_count = 0usize;
    let mut coloured = |colour: &str, dots: Dots| {
        let (body, out, count) = dots.finish(colour);
        beyond.push_str(&out);
        beyond_count += count;
        body
    };
    let drifted = coloured(DRIFTED, scans.drifted);
    let seen = coloured(point_colour(PointKind::Surface), scans.seen);
    let floor = coloured(point_colour(PointKind::Floor), scans.floor);
    let ghosts = coloured(point_colour(PointKind::Ghost), scans.ghosts);
    let estimated = coloured(ESTIMATE_SCANS, estimated);
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

/// The scans' points being drawn, sorted by what they hit.
struct ScanDots {
    /// Placed at the true pose, on a surface.
    seen: Dots,
    /// Placed at the true pose, on the floor.
    floor: Dots,
    /// Placed at the true pose, far from every surface.
    ghosts: Dots,
    /// Placed at the odometry pose.
    drifted: Dots,
}

impl ScanDots {
    fn new(plan: &Plan) -> Self {
        ScanDots {
            seen: Dots::new(plan),
            floor: Dots::new(plan),
            ghosts: Dots::new(plan),
            drifted: Dots::new(plan),
        }
    }
}

/// A layer of dots being drawn, point by point, as they come: each on a half-pixel grid and
/// drawn once (a 2-pixel dot hides any finer place, and a picture of a long run then costs what
/// its area does, not what its scans do); a point beyond the frame marked at its edge.
struct Dots {
    plan: Plan,
    /// The path data, ASCII (made text once, at the end).
    d: Vec<u8>,
    drawn: HalfPixels,
    /// The marks of the points beyond the frame, and their number.
    beyond: (String, usize),
}

impl Dots {
    fn new(plan: &Plan) -> Self {
        Dots {
            plan: *plan,
            d: Vec::new(),
            drawn: HalfPixels::new(plan),
            beyond: (String::new(), 0),
        }
    }

    /// Draws the point at `(x, y)` metres.
    fn add(&mut self, x: f64, y: f64) {
        let plan = &self.plan;
        if plan.contains(x, y) {
            // In the frame: both half-pixel numbers are positive, so adding a half and
            // truncating rounds.
            let (x, y) = (
                (plan.x(x) * 2.0 + 0.5) as i64,
                (plan.y(y) * 2.0 + 0.5) as i64,
            );
            if self.drawn.insert(x, y) {
                push_dot(&mut self.d, x, y);
            }
        } else {
            let (x, y) = plan.clamped(x, y);
            let beyond = &mut self.beyond.0;
            beyond.push('M');
            push_tenths(beyond, x);
            beyond.push(' ');
            push_tenths(beyond, y);
            beyond.push_str("h0");
            self.beyond.1 += 1;
        }
    }

    /// The layer in `colour` (nothing when no point fell in the frame), the marks of the
    /// points beyond it, and their number.
    fn finish(self, colour: &str) -> (String, String, usize) {
        let mut body = String::new();
        if !self.d.is_empty() {
            // Pieces pushed into room made once: the path data is the picture's bulk.
            let (open, close) = (
                format!(r#"<g color="{colour}"><path d=""#),
                r#"" stroke="currentColor" stroke-width="2" stroke-linecap="round" fill="none"/></g>"#,
            );
            let d = String::from_utf8(self.d).expect("path data is ASCII");
            body.reserve_exact(open.len() + d.len() + close.len());
            body.push_str(&open);
            body.push_str(&d);
            body.push_str(close);
        }
        (body, self.beyond.0, self.beyond.1)
    }
}

/// Each beam's sine and cosine, computed again only for a scan of other angles.
#[derive(Default)]
struct BeamTrig {
    angles: Option<(f64, f64)>,
    trig: Vec<(f64, f64)>,
}

impl BeamTrig {
    fn of(&mut self, scan: &LaserScan) -> &[(f64, f64)] {
        let angles = (scan.angle_min, scan.angle_increment);
        if self.angles != Some(angles) || scan.len() != self.trig.len() {
            self.angles = Some(angles);
            self.trig = (0..scan.len()).map(|i| scan.angle(i).sin_cos()).collect();
        }
        &self.trig
    }
}

/// The world point `range` metres along the beam of sine and cosine `(sa, ca)` from `frame`,
/// whose axes are `(forward, left)`: sums and products.
#[inline]
fn beam_point(
    frame: &LaserFrame,
    (forward, left): ([f64; 3], [f64; 3]),
    (sa, ca): (f64, f64),
    range: f64,
) -> [f64; 3] {
    let at = |j: usize| frame.origin[j] + range * (ca * forward[j] + sa * left[j]);
    [at(0), at(1), at(2)]
}

/// Draws every returned beam of the run (thinned to [`MAX_POINTS`]), from the laser's true 3D
/// frame and from where odometry puts it, each as it is placed.
fn draw_scan_points(record: &RunRecord, map: &WorldMap, out: &mut ScanDots) {
    let total: usize = record.scans.iter().map(|r| r.scan.len()).sum();
    let stride = total.div_ceil(MAX_POINTS).max(1);
    let mut skip = stride;
    let mut kinds = PointKinds::new(map);
    let mut trig = BeamTrig::default();
    for r in &record.scans {
        let trig = trig.of(&r.scan);
        let at_odometry = r.frame.carried(r.truth, r.odometry);
        // Each frame's axes once a scan, each beam's angle once: a point is then sums and
        // products.
        let (axes, odometry_axes) = (r.frame.axes(), at_odometry.axes());
        for (i, &beam) in trig.iter().enumerate() {
            let Some(range) = r.scan.range_m(i) else {
                continue;
            };
            // Every `stride`-th returned beam, counted down (no division per beam).
            skip -= 1;
            if skip != 0 {
                continue;
            }
            skip = stride;
            let p = beam_point(&r.frame, axes, beam, range);
            let target = match kinds.of(p) {
                PointKind::Ghost => &mut out.ghosts,
                PointKind::Floor => &mut out.floor,
                PointKind::Surface => &mut out.seen,
            };
            target.add(p[0], p[1]);
            let q = beam_point(&at_odometry, odometry_axes, beam, range);
            out.drifted.add(q[0], q[1]);
        }
    }
}

/// Which half-pixel places of a plan's frame were drawn.
struct HalfPixels {
    min: [i64; 2],
    columns: i64,
    rows: i64,
    bits: Vec<u64>,
}

impl HalfPixels {
    fn new(plan: &Plan) -> Self {
        let min = [
            (plan.origin[0] * 2.0).floor() as i64 - 1,
            (plan.origin[1] * 2.0).floor() as i64 - 1,
        ];
        let columns = (plan.width() * 2.0).ceil() as i64 + 4;
        let rows = ((plan.max[1] - plan.min[1]) * plan.scale * 2.0).ceil() as i64 + 4;
        let words = usize::try_from(columns * rows / 64 + 1).unwrap_or(0);
        HalfPixels {
            min,
            columns,
            rows,
            bits: robot::memory::written_zeros(words),
        }
    }

    /// Marks the place; whether it was new (a place outside the frame always is).
    fn insert(&mut self, x: i64, y: i64) -> bool {
        let (c, r) = (x - self.min[0], y - self.min[1]);
        if !(0..self.columns).contains(&c) || !(0..self.rows).contains(&r) {
            return true;
        }
        let k = (r * self.columns + c) as usize;
        let (word, bit) = (k / 64, 1u64 << (k % 64));
        let new = self.bits[word] & bit == 0;
        self.bits[word] |= bit;
        new
    }
}

/// Writes `n` in decimal, as `{}` does, without the formatter's machinery (a picture writes
/// hundreds of thousands of them).
fn push_whole(s: &mut String, n: u64) {
    s.push_str(itoa::Buffer::new().format(n));
}

/// Writes the path data of a dot at half-pixels `(x, y)`: `M{x} {y}h0`, each number written by
/// [`write_halves`], straight into the path data (a picture draws tens of thousands: a buffer of
/// its own copied in, and text checked as UTF-8 dot by dot, took a fifth of the picture's time).
fn push_dot(s: &mut Vec<u8>, x: i64, y: i64) {
    // 'M', two numbers of at most 20 digits, a sign and ".5" each, a space and "h0": written
    // in room made at the end, then cut to what was written.
    let start = s.len();
    s.resize(start + 56, 0);
    let buf = &mut s[start..];
    buf[0] = b'M';
    let mut n = 1 + write_halves(&mut buf[1..], x);
    buf[n] = b' ';
    n += 1;
    n += write_halves(&mut buf[n..], y);
    buf[n..n + 2].copy_from_slice(b"h0");
    n += 2;
    s.truncate(start + n);
}

/// Writes `halves / 2` into `buf` with one decimal only when it is not whole ("12", "12.5");
/// the bytes written.
fn write_halves(buf: &mut [u8], halves: i64) -> usize {
    let mut n = 0;
    if halves < 0 {
        buf[0] = b'-';
        n = 1;
    }
    let mut digits = itoa::Buffer::new();
    let whole = digits.format(halves.unsigned_abs() / 2).as_bytes();
    buf[n..n + whole.len()].copy_from_slice(whole);
    n += whole.len();
    if halves % 2 != 0 {
        buf[n..n + 2].copy_from_slice(b".5");
        n += 2;
    }
    n
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
    fn whole_numbers_and_halves_are_written_as_the_formatter_writes_them() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut values: Vec<i64> =
            vec![0, 1, -1, 2, -2, 9, 10, 19, 20, 99, 100, i64::MAX, i64::MIN];
        values.extend((0..100_000).map(|_| rng.random::<i64>() >> rng.random_range(0..63)));
        for h in values {
            let halves = |h: i64| {
                let mut buf = [0u8; 24];
                let n = write_halves(&mut buf, h);
                String::from_utf8(buf[..n].to_vec()).unwrap()
            };
            let s = halves(h);
            let whole = format!("{}{}", if h < 0 { "-" } else { "" }, h.unsigned_abs() / 2);
            let want = if h % 2 != 0 {
                format!("{whole}.5")
            } else {
                whole
            };
            assert_eq!(s, want, "{h}");
            let mut dot = Vec::new();
            push_dot(&mut dot, h, -h / 3);
            let y = halves(-h / 3);
            assert_eq!(dot, format!("M{s} {y}h0").into_bytes(), "{h}");
            let mut n = String::new();
            push_whole(&mut n, h.unsigned_abs());
            assert_eq!(n, h.unsigned_abs().to_string());
        }
    }
}
