//! A reader of the twin's SVG pictures for the picture tests: the canvas, every drawn element's
//! extent (paths, circles, lines, rectangles, text at an estimated width), the drawn layers
//! (`data-layer`) and the legend's entries (`data-legend`).
#![allow(dead_code)]

use std::collections::BTreeSet;

/// One element's extent on the canvas, pixels.
#[derive(Clone, Debug)]
pub struct Extent {
    pub tag: String,
    pub min: [f64; 2],
    pub max: [f64; 2],
    /// The element as written (shortened), for messages.
    pub text: String,
}

/// What a picture test reads from an SVG.
#[derive(Debug, Default)]
pub struct Picture {
    pub width: f64,
    pub height: f64,
    pub extents: Vec<Extent>,
    pub layers: Vec<String>,
    pub legend: Vec<String>,
    /// Layers that hold no drawn element.
    pub empty_layers: Vec<String>,
}

fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let at = tag.find(&key)? + key.len();
    let end = tag[at..].find('"')? + at;
    Some(&tag[at..end])
}

fn num(tag: &str, name: &str) -> Option<f64> {
    attr(tag, name)?.parse().ok()
}

/// The points a path's data passes through (absolute; `M L H V h v l m Z`, `A` by its end).
fn path_points(d: &str) -> Vec<[f64; 2]> {
    let mut tokens = Vec::new();
    let mut number = String::new();
    let flush = |number: &mut String, tokens: &mut Vec<Result<char, f64>>| {
        if !number.is_empty() {
            tokens.push(Err(number.parse::<f64>().unwrap_or(f64::NAN)));
            number.clear();
        }
    };
    for c in d.chars() {
        if c.is_ascii_alphabetic() && c != 'e' {
            flush(&mut number, &mut tokens);
            tokens.push(Ok(c));
        } else if c == ',' || c.is_whitespace() {
            flush(&mut number, &mut tokens);
        } else if c == '-' && !number.is_empty() && !number.ends_with('e') {
            flush(&mut number, &mut tokens);
            number.push(c);
        } else {
            number.push(c);
        }
    }
    flush(&mut number, &mut tokens);
    let mut points = Vec::new();
    let (mut x, mut y) = (0.0, 0.0);
    let mut command = 'M';
    let mut args: Vec<f64> = Vec::new();
    let arity = |c: char| match c.to_ascii_uppercase() {
        'M' | 'L' => 2,
        'H' | 'V' => 1,
        'A' => 7,
        _ => 0,
    };
    for t in tokens {
        match t {
            Ok(c) => {
                command = c;
                args.clear();
                if c.eq_ignore_ascii_case(&'z') {
                    continue;
                }
            }
            Err(v) => {
                args.push(v);
                if args.len() == arity(command) {
                    match command {
                        'M' | 'L' => (x, y) = (args[0], args[1]),
                        'm' | 'l' => (x, y) = (x + args[0], y + args[1]),
                        'H' => x = args[0],
                        'h' => x += args[0],
                        'V' => y = args[0],
                        'v' => y += args[0],
                        'A' => (x, y) = (args[5], args[6]),
                        'a' => (x, y) = (x + args[5], y + args[6]),
                        _ => {}
                    }
                    points.push([x, y]);
                    args.clear();
                }
            }
        }
    }
    points
}

/// A group's `transform` of the form `translate(x y) scale(s)` (either part may be missing):
/// the scale and the shift. Any other transform on a group is not drawn by the twin.
fn placement(transform: &str) -> (f64, [f64; 2]) {
    let args = |name: &str| -> Option<Vec<f64>> {
        let at = transform.find(&format!("{name}("))? + name.len() + 1;
        let end = transform[at..].find(')')? + at;
        Some(
            transform[at..end]
                .split([' ', ','])
                .filter(|v| !v.is_empty())
                .map(|v| v.parse().expect("a number in a transform"))
                .collect(),
        )
    };
    assert!(
        transform
            .split(')')
            .map(str::trim)
            .filter(|part| !part.is_empty())
            .all(|part| part.starts_with("translate(") || part.starts_with("scale(")),
        "a group transform other than translate and scale: {transform}"
    );
    let shift = args("translate").map_or([0.0, 0.0], |t| [t[0], t.get(1).copied().unwrap_or(0.0)]);
    let scale = args("scale").map_or(1.0, |s| s[0]);
    (scale, shift)
}

