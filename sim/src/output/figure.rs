//! What every SVG picture of the twin shares: layers that carry their legend key, a legend that
//! lists exactly the layers drawn (with a swatch drawn the way the layer is), a grid in metres
//! and a scale bar.
//!
//! Each drawn layer is a `<g data-layer="KEY">`, each legend entry a `<g data-legend="KEY">`: a
//! picture test reads both back and requires the two sets to be equal, and every drawn element
//! to lie inside the canvas.

use std::fmt::Write as _;

/// The colour of the marks of points beyond a view.
pub const BEYOND: &str = "#7a7a7a";

/// How a legend entry shows its layer.
#[derive(Clone, Debug)]
pub enum Swatch {
    /// A line of this colour and width, dashed with this SVG dash array if any.
    Line(&'static str, f64, Option<&'static str>),
    /// Round dots of this colour.
    Dots(&'static str),
    /// A filled, outlined area (sonar wedges, grid cells).
    Area(&'static str, &'static str),
    /// A marker: a circle outline with a heading tick.
    Pose(&'static str),
    /// A marker: a filled square.
    Square(&'static str),
}

/// One legend entry.
#[derive(Clone, Debug)]
struct Entry {
    key: String,
    label: String,
    swatch: Swatch,
}

/// A picture's drawn layers and their legend.
#[derive(Default)]
pub struct Layers {
    body: String,
    legend: Vec<Entry>,
}

/// The opening of a picture `width` × `height` pixels in `font_size`-pixel sans-serif, on
/// white: the `<svg>` element and its background.
pub fn open_svg(width: f64, height: f64, font_size: u32) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{height:.0}\" viewBox=\"0 0 {width:.0} {height:.0}\" font-family=\"sans-serif\" font-size=\"{font_size}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    )
}

impl Layers {
    /// Adds a layer with its legend entry; an empty `body` draws nothing and lists nothing.
    pub fn add(&mut self, key: &str, label: impl Into<String>, swatch: Swatch, body: &str) {
        if body.trim().is_empty() {
            return;
        }
        self.body.reserve(body.len() + key.len() + 24);
        let _ = writeln!(self.body, r#"<g data-layer="{key}">{body}</g>"#);
        if !self.legend.iter().any(|e| e.key == key) {
            self.legend.push(Entry {
                key: key.to_string(),
                label: label.into(),
                swatch,
            });
        }
    }

    /// Adds the marks of `count` points that fell beyond a view (path data `d` of zero-length
    /// segments at its edge), listed as "N points beyond …" (`noun`: "point", "reading"; `view`:
    /// which view).
    pub fn add_beyond(&mut self, count: usize, noun: &str, view: &str, d: &str, width: f64) {
        if count == 0 || d.is_empty() {
            return;
        }
        let plural = if count == 1 { "" } else { "s" };
        self.add(
            "beyond",
            format!("{count} {noun}{plural} beyond {view}, at its edge"),
            Swatch::Dots(BEYOND),
            &format!(
                r#"<path d="{d}" stroke="{BEYOND}" stroke-width="{width}" stroke-linecap="square" fill="none"/>"#
            ),
        );
    }

    /// Adds drawing that needs no legend entry (grids, axes, captions).
    pub fn plain(&mut self, body: &str) {
        self.body.push_str(body);
    }

    /// The drawn layers.
    pub fn body(&self) -> &str {
        &self.body
    }

    /// Legend entries.
    pub fn len(&self) -> usize {
        self.legend.len()
    }

    /// Whether nothing was drawn.
    pub fn is_empty(&self) -> bool {
        self.legend.is_empty()
    }

    /// The width a legend column needs for its longest label at the pictures' 13-pixel
    /// sans-serif (about 7 pixels a character, after the 30-pixel swatch), at least `least`.
    pub fn column_width(&self, least: f64) -> f64 {
        let longest = self
            .legend
            .iter()
            .map(|e| e.label.chars().count())
            .max()
            .unwrap_or(0);
        least.max(36.0 + 7.0 * longest as f64)
    }

    /// Rows the legend takes in `columns` columns.
    pub fn rows(&self, columns: usize) -> usize {
        self.legend.len().div_ceil(columns.max(1))
    }

    /// The legend at `(x, y)` (top left), `columns` columns of `column_width` pixels, rows 20
    /// pixels apart.
    pub fn legend(&self, x: f64, y: f64, columns: usize, column_width: f64) -> String {
        let columns = columns.max(1);
        let mut s = String::new();
        for (i, e) in self.legend.iter().enumerate() {
            let ex = x + column_width * (i % columns) as f64;
            let ey = y + 20.0 * (i / columns) as f64;
            let swatch = match &e.swatch {
                Swatch::Line(colour, width, dash) => format!(
                    r#"<line x1="{ex:.0}" y1="{:.0}" x2="{:.0}" y2="{:.0}" stroke="{colour}" stroke-width="{width}"{}/>"#,
                    ey + 3.0,
                    ex + 24.0,
                    ey + 3.0,
                    dash.map_or(String::new(), |d| format!(r#" stroke-dasharray="{d}""#))
                ),
                Swatch::Dots(colour) => format!(
                    r#"<circle cx="{:.0}" cy="{:.0}" r="2.5" fill="{colour}"/><circle cx="{:.0}" cy="{:.0}" r="2.5" fill="{colour}"/><circle cx="{:.0}" cy="{:.0}" r="2.5" fill="{colour}"/>"#,
                    ex + 4.0,
                    ey + 3.0,
                    ex + 12.0,
                    ey + 3.0,
                    ex + 20.0,
                    ey + 3.0
                ),
                Swatch::Area(fill, stroke) => format!(
                    r#"<rect x="{ex:.0}" y="{:.0}" width="24" height="10" fill="{fill}" fill-opacity="0.4" stroke="{stroke}"/>"#,
                    ey - 2.0
                ),
                Swatch::Pose(colour) => format!(
                    r#"<circle cx="{:.0}" cy="{:.0}" r="5" fill="none" stroke="{colour}" stroke-width="2"/><line x1="{:.0}" y1="{:.0}" x2="{:.0}" y2="{:.0}" stroke="{colour}" stroke-width="2"/>"#,
                    ex + 8.0,
                    ey + 3.0,
                    ex + 8.0,
                    ey + 3.0,
                    ex + 20.0,
                    ey + 3.0
                ),
                Swatch::Square(colour) => format!(
                    r#"<rect x="{:.0}" y="{:.0}" width="10" height="10" fill="{colour}"/>"#,
                    ex + 7.0,
                    ey - 2.0
                ),
            };
            let _ = writeln!(
                s,
                r#"<g data-legend="{}">{swatch}<text x="{:.0}" y="{:.0}">{}</text></g>"#,
                e.key,
                ex + 30.0,
                ey + 7.0,
                xml_escape(&e.label)
            );
        }
        s
    }
}

/// Text safe inside SVG markup.
pub fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A good grid step for `span` metres shown over `pixels`: 1, 2 or 5 × 10ⁿ metres, lines at
/// least 40 pixels apart.
pub fn grid_step(span: f64, pixels: f64) -> f64 {
    let per_pixel = span.max(1e-9) / pixels.max(1.0);
    let least = 40.0 * per_pixel;
    let decade = 10f64.powf(least.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|&s| s >= least)
        .unwrap_or(10.0 * decade)
}

/// The decimals a label of a multiple of `step` needs (1, 2 or 5 × 10ⁿ m): none for a metre
/// and more, one for 0.1–0.5 m, two for 0.01–0.05 m.
fn decimals_of(step: f64) -> usize {
    (-(step.log10() + 1e-9).floor()).max(0.0) as usize
}

/// The smallest and largest coordinates of the finite `points`, or a 2 m square around the
/// origin when none is finite: the extent a plan view is fitted to.
pub fn extent(points: impl IntoIterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        if p[0].is_finite() && p[1].is_finite() {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
    }
    if min[0].is_finite() {
        (min, max)
    } else {
        ([-1.0, -1.0], [1.0, 1.0])
    }
}

/// A plan view's mapping from metres to pixels: `min`..`max` (metres) drawn in the rectangle at
/// `origin` (pixels, top left) at `scale` pixels per metre, y up.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    /// Lower-left corner of the view, metres.
    pub min: [f64; 2],
    /// Upper-right corner, metres.
    pub max: [f64; 2],
    /// Top-left corner of the view on the canvas, pixels.
    pub origin: [f64; 2],
    /// Pixels per metre.
    pub scale: f64,
}

impl Plan {
    /// Pixel x of `x` metres.
    pub fn x(&self, x: f64) -> f64 {
        self.origin[0] + (x - self.min[0]) * self.scale
    }

    /// Pixel y of `y` metres.
    pub fn y(&self, y: f64) -> f64 {
        self.origin[1] + (self.max[1] - y) * self.scale
    }

    /// Width of the view, pixels.
    pub fn width(&self) -> f64 {
        (self.max[0] - self.min[0]) * self.scale
    }

    /// Height of the view, pixels.
    pub fn height(&self) -> f64 {
        (self.max[1] - self.min[1]) * self.scale
    }

    /// Whether `(x, y)` metres is inside the view.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x.is_finite()
            && y.is_finite()
            && (self.min[0]..=self.max[0]).contains(&x)
            && (self.min[1]..=self.max[1]).contains(&y)
    }

    /// `(x, y)` metres moved onto the view's edge when it lies beyond (where a clipped point is
    /// marked), in pixels.
    pub fn clamped(&self, x: f64, y: f64) -> (f64, f64) {
        let x = if x.is_finite() { x } else { self.max[0] };
        let y = if y.is_finite() { y } else { self.max[1] };
        (
            self.x(x.clamp(self.min[0], self.max[0])),
            self.y(y.clamp(self.min[1], self.max[1])),
        )
    }

    /// Room the grid's labels take left of the view, pixels.
    pub const LEFT: f64 = 34.0;
    /// Room the grid's labels take above the view, pixels.
    pub const ABOVE: f64 = 16.0;
    /// Room the grid's labels take below the view, pixels.
    pub const BELOW: f64 = 28.0;

    /// A light grid in metres over the view with its frame, labelled outside the view (along
    /// the left and bottom edges, in the room [`Plan::LEFT`], [`Plan::ABOVE`] and
    /// [`Plan::BELOW`] name), with the axes' names.
    pub fn grid(&self) -> String {
        let step = grid_step(
            (self.max[0] - self.min[0]).max(self.max[1] - self.min[1]),
            self.width().max(self.height()),
        );
        let mut lines = String::new();
        let mut labels = String::new();
        let decimals = decimals_of(step);
        let label = |v: f64| {
            let v = if v.abs() < step * 1e-6 { 0.0 } else { v };
            format!("{v:.decimals$}")
        };
        let bottom = self.y(self.min[1]);
        let mut gx = (self.min[0] / step).ceil() * step;
        while gx <= self.max[0] + 1e-9 {
            let px = self.x(gx);
            let _ = write!(lines, "M{px:.1} {:.1}V{bottom:.1}", self.origin[1]);
            let _ = write!(
                labels,
                r#"<text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
                bottom + 12.0,
                label(gx)
            );
            gx += step;
        }
        let mut gy = (self.min[1] / step).ceil() * step;
        while gy <= self.max[1] + 1e-9 {
            let py = self.y(gy);
            let _ = write!(
                lines,
                "M{:.1} {py:.1}H{:.1}",
                self.origin[0],
                self.origin[0] + self.width()
            );
            let _ = write!(
                labels,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
                self.origin[0] - 4.0,
                py + 3.5,
                label(gy)
            );
            gy += step;
        }
        format!(
            r##"<path d="{lines}" stroke="#e6e6e6" stroke-width="1" fill="none"/><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#9a9a9a"/><g fill="#6a6a6a" font-size="10">{labels}<text x="{:.1}" y="{:.1}" text-anchor="end">x (m), grid {step} m</text><text x="{:.1}" y="{:.1}" text-anchor="end">y (m)</text></g>"##,
            self.origin[0],
            self.origin[1],
            self.width(),
            self.height(),
            self.origin[0] + self.width(),
            bottom + 24.0,
            self.origin[0] - 4.0,
            self.origin[1] - 5.0,
        )
    }

    /// A scale bar of a round length (1, 2 or 5 × 10ⁿ m, 50 to 125 pixels long) with its label,
    /// its right end at `(right, y)` pixels.
    pub fn scale_bar(&self, right: f64, y: f64) -> String {
        let target = 125.0 / self.scale;
        let decade = 10f64.powf(target.log10().floor());
        let metres = [5.0, 2.0, 1.0]
            .into_iter()
            .map(|m| m * decade)
            .find(|&m| m <= target)
            .unwrap_or(decade);
        let length = metres * self.scale;
        let left = right - length;
        let shown = if metres >= 1.0 {
            format!("{metres:.0} m")
        } else if metres >= 0.01 {
            format!("{:.0} cm", metres * 100.0)
        } else {
            format!("{:.0} mm", metres * 1000.0)
        };
        format!(
            r#"<g><line x1="{left:.1}" y1="{y:.1}" x2="{right:.1}" y2="{y:.1}" stroke="black" stroke-width="3"/><line x1="{left:.1}" y1="{:.1}" x2="{left:.1}" y2="{:.1}" stroke="black"/><line x1="{right:.1}" y1="{:.1}" x2="{right:.1}" y2="{:.1}" stroke="black"/><text x="{:.1}" y="{:.1}" text-anchor="middle">{shown}</text></g>"#,
            y - 5.0,
            y + 5.0,
            y - 5.0,
            y + 5.0,
            (left + right) / 2.0,
            y - 8.0,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_steps_are_round_and_far_enough_apart() {
        assert_eq!(grid_step(20.0, 1200.0), 1.0);
        assert_eq!(grid_step(20.0, 400.0), 2.0);
        assert_eq!(grid_step(200.0, 900.0), 10.0);
        assert_eq!(grid_step(2.0, 900.0), 0.1);
    }

    #[test]
    fn small_grids_and_scale_bars_keep_their_digits() {
        assert_eq!(decimals_of(5.0), 0);
        assert_eq!(decimals_of(1.0), 0);
        assert_eq!(decimals_of(0.5), 1);
        assert_eq!(decimals_of(0.1), 1);
        assert_eq!(decimals_of(0.05), 2);
        assert_eq!(decimals_of(0.01), 2);
        let plan = |scale| Plan {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
            origin: [0.0, 0.0],
            scale,
        };
        // 125 pixels are 5 m, 50 cm, 5 cm and 5 mm at these scales.
        for (scale, label) in [
            (25.0, ">5 m<"),
            (250.0, ">50 cm<"),
            (2500.0, ">5 cm<"),
            (25_000.0, ">5 mm<"),
        ] {
            let bar = plan(scale).scale_bar(200.0, 50.0);
            assert!(bar.contains(label), "{scale}: {bar}");
        }
        let grid = Plan {
            min: [0.0, 0.0],
            max: [0.3, 0.3],
            origin: [40.0, 20.0],
            scale: 2000.0,
        }
        .grid();
        assert!(
            grid.contains(">0.02<") && grid.contains("grid 0.02 m"),
            "{grid}"
        );
    }

    #[test]
    fn an_empty_layer_is_neither_drawn_nor_listed() {
        let mut layers = Layers::default();
        layers.add(
            "a",
            "drawn",
            Swatch::Dots("#000"),
            "<circle cx=\"1\" cy=\"1\" r=\"1\"/>",
        );
        layers.add("b", "empty", Swatch::Dots("#000"), "  ");
        assert_eq!(layers.len(), 1);
        assert!(layers.body().contains(r#"data-layer="a""#));
        assert!(!layers.body().contains(r#"data-layer="b""#));
        let legend = layers.legend(0.0, 0.0, 2, 100.0);
        assert!(legend.contains(r#"data-legend="a""#) && !legend.contains(r#"data-legend="b""#));
    }
}
