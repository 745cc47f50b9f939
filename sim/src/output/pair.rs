//! A picture of one scan pair: the reference scan's points, and the current scan's points
//! placed at several poses (the reference pose of a corrected log, each matcher's answer), each
//! labelled with the share of its points within 5 cm of the reference's surfaces. It shows at a
//! glance whether the scans side with the log's pose or with an answer; where the surfaces both
//! scans see fill only a corner of the overview, a detail view beside it shows them.

use super::figure::{Layers, Plan, Swatch, extent, open_svg, xml_escape};
use robot::Pose2;
use robot::localization::KdTree;
use std::fmt::Write as _;
use std::path::Path;

/// The current scan placed at one pose.
#[derive(Clone, Debug)]
pub struct Placement {
    /// What the pose is (`the log's pose`, a matcher's name).
    pub label: String,
    /// The current laser frame in the reference laser frame.
    pub pose: Pose2,
    /// The share of current points within 5 cm of the reference's surfaces there.
    pub share: f64,
}

const REFERENCE: &str = "#222222";
const COLOURS: [&str; 5] = ["#d73027", "#4575b4", "#1a9850", "#984ea3", "#ff7f00"];
const AREA: &str = "#555555";
/// The picture's width with one view (and at least, with two).
const WIDTH: f64 = 900.0;
/// The square each view is fitted into when the overview and the detail stand side by side.
const VIEW_BOX: f64 = 620.0;
/// The caption of the detail view.
const DETAIL: &str = "detail: where the scans share surfaces (the dashed box)";
/// How near a current point (at any pose drawn) must lie to a reference point for the detail
/// view to count that reference point as part of what the scans share.
const SHARED_M: f64 = 0.05;

/// Writes the picture of `title`'s pair: `reference` points (in the reference laser frame),
/// `current` points (in the current laser frame) at each of `placements` (at most five).
///
/// Where the scans share only a small part of the overview (outliers tens of metres out, a
/// robot facing a box), a detail view beside it shows that part, its area marked on the
/// overview (fitted to the reference points that some current point lies within 5 cm of).
pub fn write_pair_svg(
    path: &Path,
    title: &str,
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    placements: &[Placement],
) -> std::io::Result<()> {
    robot::logs::write_file(path, render(title, reference, current, placements))
}

/// The area of the detail view: the box round the reference points that some current point,
/// at any of the poses drawn, lies within 5 cm of (the part of the scene both scans see), the
/// extreme 1 % on each axis left out and a margin added. `None` when fewer than five
/// reference points are shared, or when the box is over half the overview's `span` (the
/// overview shows it well enough).
fn detail_area(
    reference: &[[f64; 2]],
    placed: &[Vec<[f64; 2]>],
    span: f64,
) -> Option<([f64; 2], [f64; 2])> {
    let all: Vec<[f64; 2]> = placed
        .iter()
        .flatten()
        .copied()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .collect();
    let tree = KdTree::new(&all);
    let shared: Vec<[f64; 2]> = reference
        .iter()
        .copied()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .filter(|p| {
            tree.nearest(*p)
                .is_some_and(|(_, d2)| d2 <= SHARED_M * SHARED_M)
        })
        .collect();
    if shared.len() < 5 {
        return None;
    }
    let mut min = [0.0; 2];
    let mut max = [0.0; 2];
    for k in 0..2 {
        let mut values: Vec<f64> = shared.iter().map(|p| p[k]).collect();
        values.sort_by(f64::total_cmp);
        let cut = values.len() / 100;
        (min[k], max[k]) = (values[cut], values[values.len() - 1 - cut]);
    }
    let larger = (max[0] - min[0]).max(max[1] - min[1]);
    let margin = 0.1 * larger + 0.2;
    let (min, max) = (
        [min[0] - margin, min[1] - margin],
        [max[0] + margin, max[1] + margin],
    );
    ((max[0] - min[0]).max(max[1] - min[1]) <= 0.5 * span).then_some((min, max))
}

/// The plan view of `min`..`max` fitted into a `size`-pixel square whose view starts at
/// `(left, top)` pixels (its grid's labels to the left of and above that).
fn fitted(min: [f64; 2], max: [f64; 2], (left, top): (f64, f64), size: f64) -> Plan {
    let span = (max[0] - min[0]).max(max[1] - min[1]).max(1e-3);
    Plan {
        min,
        max,
        origin: [left, top],
        scale: size / span,
    }
}

