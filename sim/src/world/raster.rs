//! A world drawn as a Stage bitmap: each face's cells painted in the grey of its material, so a
//! world written by hand can be handed to Stage (or read back through a world's `[map]
//! bitmap`, as `worlds/lab-stage.toml` does with the lab). Stage reads a pixel of 127 or darker
//! as occupied; every material's grey is.

use super::WorldMap;
use crate::config::Material;

/// The grey each material is painted in (all occupied for Stage), and the order they are painted:
/// where two meet in a cell, the later wins.
pub const MATERIAL_GREYS: [(Material, u8); 4] = [
    (Material::Matte, 0),
    (Material::Metal, 80),
    (Material::Black, 40),
    (Material::Glass, 100),
];

/// A bitmap of `map`'s faces: `cell` metres per pixel, white (255) where there is nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct Bitmap {
    /// Pixels across.
    pub width: usize,
    /// Pixels up.
    pub height: usize,
    /// The world point at the bitmap's centre, metres.
    pub center: [f64; 2],
    /// Size of the area drawn, metres (`width × cell`, `height × cell`).
    pub size: [f64; 2],
    /// Grey values, top row first.
    pub pixels: Vec<u8>,
}

/// Draws every face of `map` into a bitmap with a margin of two cells around them.
pub fn faces_bitmap(map: &WorldMap, cell: f64) -> Bitmap {
    let faces = map.faces();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for f in faces {
        for p in [f.a, f.b] {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let origin = [lo[0] - 2.0 * cell, lo[1] - 2.0 * cell];
    let width = ((hi[0] - lo[0]) / cell).ceil() as usize + 4;
    let height = ((hi[1] - lo[1]) / cell).ceil() as usize + 4;
    let mut pixels = vec![255u8; width * height];
    for (material, grey) in MATERIAL_GREYS {
        for f in faces.iter().filter(|f| f.material == material) {
            let length = ((f.b[0] - f.a[0]).powi(2) + (f.b[1] - f.a[1]).powi(2)).sqrt();
            let steps = (length / (cell / 4.0)).ceil().max(1.0) as usize;
            for s in 0..=steps {
                let t = s as f64 / steps as f64;
                let x = f.a[0] + t * (f.b[0] - f.a[0]);
                let y = f.a[1] + t * (f.b[1] - f.a[1]);
                let column = ((x - origin[0]) / cell).floor() as usize;
                let row_up = ((y - origin[1]) / cell).floor() as usize;
                if column < width && row_up < height {
                    pixels[(height - 1 - row_up) * width + column] = grey;
                }
            }
        }
    }
    let size = [width as f64 * cell, height as f64 * cell];
    Bitmap {
        width,
        height,
        center: [origin[0] + size[0] / 2.0, origin[1] + size[1] / 2.0],
        size,
        pixels,
    }
}

impl Bitmap {
    /// The bitmap as an 8-bit greyscale PNG.
    pub fn png(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().expect("a PNG header into memory");
        writer
            .write_image_data(&self.pixels)
            .expect("PNG data into memory");
        writer.finish().expect("a PNG into memory");
        out
    }
}