/// Reads `svg`.
pub fn read(svg: &str) -> Picture {
    let mut picture = Picture::default();
    let mut fonts: Vec<f64> = Vec::new();
    // Open `<g data-layer>` groups and whether they drew anything.
    let mut groups: Vec<Option<(String, bool)>> = Vec::new();
    // Each open group's placement of what it holds: a point `p` lands at `scale × p + shift`.
    let mut placements: Vec<(f64, [f64; 2])> = vec![(1.0, [0.0, 0.0])];
    let mut rest = svg;
    while let Some(open) = rest.find('<') {
        let close = rest[open..].find('>').expect("a closed tag") + open;
        let tag = &rest[open..=close];
        let after = &rest[close + 1..];
        rest = after;
        let name: String = tag[1..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '/')
            .collect();
        let self_closing = tag.ends_with("/>");
        match name.as_str() {
            "svg" => {
                picture.width = num(tag, "width").expect("svg width");
                picture.height = num(tag, "height").expect("svg height");
                fonts.push(num(tag, "font-size").unwrap_or(16.0));
                continue;
            }
            "g" => {
                fonts.push(num(tag, "font-size").unwrap_or(*fonts.last().unwrap_or(&16.0)));
                let layer = attr(tag, "data-layer").map(|k| (k.to_string(), false));
                if let Some((k, _)) = &layer {
                    picture.layers.push(k.clone());
                }
                if let Some(k) = attr(tag, "data-legend") {
                    picture.legend.push(k.to_string());
                }
                groups.push(layer);
                let (scale, shift) = *placements.last().expect("the canvas's placement");
                let (s, t) = attr(tag, "transform").map_or((1.0, [0.0, 0.0]), placement);
                placements.push((
                    scale * s,
                    [scale * t[0] + shift[0], scale * t[1] + shift[1]],
                ));
                continue;
            }
            "/g" => {
                fonts.pop();
                placements.pop();
                if let Some(Some((key, drew))) = groups.pop()
                    && !drew
                {
                    picture.empty_layers.push(key);
                }
                continue;
            }
            _ => {}
        }
        let font = num(tag, "font-size").unwrap_or(*fonts.last().unwrap_or(&16.0));
        let extent = match name.as_str() {
            "path" => {
                let points = path_points(attr(tag, "d").unwrap_or(""));
                if points.is_empty() {
                    None
                } else {
                    let mut min = [f64::INFINITY; 2];
                    let mut max = [f64::NEG_INFINITY; 2];
                    for p in points {
                        for k in 0..2 {
                            min[k] = min[k].min(p[k]);
                            max[k] = max[k].max(p[k]);
                        }
                    }
                    Some((min, max))
                }
            }
            "circle" => {
                let (x, y, r) = (
                    num(tag, "cx").unwrap(),
                    num(tag, "cy").unwrap(),
                    num(tag, "r").unwrap(),
                );
                Some(([x - r, y - r], [x + r, y + r]))
            }
            "line" => {
                let (x1, y1, x2, y2) = (
                    num(tag, "x1").unwrap(),
                    num(tag, "y1").unwrap(),
                    num(tag, "x2").unwrap(),
                    num(tag, "y2").unwrap(),
                );
                Some(([x1.min(x2), y1.min(y2)], [x1.max(x2), y1.max(y2)]))
            }
            "rect" if attr(tag, "width") != Some("100%") && !tag.contains("clipPath") => {
                let (x, y) = (num(tag, "x").unwrap_or(0.0), num(tag, "y").unwrap_or(0.0));
                let (w, h) = (num(tag, "width").unwrap(), num(tag, "height").unwrap());
                Some(([x, y], [x + w, y + h]))
            }
            "text" => {
                let end = after.find("</text>").expect("closed text");
                let content = after[..end]
                    .replace("&amp;", "&")
                    .replace("&lt;", "<")
                    .replace("&gt;", ">");
                // Sans-serif averages about 0.55 em per character: 0.6 errs wide.
                let w = 0.6 * font * content.chars().count() as f64;
                let (x, y) = (num(tag, "x").unwrap(), num(tag, "y").unwrap());
                let left = match attr(tag, "text-anchor") {
                    Some("middle") => x - w / 2.0,
                    Some("end") => x - w,
                    _ => x,
                };
                if attr(tag, "transform").is_some_and(|t| t.starts_with("rotate(-90")) {
                    // Rotated a quarter turn about (x, y): an offset (dx, dy) lands at (dy, -dx).
                    let (a0, a1) = (left - x, left - x + w);
                    Some(([x - font * 0.8, y - a1], [x + font * 0.25, y - a0]))
                } else {
                    Some(([left, y - font * 0.8], [left + w, y + font * 0.25]))
                }
            }
            _ => None,
        };
        // Placed by the groups it is in.
        let extent = extent.map(|(min, max)| {
            let (scale, shift) = *placements.last().expect("the canvas's placement");
            let at = |p: [f64; 2]| [scale * p[0] + shift[0], scale * p[1] + shift[1]];
            (at(min), at(max))
        });
        if let Some((min, max)) = extent {
            if let Some(Some((_, drew))) = groups.iter_mut().rev().find(|g| g.is_some()) {
                *drew = true;
            }
            let shown: String = tag.chars().take(140).collect();
            picture.extents.push(Extent {
                tag: name.clone(),
                min,
                max,
                text: shown,
            });
        }
        let _ = self_closing;
    }
    picture
}