fn render(
    title: &str,
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    placements: &[Placement],
) -> String {
    let placed: Vec<Vec<[f64; 2]>> = placements
        .iter()
        .take(COLOURS.len())
        .map(|p| {
            current
                .iter()
                .map(|q| {
                    let (x, y) = p.pose.transform_point(q[0], q[1]);
                    [x, y]
                })
                .collect()
        })
        .collect();
    let (min, max) = extent(reference.iter().chain(placed.iter().flatten()).copied());
    let margin = 0.3;
    let (min, max) = (
        [min[0] - margin, min[1] - margin],
        [max[0] + margin, max[1] + margin],
    );
    let span = (max[0] - min[0]).max(max[1] - min[1]).max(1.0);
    let detail = detail_area(reference, &placed, span);
    let mut views = Vec::new();
    let width = match detail {
        Some((dmin, dmax)) => {
            // Below the title and the views' captions.
            let top = 56.0 + Plan::ABOVE;
            let overview = fitted(min, max, (Plan::LEFT + 10.0, top), VIEW_BOX);
            let left = overview.origin[0] + overview.width() + 50.0 + Plan::LEFT;
            let detail = fitted(dmin, dmax, (left, top), VIEW_BOX);
            views.push(("overview", overview));
            views.push((DETAIL, detail));
            // Room for the detail's caption too (at most 9 pixels a character at 15 pixels).
            let caption = left + 9.0 * DETAIL.chars().count() as f64;
            (left + detail.width() + 30.0).max(caption).max(WIDTH)
        }
        None => {
            let inner = WIDTH - Plan::LEFT - 30.0;
            let top = 40.0 + Plan::ABOVE;
            views.push(("", fitted(min, max, (Plan::LEFT + 10.0, top), inner)));
            WIDTH
        }
    };
    let mut layers = Layers::default();
    layers.plain(&format!(
        r#"<text x="{:.0}" y="24">{}</text>"#,
        Plan::LEFT + 10.0,
        xml_escape(title)
    ));
    for (caption, plan) in &views {
        layers.plain(&plan.grid());
        if !caption.is_empty() {
            layers.plain(&format!(
                r#"<text x="{:.0}" y="46" fill="{AREA}">{}</text>"#,
                plan.origin[0],
                xml_escape(caption)
            ));
        }
        let dots = |points: &[[f64; 2]], colour: &str, r: f64| {
            let mut body = String::new();
            for p in points.iter().filter(|p| plan.contains(p[0], p[1])) {
                let _ = write!(
                    body,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="{r}" fill="{colour}"/>"#,
                    plan.x(p[0]),
                    plan.y(p[1])
                );
            }
            body
        };
        layers.add(
            "reference",
            "reference scan",
            Swatch::Dots(REFERENCE),
            &dots(reference, REFERENCE, 2.2),
        );
        for (k, (placement, points)) in placements.iter().zip(&placed).enumerate() {
            let colour = COLOURS[k];
            layers.add(
                &format!("placed-{k}"),
                format!(
                    "current scan at {}: {:.0} % within 5 cm",
                    placement.label,
                    placement.share * 100.0
                ),
                Swatch::Dots(colour),
                &dots(points, colour, 1.6),
            );
        }
    }
    if let (Some((dmin, dmax)), Some((_, overview))) = (detail, views.first()) {
        let (x0, y0) = (overview.x(dmin[0]), overview.y(dmax[1]));
        let (x1, y1) = (overview.x(dmax[0]), overview.y(dmin[1]));
        layers.add(
            "detail-area",
            "the area of the detail view",
            Swatch::Line(AREA, 1.2, Some("5 3")),
            &format!(
                r#"<rect x="{x0:.1}" y="{y0:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="{AREA}" stroke-width="1.2" stroke-dasharray="5 3"/>"#,
                x1 - x0,
                y1 - y0
            ),
        );
    }
    let bottom = views
        .iter()
        .map(|(_, plan)| plan.origin[1] + plan.height() + Plan::BELOW)
        .fold(0.0, f64::max);
    // One view: its scale bar at the right, beside the legend. Two: each view's under it, and
    // the legend below them (the overview's bar may reach back over the legend's column).
    let legend_top = if detail.is_some() {
        bottom + 40.0
    } else {
        bottom + 18.0
    };
    let rows = layers.rows(1);
    let height = legend_top + 20.0 * rows as f64 + 12.0;
    let mut s = open_svg(width, height, 15);
    s.push_str(layers.body());
    s.push_str(&layers.legend(20.0, legend_top, 1, 600.0));
    for (_, plan) in &views {
        let right = if detail.is_some() {
            plan.origin[0] + plan.width()
        } else {
            width - 30.0
        };
        s.push_str(&plan.scale_bar(right, bottom + 24.0));
    }
    s.push_str("</svg>\n");
    s
}
