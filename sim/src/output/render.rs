//! A 3D model drawn to PNG without a GPU: a perspective view and a top view side by side, the
//! mesh coloured by height and shaded by its normals, the stations marked, a 1 m floor grid and a
//! scale bar, a legend naming what is drawn.
//!
//! A small z-buffered rasteriser does it: a few hundred thousand triangles take tens of
//! milliseconds. Everything above the cut height (the ceiling) is left out of both views so
//! the rooms can be seen into.

use robot::Pose2;
use robot::reconstruction::Model;
use std::io::BufWriter;
use std::path::Path;

const WIDTH: usize = 1600;
const HEIGHT: usize = 860;
const TITLE_H: usize = 40;
const LEGEND_H: usize = 110;
const MARGIN: usize = 10;
const BACKGROUND: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [30, 30, 30];
const GRID: [u8; 3] = [190, 190, 190];
const STATION: [u8; 3] = [220, 30, 60];
const TRUTH: [u8; 3] = [150, 150, 150];

/// What to draw besides the model.
#[derive(Clone, Debug)]
pub struct Picture<'a> {
    /// The title line.
    pub title: String,
    /// A second line under the title.
    pub subtitle: String,
    /// The model.
    pub model: &'a Model,
    /// The stations: where the base stood, with their numbers.
    pub stations: Vec<(usize, Pose2)>,
    /// Nothing higher than this is drawn, metres.
    pub cut_z: f32,
    /// The true walls' footprints, on the twin: drawn under the top view.
    pub walls: Vec<([f64; 2], [f64; 2])>,
}

/// An RGB image with a depth buffer.
struct Canvas {
    rgb: Vec<u8>,
    depth: Vec<f32>,
}

/// A rectangle of the canvas.
#[derive(Copy, Clone)]
struct Rect {
    x: usize,
    y: usize,
    w: usize,
    h: usize,
}

impl Rect {
    fn contains(&self, x: i64, y: i64) -> bool {
        x >= self.x as i64
            && y >= self.y as i64
            && x < (self.x + self.w) as i64
            && y < (self.y + self.h) as i64
    }
}

impl Canvas {
    fn new() -> Self {
        Canvas {
            rgb: BACKGROUND.repeat(WIDTH * HEIGHT),
            depth: vec![f32::INFINITY; WIDTH * HEIGHT],
        }
    }

