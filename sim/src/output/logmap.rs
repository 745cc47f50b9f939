//! The picture `twin map` draws: the same scans placed by odometry (left) and by the scan-matching
//! estimate (right), each as the cells of a 5 cm grid they occupy, with the path on top.
//!
//! A sharper map puts the same wall's points into fewer cells: [`occupied_cells`] counts them.

use super::svg::{path_data, xml_escape};
use robot::Pose2;
use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::Path;

/// Side of a map cell, metres.
pub const CELL_M: f64 = 0.05;
/// Width of each panel, pixels.
const PANEL: f64 = 900.0;

/// One panel: a title, the point map and the path.
pub struct Panel<'a> {
    /// The caption.
    pub title: String,
    /// The points, map frame.
    pub points: &'a [[f64; 2]],
    /// The base's path, map frame.
    pub path: &'a [Pose2],
}

/// The cells of a `CELL_M` grid that hold at least one point.
pub fn occupied_cells(points: &[[f64; 2]]) -> HashSet<(i64, i64)> {
    points
        .iter()
        .map(|p| {
            (
                (p[0] / CELL_M).floor() as i64,
                (p[1] / CELL_M).floor() as i64,
            )
        })
        .collect()
}

/// Writes the panels side by side, on one common scale.
pub fn write_log_map_svg(path: &Path, panels: &[Panel<'_>]) -> std::io::Result<()> {
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for panel in panels {
        for p in panel.points {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
    }
    if !min[0].is_finite() {
        (min, max) = ([-1.0, -1.0], [1.0, 1.0]);
    }
    let span = (max[0] - min[0]).max(max[1] - min[1]).max(1.0);
    let scale = (PANEL - 20.0) / span;
    let height = (max[1] - min[1]) * scale + 80.0;
    let width = PANEL * panels.len() as f64;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="15">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let cell = (CELL_M * scale).max(0.6);
    for (k, panel) in panels.iter().enumerate() {
        let x0 = PANEL * k as f64 + 10.0;
        let px = |x: f64| x0 + (x - min[0]) * scale;
        let py = |y: f64| 40.0 + (max[1] - y) * scale;
        let mut cells: Vec<(i64, i64)> = occupied_cells(panel.points).into_iter().collect();
        cells.sort_unstable();
        let mut d = String::new();
        for (i, j) in &cells {
            let _ = write!(
                d,
                "M{:.1} {:.1}h{cell:.1}v{cell:.1}h-{cell:.1}z",
                px(*i as f64 * CELL_M),
                py((*j + 1) as f64 * CELL_M)
            );
        }
        let _ = writeln!(s, r##"<path d="{d}" fill="#1f3b73"/>"##);
        let line = path_data(panel.path.iter().map(|p| (px(p.x), py(p.y))), false);
        let _ = writeln!(
            s,
            r##"<path d="{line}" stroke="#d73027" stroke-width="1.2" fill="none" opacity="0.8"/>"##
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.0}" y="24">{} — {} cells of {:.0} cm occupied</text>"#,
            x0,
            xml_escape(&panel.title),
            cells.len(),
            CELL_M * 100.0
        );
    }
    let bar = 10.0 * scale;
    let _ = writeln!(
        s,
        r#"<line x1="12" y1="{y:.0}" x2="{:.0}" y2="{y:.0}" stroke="black" stroke-width="3"/><text x="12" y="{:.0}">10 m</text>"#,
        12.0 + bar,
        height - 22.0,
        y = height - 12.0
    );
    s.push_str("</svg>\n");
    std::fs::write(path, s)
}
