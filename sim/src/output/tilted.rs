//! `tilted-scan.svg`: one scan of a tilted laser, seen from the side and from above, with the
//! floor hits apart — what the pan-tilt makes the laser see in 3D.
//!
//! The left panel plots each beam's range against its angle in the scan, with the floor's range
//! by trigonometry — a beam at angle `a` in a plane tilted down by `t` from height `h` meets the
//! floor at `h / (cos a · sin t)` — dashed: floor hits lie on the curve, walls and objects in
//! front of the floor below it. The right panel places the points in the world, with the walls.
//! Readings beyond either view are marked at its edge and counted in the legend.

use super::figure::{Layers, Plan, Swatch, open_svg};
use super::svg::{draw_walls, point_colour, xml_escape};
use crate::config::WorldDescription;
use crate::record::{RunRecord, ScanRecord};
use crate::world::{PointKind, WorldMap};
use std::fmt::Write as _;
use std::path::Path;

/// A scan counts as tilted beyond this, radians (half a degree).
const TILTED: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// Size of each panel, pixels.
const PANEL: f64 = 460.0;

/// The last scan of the run taken with the scan plane clearly tilted down (5° or more: the
/// picture is about the floor), else the last tilted at all, if any.
pub fn last_tilted(record: &RunRecord) -> Option<&ScanRecord> {
    let mut latest = record.scans.iter().rev();
    let down = latest.clone().find(|r| r.frame.tilt < -(5f64.to_radians()));
    down.or_else(|| latest.find(|r| r.frame.tilt.abs() > TILTED))
}

/// Writes the picture of `scan` in `world`.
pub fn write_tilted_svg(
    path: &Path,
    scan: &ScanRecord,
    world: &WorldDescription,
    map: &WorldMap,
    scenario: &str,
) -> std::io::Result<()> {
    robot::logs::write_file(path, render(scan, world, map, scenario))
}

struct Point {
    angle: f64,
    range: f64,
    xy: [f64; 2],
    kind: PointKind,
}

/// Legend keys and labels of the point kinds.
fn kind_legend(kind: PointKind) -> (&'static str, &'static str) {
    match kind {
        PointKind::Floor => ("floor", "floor hits"),
        PointKind::Surface => ("surface", "walls and objects"),
        PointKind::Ghost => ("ghosts", "ghosts: no surface there"),
    }
}

const KINDS: [PointKind; 3] = [PointKind::Surface, PointKind::Floor, PointKind::Ghost];
const LASER: &str = "#d73027";

