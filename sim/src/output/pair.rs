//! A picture of one scan pair: the reference scan's points, and the current scan's points
//! placed at several poses (the reference pose of a corrected log, each matcher's answer), each
//! labelled with the share of its points within 5 cm of the reference's surfaces. It shows at a
//! glance whether the scans side with the log's pose or with an answer.

use super::figure::{Layers, Plan, Swatch, extent, open_svg, xml_escape};
use robot::Pose2;
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
const WIDTH: f64 = 900.0;

/// Writes the picture of `title`'s pair: `reference` points (in the reference laser frame),
/// `current` points (in the current laser frame) at each of `placements` (at most five).
pub fn write_pair_svg(
    path: &Path,
    title: &str,
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    placements: &[Placement],
) -> std::io::Result<()> {
    robot::logs::write_file(path, render(title, reference, current, placements))
}

fn render(
    title: &str,
    reference: &[[f64; 2]],
    current: &[[f64; 2]],
    placements: &[Placement],
) -> String {
    let placed: Vec<Vec<[f64; 2]>> = placements
        .iter()
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
    let inner = WIDTH - Plan::LEFT - 30.0;
    let scale = inner / (max[0] - min[0]).max(max[1] - min[1]).max(1.0);
    let plan = Plan {
        min,
        max,
        origin: [Plan::LEFT + 10.0, 40.0 + Plan::ABOVE],
        scale,
    };
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
    let mut layers = Layers::default();
    layers.plain(&format!(
        r#"<text x="{:.0}" y="24">{}</text>{}"#,
        plan.origin[0],
        xml_escape(title),
        plan.grid()
    ));
    layers.add(
        "reference",
        "reference scan",
        Swatch::Dots(REFERENCE),
        &dots(reference, REFERENCE, 2.2),
    );
    for (k, (placement, points)) in placements
        .iter()
        .zip(&placed)
        .take(COLOURS.len())
        .enumerate()
    {
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
    let bottom = plan.origin[1] + plan.height() + Plan::BELOW;
    let rows = layers.rows(1);
    let height = bottom + 20.0 * rows as f64 + 30.0;
    let mut s = open_svg(WIDTH, height, 15);
    s.push_str(layers.body());
    s.push_str(&layers.legend(20.0, bottom + 18.0, 1, 600.0));
    s.push_str(&plan.scale_bar(WIDTH - 30.0, bottom + 24.0));
    s.push_str("</svg>\n");
    s
}
