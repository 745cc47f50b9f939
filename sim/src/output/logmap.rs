//! The picture `twin map` draws: the same scans placed by odometry (left) and by the scan-matching
//! estimate (right), each as the cells of a 5 cm grid they occupy, with the path on top, a grid
//! in metres, the start, a legend and a scale bar.
//!
//! A sharper map puts the same wall's points into fewer cells: [`occupied_cells`] counts them.

use super::figure::{Layers, Plan, Swatch, extent, open_svg};
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

/// Writes the panels side by side, on one common scale, each with a grid in metres, the path
/// and its start; a legend and a scale bar below.
pub fn write_log_map_svg(path: &Path, panels: &[Panel<'_>]) -> std::io::Result<()> {
    robot::logs::write_file(path, render(panels))
}

const CELLS: &str = "#1f3b73";
const PATH: &str = "#d73027";

fn render(panels: &[Panel<'_>]) -> String {
    let (min, max) = extent(panels.iter().flat_map(|panel| {
        let path = panel.path.iter().map(|p| [p.x, p.y]);
        panel.points.iter().copied().chain(path)
    }));
    let margin = 0.5;
    let span = (max[0] - min[0]).max(max[1] - min[1]).max(1.0) + 2.0 * margin;
    let scale = (PANEL - 30.0 - Plan::LEFT) / span;
    let cell = (CELL_M * scale).max(0.6);
    let mut layers = Layers::default();
    let mut cells_body = String::new();
    let mut path_body = String::new();
    let mut start_body = String::new();
    let mut plans = Vec::new();
    for (k, panel) in panels.iter().enumerate() {
        let plan = Plan {
            min: [min[0] - margin, min[1] - margin],
            max: [max[0] + margin, max[1] + margin],
            origin: [PANEL * k as f64 + 10.0 + Plan::LEFT, 40.0 + Plan::ABOVE],
            scale,
        };
        layers.plain(&format!(
            r#"<text x="{:.0}" y="24">{} — {} cells of {:.0} cm occupied</text>{}"#,
            plan.origin[0],
            xml_escape(&panel.title),
            occupied_cells(panel.points).len(),
            CELL_M * 100.0,
            plan.grid()
        ));
        let mut cells: Vec<(i64, i64)> = occupied_cells(panel.points).into_iter().collect();
        cells.sort_unstable();
        let mut d = String::new();
        for (i, j) in &cells {
            // Cells are drawn inside the view (a cell on its edge is cut to it).
            let (x, y) = plan.clamped(*i as f64 * CELL_M, (*j + 1) as f64 * CELL_M);
            let w = cell.min(plan.origin[0] + plan.width() - x);
            let h = cell.min(plan.origin[1] + plan.height() - y);
            let _ = write!(d, "M{x:.1} {y:.1}h{w:.1}v{h:.1}h-{w:.1}z");
        }
        if !d.is_empty() {
            let _ = write!(cells_body, r#"<path d="{d}" fill="{CELLS}"/>"#);
        }
        if !panel.path.is_empty() {
            let line = path_data(panel.path.iter().map(|p| plan.clamped(p.x, p.y)), false);
            let _ = write!(
                path_body,
                r#"<path d="{line}" stroke="{PATH}" stroke-width="1.2" fill="none" opacity="0.8"/>"#
            );
            let (x, y) = plan.clamped(panel.path[0].x, panel.path[0].y);
            let _ = write!(
                start_body,
                r#"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="black"/>"#,
                x - 5.0,
                y - 5.0
            );
        }
        plans.push(plan);
    }
    layers.add(
        "cells",
        format!("occupied {:.0} cm cells", CELL_M * 100.0),
        Swatch::Square(CELLS),
        &cells_body,
    );
    layers.add(
        "path",
        "the base's path",
        Swatch::Line(PATH, 1.2, None),
        &path_body,
    );
    layers.add("start", "start", Swatch::Square("black"), &start_body);
    let width = PANEL * panels.len().max(1) as f64;
    let bottom = plans
        .first()
        .map_or(60.0, |p| p.origin[1] + p.height() + Plan::BELOW);
    let height = bottom + 44.0;
    let mut s = open_svg(width, height, 15);
    s.push_str(layers.body());
    s.push_str(&layers.legend(20.0, bottom + 18.0, 3, 260.0));
    if let Some(plan) = plans.first() {
        s.push_str(&plan.scale_bar(width - 30.0, bottom + 24.0));
    }
    s.push_str("</svg>\n");
    s
}