fn render(r: &ScanRecord, world: &WorldDescription, map: &WorldMap, scenario: &str) -> String {
    let frame = r.frame;
    let (sy, cy) = frame.yaw.sin_cos();
    let mut kinds = crate::world::PointKinds::new(map);
    let points: Vec<Point> = (0..r.scan.len())
        .filter_map(|i| {
            let angle = r.scan.angle(i);
            let range = r.scan.range_m(i)?;
            let p = frame.point(angle, range);
            Some(Point {
                angle,
                range,
                xy: [p[0], p[1]],
                kind: kinds.of(p),
            })
        })
        .collect();
    let floor_hits = points.iter().filter(|p| p.kind == PointKind::Floor).count();
    let mut layers = Layers::default();
    let mut beyond = String::new();
    let mut beyond_count = 0usize;

    // Left: range against beam angle, with the floor's range by trigonometry: a beam at angle a
    // in a plane tilted down by t from height h meets the floor at h / (cos a · sin t).
    // The axis reaches the farthest reading and, tilted down, the floor's nearest range (so the
    // dashed curve is in the picture), at most 16 m; farther readings are marked at the top.
    let side_height = 0.6 * PANEL;
    let floor_nearest = if frame.tilt < 0.0 {
        frame.origin[2] / (-frame.tilt).sin()
    } else {
        0.0
    };
    let r_max = points
        .iter()
        .map(|p| p.range)
        .fold(1.0f64.max(floor_nearest * 1.05), f64::max)
        .min(16.0)
        .ceil();
    let (x0, y0) = (60.0, 40.0 + side_height);
    let ax = |a: f64| x0 + (a.to_degrees() + 90.0) / 180.0 * PANEL;
    let ry = |range: f64| y0 - range.min(r_max) / r_max * side_height;
    let mut axes = String::new();
    let _ = write!(
        axes,
        r#"<text x="{x0:.0}" y="20">range against beam angle{}</text>"#,
        if frame.tilt < 0.0 {
            ""
        } else {
            " (tilted up: the plane never meets the floor)"
        }
    );
    let mut ticks = String::new();
    for deg in [-90, -45, 0, 45, 90] {
        let x = ax(f64::from(deg).to_radians());
        let _ = write!(ticks, "M{x:.1} {y0:.1}v6");
        let _ = write!(
            axes,
            r##"<text x="{x:.1}" y="{:.1}" text-anchor="middle" fill="#6a6a6a">{deg}°</text>"##,
            y0 + 20.0
        );
    }
    let _ = write!(
        axes,
        r##"<text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#6a6a6a">beam angle in the scan (degrees)</text>"##,
        x0 + PANEL / 2.0,
        y0 + 38.0
    );
    let mut m = 0.0;
    while m <= r_max {
        let y = ry(m);
        let _ = write!(ticks, "M{:.1} {y:.1}h-6", x0);
        let _ = write!(
            axes,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="end" fill="#6a6a6a">{m:.0} m</text>"##,
            x0 - 9.0,
            y + 4.0
        );
        m += if r_max > 8.0 { 4.0 } else { 2.0 };
    }
    let _ = write!(
        axes,
        r##"<text x="14" y="{:.1}" fill="#6a6a6a" transform="rotate(-90 14 {:.1})" text-anchor="middle">range (m)</text>"##,
        y0 - side_height / 2.0,
        y0 - side_height / 2.0
    );
    let _ = write!(
        axes,
        r##"<path d="M{x0:.1} {:.1}V{y0:.1}H{:.1}{ticks}" stroke="#6a6a6a" stroke-width="1.2" fill="none"/>"##,
        y0 - side_height,
        x0 + PANEL
    );
    layers.plain(&axes);
    if frame.tilt < 0.0 {
        let mut curve = String::new();
        let mut pen = false;
        for i in 0..=360 {
            let a = (f64::from(i) / 2.0 - 90.0).to_radians();
            let floor = frame.origin[2] / (a.cos() * -frame.tilt.sin());
            if a.cos() > 1e-9 && floor <= r_max {
                let _ = write!(
                    curve,
                    "{}{:.1} {:.1}",
                    if pen { "L" } else { "M" },
                    ax(a),
                    ry(floor)
                );
                pen = true;
            } else {
                pen = false;
            }
        }
        if !curve.is_empty() {
            layers.add(
                "floor-trig",
                "the floor's range by trigonometry",
                Swatch::Line(point_colour(PointKind::Floor), 1.5, Some("5 4")),
                &format!(
                    r#"<path d="{curve}" stroke="{}" stroke-width="1.5" stroke-dasharray="5 4" fill="none"/>"#,
                    point_colour(PointKind::Floor)
                ),
            );
        }
    }
    let mut side: [String; 3] = Default::default();
    for p in &points {
        let k = KINDS.iter().position(|&k| k == p.kind).unwrap_or(0);
        if p.range > r_max {
            beyond_count += 1;
            let _ = write!(beyond, "M{:.1} {:.1}h0", ax(p.angle), ry(r_max));
        } else {
            let _ = write!(side[k], "M{:.1} {:.1}h0", ax(p.angle), ry(p.range));
        }
    }

    // Right: top view, the points in the world with the walls.
    let (min, max) = world.bounds();
    let k = PANEL / ((max[0] - min[0]).max(max[1] - min[1]) + 1.0);
    let plan = Plan {
        min: [min[0] - 0.5, min[1] - 0.5],
        max: [max[0] + 0.5, max[1] + 0.5],
        origin: [PANEL + 100.0 + Plan::LEFT, 30.0 + Plan::ABOVE],
        scale: k,
    };
    layers.plain(&format!(
        r#"<text x="{:.0}" y="20">top view</text>{}"#,
        plan.origin[0],
        plan.grid()
    ));
    draw_walls(&mut layers, &plan, world, 4.0);
    let mut top: [String; 3] = Default::default();
    for p in &points {
        let k = KINDS.iter().position(|&k| k == p.kind).unwrap_or(0);
        if plan.contains(p.xy[0], p.xy[1]) {
            let _ = write!(top[k], "M{:.1} {:.1}h0", plan.x(p.xy[0]), plan.y(p.xy[1]));
        } else {
            beyond_count += 1;
            let (x, y) = plan.clamped(p.xy[0], p.xy[1]);
            let _ = write!(beyond, "M{x:.1} {y:.1}h0");
        }
    }
    for (i, kind) in KINDS.iter().enumerate() {
        let colour = point_colour(*kind);
        let (key, label) = kind_legend(*kind);
        let mut body = String::new();
        for d in [&side[i], &top[i]] {
            if !d.is_empty() {
                let _ = write!(
                    body,
                    r#"<path d="{d}" stroke="{colour}" stroke-width="4" stroke-linecap="round" fill="none"/>"#
                );
            }
        }
        layers.add(key, label, Swatch::Dots(colour), &body);
    }
    layers.add_beyond(beyond_count, "reading", "a view", &beyond, 4.0);
    let (hx, hy) = (frame.origin[0] + 0.4 * cy, frame.origin[1] + 0.4 * sy);
    let (lx, ly) = plan.clamped(frame.origin[0], frame.origin[1]);
    let (hx, hy) = plan.clamped(hx, hy);
    layers.add(
        "laser",
        "the laser, looking along the tick",
        Swatch::Pose(LASER),
        &format!(
            r#"<circle cx="{lx:.1}" cy="{ly:.1}" r="5" fill="none" stroke="{LASER}" stroke-width="2"/><line x1="{lx:.1}" y1="{ly:.1}" x2="{hx:.1}" y2="{hy:.1}" stroke="{LASER}" stroke-width="2"/>"#
        ),
    );

    // Figures, legend and scale bar below both panels.
    let width = plan.origin[0] + plan.width() + 20.0;
    let body = (plan.origin[1] + plan.height() + Plan::BELOW).max(y0 + 44.0);
    let legend_top = body + 70.0;
    let columns = 3;
    let height = legend_top + 20.0 * layers.rows(columns) as f64 + 12.0;
    let mut s = open_svg(width, height, 13);
    s.push_str(layers.body());
    let middle = r.scan.len() / 2;
    let measured = r
        .scan
        .range_m(middle)
        .map_or("no return".to_string(), |m| format!("{m:.3} m"));
    let y = body + 24.0;
    let _ = writeln!(
        s,
        r#"<text x="20" y="{y:.0}">{}: scan at t = {:.2} s, laser {:.3} m above the floor, tilted {:.2}°, panned {:.1}° from the base</text>"#,
        xml_escape(scenario),
        r.scan.stamp.secs_f64(),
        frame.origin[2],
        frame.tilt.to_degrees(),
        crate::devices::laser::LaserFrame::mount_on(&frame, r.truth)
            .theta
            .to_degrees(),
    );
    let trig = if frame.tilt < 0.0 {
        let range = frame.origin[2] / (-frame.tilt.sin() * r.scan.angle(middle).cos());
        if range.is_finite() && range < 1000.0 {
            format!("the floor by trigonometry (height / sin tilt) {range:.3} m away")
        } else {
            "tilted so little that the plane meets the floor only beyond a kilometre".to_string()
        }
    } else {
        "tilted up, the plane never meets the floor".to_string()
    };
    let _ = writeln!(
        s,
        r#"<text x="20" y="{:.0}">middle beam: measured {measured}; {trig}. {floor_hits} of {} returns on the floor.</text>"#,
        y + 20.0,
        points.len()
    );
    s.push_str(&layers.legend(20.0, legend_top, columns, 300.0));
    s.push_str(&plan.scale_bar(width - 24.0, legend_top + 4.0));
    s.push_str("</svg>\n");
    s
}