/// What is wrong with a picture: elements outside the canvas (or not finite), layers without a
/// legend entry, legend entries without a layer, empty layers, "inf" or "NaN" written.
pub fn problems(svg: &str) -> Vec<String> {
    let p = read(svg);
    let mut out = Vec::new();
    if !(p.width > 0.0 && p.height > 0.0) {
        out.push(format!("no canvas: {} × {}", p.width, p.height));
    }
    let outside: Vec<&Extent> = p
        .extents
        .iter()
        .filter(|e| {
            !(e.min.iter().chain(&e.max).all(|v| v.is_finite())
                && e.min[0] >= -0.5
                && e.min[1] >= -0.5
                && e.max[0] <= p.width + 0.5
                && e.max[1] <= p.height + 0.5)
        })
        .collect();
    if !outside.is_empty() {
        out.push(format!(
            "{} of {} elements outside the {} × {} canvas, e.g. {:?} {:?}..{:?}: {}",
            outside.len(),
            p.extents.len(),
            p.width,
            p.height,
            outside[0].tag,
            outside[0].min,
            outside[0].max,
            outside[0].text
        ));
    }
    let layers: BTreeSet<&String> = p.layers.iter().collect();
    let legend: BTreeSet<&String> = p.legend.iter().collect();
    if legend.len() != p.legend.len() {
        out.push(format!("a legend entry is listed twice: {:?}", p.legend));
    }
    for k in layers.difference(&legend) {
        out.push(format!("drawn but not in the legend: {k}"));
    }
    for k in legend.difference(&layers) {
        out.push(format!("in the legend but not drawn: {k}"));
    }
    for k in &p.empty_layers {
        out.push(format!("layer {k} draws nothing"));
    }
    if p.legend.is_empty() {
        out.push("no legend".into());
    }
    // No number a reader cannot use: "inf" or "NaN" as a word anywhere in the text.
    let words = svg.split(|c: char| !c.is_ascii_alphanumeric());
    for bad in ["inf", "NaN", "nan"] {
        if words.clone().any(|w| w == bad) {
            out.push(format!("the picture writes {bad:?}"));
        }
    }
    out
}