    #[inline]
    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < WIDTH && (y as usize) < HEIGHT {
            let k = 3 * (y as usize * WIDTH + x as usize);
            self.rgb[k..k + 3].copy_from_slice(&c);
        }
    }

    /// A pixel drawn only where nothing nearer is, inside `clip`.
    #[inline]
    fn put_depth(&mut self, x: i64, y: i64, z: f32, c: [u8; 3], clip: Rect) {
        if !clip.contains(x, y) {
            return;
        }
        let k = y as usize * WIDTH + x as usize;
        if z < self.depth[k] {
            self.depth[k] = z;
            self.rgb[3 * k..3 * k + 3].copy_from_slice(&c);
        }
    }

    fn fill(&mut self, r: Rect, c: [u8; 3]) {
        for y in r.y..r.y + r.h {
            for x in r.x..r.x + r.w {
                self.put(x as i64, y as i64, c);
            }
        }
    }

    fn frame(&mut self, r: Rect, c: [u8; 3]) {
        for x in r.x..r.x + r.w {
            self.put(x as i64, r.y as i64, c);
            self.put(x as i64, (r.y + r.h - 1) as i64, c);
        }
        for y in r.y..r.y + r.h {
            self.put(r.x as i64, y as i64, c);
            self.put((r.x + r.w - 1) as i64, y as i64, c);
        }
    }

    /// A line `width` pixels wide, clipped to `clip`; with depths, hidden where something is
    /// nearer.
    #[allow(clippy::too_many_arguments)]
    fn line(&mut self, a: [f32; 3], b: [f32; 3], c: [u8; 3], width: i64, clip: Rect, depth: bool) {
        let steps = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as i64).clamp(1, 20_000);
        for s in 0..=steps {
            let t = s as f32 / steps as f32;
            let x = (a[0] + (b[0] - a[0]) * t).round() as i64;
            let y = (a[1] + (b[1] - a[1]) * t).round() as i64;
            let z = a[2] + (b[2] - a[2]) * t;
            for dy in 0..width {
                for dx in 0..width {
                    let (px, py) = (x + dx - width / 2, y + dy - width / 2);
                    if depth {
                        self.put_depth(px, py, z, c, clip);
                    } else if clip.contains(px, py) {
                        self.put(px, py, c);
                    }
                }
            }
        }
    }

    /// Text in the 8×8 bitmap font, `scale` pixels per font pixel, top-left at `(x, y)`.
    fn text(&mut self, x: usize, y: usize, text: &str, scale: usize, c: [u8; 3]) {
        for (n, ch) in text.chars().enumerate() {
            let code = if ch.is_ascii() {
                ch as usize
            } else {
                b'?' as usize
            };
            let glyph = font8x8::legacy::BASIC_LEGACY[code];
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits & (1 << col) != 0 {
                        for sy in 0..scale {
                            for sx in 0..scale {
                                self.put(
                                    (x + (n * 8 + col) * scale + sx) as i64,
                                    (y + row * scale + sy) as i64,
                                    c,
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// A triangle of screen points `(x, y, depth)`, flat `c`, z-buffered, inside `clip`.
    fn triangle(&mut self, p: [[f32; 3]; 3], c: [u8; 3], clip: Rect) {
        let min_x = p.iter().map(|q| q[0]).fold(f32::INFINITY, f32::min).floor();
        let max_x = p
            .iter()
            .map(|q| q[0])
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil();
        let min_y = p.iter().map(|q| q[1]).fold(f32::INFINITY, f32::min).floor();
        let max_y = p
            .iter()
            .map(|q| q[1])
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil();
        let x0 = min_x.max(clip.x as f32) as i64;
        let x1 = max_x.min((clip.x + clip.w - 1) as f32) as i64;
        let y0 = min_y.max(clip.y as f32) as i64;
        let y1 = max_y.min((clip.y + clip.h - 1) as f32) as i64;
        if x0 > x1 || y0 > y1 {
            return;
        }
        let edge = |a: [f32; 3], b: [f32; 3], x: f32, y: f32| {
            (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
        };
        let area = edge(p[0], p[1], p[2][0], p[2][1]);
        if area.abs() < 1e-9 {
            return;
        }
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
                let w0 = edge(p[1], p[2], fx, fy) / area;
                let w1 = edge(p[2], p[0], fx, fy) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                    let z = w0 * p[0][2] + w1 * p[1][2] + w2 * p[2][2];
                    self.put_depth(x, y, z, c, clip);
                }
            }
        }
    }
}

/// The colour of height `t` in 0..=1: dark blue, teal, green, yellow (a viridis-like ramp).
fn ramp(t: f32) -> [f32; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = t.clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f32;
    [0, 1, 2].map(|k| STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f)
}

/// The colour of a surface at height `z` facing `n`, lit from `light`.
fn shade(z: f32, cut: f32, n: [f32; 3], light: [f32; 3]) -> [u8; 3] {
    let lambert = (n[0] * light[0] + n[1] * light[1] + n[2] * light[2]).abs();
    let k = 0.45 + 0.55 * lambert;
    ramp(z / cut).map(|c| (c * k).clamp(0.0, 255.0) as u8)
}

/// A camera: world → screen `(x, y, depth)`.
trait Camera {
    fn project(&self, p: [f32; 3]) -> Option<[f32; 3]>;
}

/// A perspective camera at `eye` looking at `target`, z up.
struct Perspective {
    eye: [f32; 3],
    right: [f32; 3],
    up: [f32; 3],
    forward: [f32; 3],
    focal: f32,
    centre: [f32; 2],
}

impl Camera for Perspective {
    fn project(&self, p: [f32; 3]) -> Option<[f32; 3]> {
        let d = [p[0] - self.eye[0], p[1] - self.eye[1], p[2] - self.eye[2]];
        let dot = |a: [f32; 3]| a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
        let z = dot(self.forward);
        if z < 0.1 {
            return None;
        }
        Some([
            self.centre[0] + self.focal * dot(self.right) / z,
            self.centre[1] - self.focal * dot(self.up) / z,
            z,
        ])
    }
}

/// An orthographic camera looking down: metres to pixels, y flipped (north up).
struct Top {
    origin: [f32; 2],
    scale: f32,
    corner: [f32; 2],
}

impl Camera for Top {
    fn project(&self, p: [f32; 3]) -> Option<[f32; 3]> {
        Some([
            self.corner[0] + (p[0] - self.origin[0]) * self.scale,
            self.corner[1] - (p[1] - self.origin[1]) * self.scale,
            -p[2],
        ])
    }
}

fn normalise(v: [f32; 3]) -> [f32; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-12);
    [v[0] / n, v[1] / n, v[2] / n]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Draws the mesh's triangles below the cut through `camera`.
fn draw_mesh(
    canvas: &mut Canvas,
    pic: &Picture<'_>,
    camera: &dyn Camera,
    light: [f32; 3],
    clip: Rect,
) {
    let m = pic.model;
    for t in &m.triangles {
        let v = t.map(|k| m.vertices[k as usize]);
        if v.iter().any(|p| p[2] > pic.cut_z) {
            continue;
        }
        let Some(s0) = camera.project(v[0]) else {
            continue;
        };
        let Some(s1) = camera.project(v[1]) else {
            continue;
        };
        let Some(s2) = camera.project(v[2]) else {
            continue;
        };
        let n = normalise(robot::reconstruction::normal(&v[0], &v[1], &v[2]));
        let z = (v[0][2] + v[1][2] + v[2][2]) / 3.0;
        canvas.triangle([s0, s1, s2], shade(z, pic.cut_z, n, light), clip);
    }
}

/// A station's marker: a circle of the base's size and a line along its heading.
fn draw_station(canvas: &mut Canvas, camera: &dyn Camera, pose: Pose2, clip: Rect, depth: bool) {
    let (x, y, h) = (pose.x as f32, pose.y as f32, pose.theta as f32);
    let r = 0.28;
    let ring: Vec<[f32; 3]> = (0..=24)
        .map(|k| {
            let a = k as f32 / 24.0 * std::f32::consts::TAU;
            [x + r * a.cos(), y + r * a.sin(), 0.02]
        })
        .collect();
    for w in ring.windows(2) {
        if let (Some(a), Some(b)) = (camera.project(w[0]), camera.project(w[1])) {
            canvas.line(a, b, STATION, 3, clip, depth);
        }
    }
    let tip = [x + 0.5 * h.cos(), y + 0.5 * h.sin(), 0.02];
    if let (Some(a), Some(b)) = (camera.project([x, y, 0.02]), camera.project(tip)) {
        canvas.line(a, b, STATION, 3, clip, depth);
    }
}

/// The model's extent below the cut: (min, max) corners.
fn extent(pic: &Picture<'_>) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let points = pic
        .model
        .vertices
        .iter()
        .filter(|p| p[2] <= pic.cut_z)
        .copied()
        .chain(
            pic.stations
                .iter()
                .map(|(_, s)| [s.x as f32, s.y as f32, 0.0]),
        );
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if !lo[0].is_finite() {
        return ([0.0; 3], [1.0; 3]);
    }
    (lo, hi)
}

/// Draws `pic` and writes it to `path` as PNG.
pub fn write_model_png(path: &Path, pic: &Picture<'_>) -> std::io::Result<()> {
    let mut canvas = Canvas::new();
    let panel_w = (WIDTH - 3 * MARGIN) / 2;
    let panel_h = HEIGHT - TITLE_H - LEGEND_H - MARGIN;
    let left = Rect {
        x: MARGIN,
        y: TITLE_H,
        w: panel_w,
        h: panel_h,
    };
    let right = Rect {
        x: 2 * MARGIN + panel_w,
        ..left
    };
    canvas.text(MARGIN, 6, &pic.title, 2, INK);
    canvas.text(MARGIN, 26, &pic.subtitle, 1, INK);
    let (lo, hi) = extent(pic);
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);

    // Perspective: from the south-west, 40° above the horizon, the whole model in view.
    let fov = 50f32.to_radians();
    let (az, el) = (225f32.to_radians(), 40f32.to_radians());
    let distance = 0.75 * span / (fov / 2.0).tan();
    let target = [centre[0], centre[1], 0.4];
    let eye = [
        target[0] + distance * el.cos() * az.cos(),
        target[1] + distance * el.cos() * az.sin(),
        target[2] + distance * el.sin(),
    ];
    let forward = normalise([target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]]);
    let right_axis = normalise(cross(forward, [0.0, 0.0, 1.0]));
    let up = cross(right_axis, forward);
    let perspective = Perspective {
        eye,
        right: right_axis,
        up,
        forward,
        focal: (panel_w.min(panel_h) as f32 / 2.0) / (fov / 2.0).tan(),
        centre: [(left.x + panel_w / 2) as f32, (left.y + panel_h / 2) as f32],
    };
    let light = normalise([-forward[0] + 0.3, -forward[1] - 0.2, -forward[2] + 0.5]);
    draw_mesh(&mut canvas, pic, &perspective, light, left);
    // The 1 m floor grid, hidden behind what stands on it.
    let (gx0, gx1) = (lo[0].floor() as i32 - 1, hi[0].ceil() as i32 + 1);
    let (gy0, gy1) = (lo[1].floor() as i32 - 1, hi[1].ceil() as i32 + 1);
    let grid_line = |canvas: &mut Canvas, a: [f32; 3], b: [f32; 3]| {
        if let (Some(pa), Some(pb)) = (perspective.project(a), perspective.project(b)) {
            // Slightly nearer than the floor itself, so the floor's mesh does not hide it.
            canvas.line(
                [pa[0], pa[1], pa[2] - 0.05],
                [pb[0], pb[1], pb[2] - 0.05],
                GRID,
                1,
                left,
                true,
            );
        }
    };
    for gx in gx0..=gx1 {
        grid_line(
            &mut canvas,
            [gx as f32, gy0 as f32, 0.0],
            [gx as f32, gy1 as f32, 0.0],
        );
    }
    for gy in gy0..=gy1 {
        grid_line(
            &mut canvas,
            [gx0 as f32, gy as f32, 0.0],
            [gx1 as f32, gy as f32, 0.0],
        );
    }
    for (_, s) in &pic.stations {
        draw_station(&mut canvas, &perspective, *s, left, false);
    }

    // Top view: north up, the model's extent filling the panel.
    let scale = ((panel_w - 40) as f32 / (hi[0] - lo[0]).max(0.5))
        .min((panel_h - 60) as f32 / (hi[1] - lo[1]).max(0.5));
    let top = Top {
        origin: [centre[0], centre[1]],
        scale,
        corner: [
            (right.x + panel_w / 2) as f32,
            (right.y + panel_h / 2) as f32,
        ],
    };
    for (a, b) in &pic.walls {
        let (a, b) = (
            top.project([a[0] as f32, a[1] as f32, 0.0]),
            top.project([b[0] as f32, b[1] as f32, 0.0]),
        );
        if let (Some(a), Some(b)) = (a, b) {
            canvas.line([a[0], a[1], 0.0], [b[0], b[1], 0.0], TRUTH, 1, right, false);
        }
    }
    draw_mesh(&mut canvas, pic, &top, [0.3, -0.4, 0.87], right);
    // Walls are edge-on from above: their readings are drawn as dots, highest on top.
    let m = pic.model;
    for (v, n) in m.vertices.iter().zip(&m.normals) {
        if v[2] <= pic.cut_z
            && n[2].abs() < 0.5
            && let Some(s) = top.project(*v)
        {
            let c = shade(v[2], pic.cut_z, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]);
            canvas.put_depth(s[0] as i64, s[1] as i64, s[2] - 0.01, c, right);
        }
    }
    for (n, s) in &pic.stations {
        draw_station(&mut canvas, &top, *s, right, false);
        if let Some(p) = top.project([s.x as f32 + 0.35, s.y as f32 + 0.35, 0.0])
            && right.contains(p[0] as i64, p[1] as i64 - 16)
        {
            canvas.text(
                p[0] as usize,
                p[1] as usize - 16,
                &format!("S{n}"),
                2,
                STATION,
            );
        }
    }
    // The scale bar: a round length about a fifth of the panel.
    let metres = [0.5f32, 1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .find(|m| m * scale >= panel_w as f32 / 8.0)
        .unwrap_or(10.0);
    let (bx, by) = ((right.x + 20) as f32, (right.y + panel_h - 24) as f32);
    canvas.line(
        [bx, by, 0.0],
        [bx + metres * scale, by, 0.0],
        INK,
        3,
        right,
        false,
    );
    canvas.text(
        right.x + 20,
        right.y + panel_h - 44,
        &format!("{metres} m"),
        2,
        INK,
    );
    canvas.frame(left, INK);
    canvas.frame(right, INK);
    canvas.text(
        left.x + 8,
        left.y + 8,
        "perspective, from the south-west",
        2,
        INK,
    );
    canvas.text(right.x + 8, right.y + 8, "top view, north up", 2, INK);

    // The legend: the height ramp, the station marker, the grid.
    let ly = TITLE_H + panel_h + 14;
    let bar = Rect {
        x: MARGIN + 300,
        y: ly + 4,
        w: 400,
        h: 18,
    };
    canvas.text(MARGIN, ly + 6, "height above floor", 2, INK);
    for x in 0..bar.w {
        let c = ramp(x as f32 / (bar.w - 1) as f32).map(|v| v as u8);
        for y in 0..bar.h {
            canvas.put((bar.x + x) as i64, (bar.y + y) as i64, c);
        }
    }
    canvas.frame(bar, INK);
    for k in 0..=4 {
        let z = pic.cut_z * k as f32 / 4.0;
        let x = bar.x + (bar.w - 1) * k / 4;
        canvas.text(
            x.saturating_sub(16),
            bar.y + bar.h + 6,
            &format!("{z:.1}"),
            1,
            INK,
        );
    }
    canvas.text(
        bar.x + bar.w + 10,
        ly + 10,
        "m (mesh shaded by its normals)",
        1,
        INK,
    );
    let sx = MARGIN + 1010;
    canvas.fill(
        Rect {
            x: sx,
            y: ly + 6,
            w: 24,
            h: 4,
        },
        STATION,
    );
    canvas.text(
        sx + 32,
        ly + 4,
        "stations S0, S1, ... (base, heading)",
        1,
        INK,
    );
    canvas.fill(
        Rect {
            x: sx,
            y: ly + 30,
            w: 24,
            h: 2,
        },
        GRID,
    );
    canvas.text(sx + 32, ly + 26, "floor grid, 1 m (perspective)", 1, INK);
    if !pic.walls.is_empty() {
        canvas.fill(
            Rect {
                x: sx,
                y: ly + 50,
                w: 24,
                h: 1,
            },
            TRUTH,
        );
        canvas.text(
            sx + 32,
            ly + 46,
            "true walls and objects (top view)",
            1,
            INK,
        );
    }
    canvas.text(
        MARGIN,
        ly + 56,
        &format!(
            "wall readings drawn as dots in the top view; nothing above {:.1} m (the ceiling) is drawn",
            pic.cut_z
        ),
        1,
        INK,
    );

    let file = robot::logs::create_file(path)?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), WIDTH as u32, HEIGHT as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(&canvas.rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}
