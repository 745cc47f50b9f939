//! `tilted-scan.svg`: one scan of a tilted laser, seen from the side and from above, with the
//! floor hits apart — what the pan-tilt makes the laser see in 3D.
//!
//! The left panel plots each beam's range against its angle in the scan, with the floor's range
//! by trigonometry — a beam at angle `a` in a plane tilted down by `t` from height `h` meets the
//! floor at `h / (cos a · sin t)` — dashed: floor hits lie on the curve, walls and objects in
//! front of the floor below it. The right panel places the points in the world, with the walls.

use super::svg::{path_data, point_colour, wall_colour, xml_escape};
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
    scenario: &str,
) -> std::io::Result<()> {
    std::fs::write(path, render(scan, world, scenario))
}

struct Point {
    angle: f64,
    range: f64,
    xy: [f64; 2],
    colour: &'static str,
}

fn render(r: &ScanRecord, world: &WorldDescription, scenario: &str) -> String {
    let map = WorldMap::new(world);
    let frame = r.frame;
    let (sy, cy) = frame.yaw.sin_cos();
    let points: Vec<Point> = (0..r.scan.len())
        .filter_map(|i| {
            let angle = r.scan.angle(i);
            let range = r.scan.range_m(i)?;
            let p = frame.point(angle, range);
            Some(Point {
                angle,
                range,
                xy: [p[0], p[1]],
                colour: point_colour(PointKind::of(&map, p)),
            })
        })
        .collect();
    let floor_colour = point_colour(PointKind::Floor);
    let floor_hits = points.iter().filter(|p| p.colour == floor_colour).count();

    let (min, max) = world.bounds();
    let k = PANEL / ((max[0] - min[0]).max(max[1] - min[1]) + 1.0);
    let top_height = (max[1] - min[1] + 1.0) * k;
    let side_height = 0.6 * PANEL;
    let width = 2.0 * PANEL + 80.0;
    let body = top_height.max(side_height + 40.0);
    let height = body + 130.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);

    // Range against beam angle, with the floor's range by trigonometry: a beam at angle a in a
    // plane tilted down by t from height h meets the floor at h / (cos a · sin t).
    // The axis reaches the farthest reading and, tilted down, the floor's nearest range (so the
    // dashed curve the title announces is in the picture), at most 16 m.
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
    let (x0, y0) = (50.0, 40.0 + side_height);
    let ax = |a: f64| x0 + (a.to_degrees() + 90.0) / 180.0 * PANEL;
    let ry = |range: f64| y0 - range.min(r_max) / r_max * side_height;
    let _ = writeln!(
        s,
        r#"<text x="{x0:.0}" y="20">range against beam angle{}</text>"#,
        if frame.tilt < 0.0 {
            "; dashed: the floor by trigonometry"
        } else {
            " (tilted up: no floor in the plane)"
        }
    );
    let mut grid = String::new();
    for deg in [-90, -45, 0, 45, 90] {
        let x = ax(f64::from(deg).to_radians());
        let _ = write!(grid, "M{x:.1} {y0:.1}v6");
        let _ = write!(
            s,
            r##"<text x="{x:.1}" y="{:.1}" text-anchor="middle" fill="#6a6a6a">{deg}°</text>"##,
            y0 + 20.0
        );
    }
    let mut m = 0.0;
    while m <= r_max {
        let y = ry(m);
        let _ = write!(grid, "M{:.1} {y:.1}h-6", x0);
        let _ = write!(
            s,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="end" fill="#6a6a6a">{m:.0} m</text>"##,
            x0 - 9.0,
            y + 4.0
        );
        m += if r_max > 8.0 { 4.0 } else { 2.0 };
    }
    let _ = writeln!(
        s,
        r##"<path d="M{x0:.1} {:.1}V{y0:.1}H{:.1}{grid}" stroke="#6a6a6a" stroke-width="1.2" fill="none"/>"##,
        y0 - side_height,
        x0 + PANEL
    );
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
        let _ = writeln!(
            s,
            r##"<path d="{curve}" stroke="#2ca25f" stroke-width="1.5" stroke-dasharray="5 4" fill="none"/>"##
        );
    }
    for p in &points {
        let _ = write!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="2" fill="{}"/>"#,
            ax(p.angle),
            ry(p.range),
            p.colour
        );
    }
    let _ = writeln!(s);

    // Top view: the points in the world, with the walls.
    let (ox, oy) = (PANEL + 70.0, 30.0);
    let tx = |x: f64| ox + (x - min[0] + 0.5) * k;
    let ty = |y: f64| oy + (max[1] + 0.5 - y) * k;
    let _ = writeln!(s, r#"<text x="{ox:.0}" y="20">top view</text>"#);
    let _ = writeln!(
        s,
        r#"<clipPath id="top"><rect x="{ox:.0}" y="{oy:.0}" width="{PANEL:.0}" height="{top_height:.0}"/></clipPath><g clip-path="url(#top)">"#
    );
    for wall in &world.walls {
        let d = path_data(
            wall.points.iter().map(|p| (tx(p[0]), ty(p[1]))),
            wall.closed,
        );
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{}" stroke-width="4" fill="none"/>"#,
            wall_colour(wall.material)
        );
    }
    for p in &points {
        let _ = write!(
            s,
            r#"<circle cx="{:.1}" cy="{:.1}" r="2" fill="{}"/>"#,
            tx(p.xy[0]),
            ty(p.xy[1]),
            p.colour
        );
    }
    let (hx, hy) = (frame.origin[0] + 0.4 * cy, frame.origin[1] + 0.4 * sy);
    let _ = writeln!(
        s,
        r##"<circle cx="{:.1}" cy="{:.1}" r="5" fill="#d73027"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#d73027" stroke-width="2"/></g>"##,
        tx(frame.origin[0]),
        ty(frame.origin[1]),
        tx(frame.origin[0]),
        ty(frame.origin[1]),
        tx(hx),
        ty(hy)
    );

    // Figures.
    let middle = r.scan.len() / 2;
    let trig = if frame.tilt < 0.0 {
        frame.origin[2] / (-frame.tilt.sin() * r.scan.angle(middle).cos())
    } else {
        f64::INFINITY
    };
    let measured = r
        .scan
        .range_m(middle)
        .map_or("no return".to_string(), |m| format!("{m:.3} m"));
    let y = body + 50.0;
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
    let _ = writeln!(
        s,
        r#"<text x="20" y="{:.0}">middle beam: measured {measured}; {}. {floor_hits} of {} returns on the floor.</text>"#,
        y + 20.0,
        if trig.is_finite() {
            format!("the floor by trigonometry (height / sin tilt) at {trig:.3} m")
        } else {
            "tilted up, the plane never meets the floor".to_string()
        },
        points.len()
    );
    for (i, (colour, label)) in [
        (point_colour(PointKind::Floor), "floor hits"),
        (point_colour(PointKind::Surface), "walls and objects"),
        (point_colour(PointKind::Ghost), "ghosts: no surface there"),
    ]
    .iter()
    .enumerate()
    {
        let x = 20.0 + 200.0 * i as f64;
        let _ = writeln!(
            s,
            r#"<circle cx="{:.0}" cy="{:.0}" r="5" fill="{colour}"/><text x="{:.0}" y="{:.0}">{label}</text>"#,
            x + 5.0,
            y + 41.0,
            x + 16.0,
            y + 46.0
        );
    }
    s.push_str("</svg>\n");
    s
}
