//! Worlds made from the maps people already have, in either convention:
//!
//! - ROS `map_server`: an occupancy image (`.pgm` or `.png`) and its `map.yaml` (`image`,
//!   `resolution`, `origin`, `negate`, `occupied_thresh`; a cell is occupied when
//!   `(255 − value) / 255` — or `value / 255` with `negate: 1` — exceeds the threshold);
//! - Stage's bitmaps (`floorplan( bitmap "…" size [x y z] pose [x y z a] )`): the image is
//!   stretched over `size` and centred on `pose`, and a pixel is occupied when its first channel
//!   is 127 or darker (Stage's `stg_rotrects_from_image_file`).
//!
//! Occupied cells become walls: the outline of each occupied region, its edges merged along rows
//! and columns into as few straight segments as the pixels allow, so a map costs the laser what
//! its shape costs, not what its pixels do. Each wall takes the material of the occupied cell it
//! bounds: the default, or the one a [`Palette`] gives that cell's pixel value (glass drawn in
//! one grey, black furniture in another).

use super::error::{ConfigError, resolve};
use super::world::Wall;
use crate::config::Material;
use std::path::{Path, PathBuf};

/// The material of each occupied cell: one for all, or by the cell's pixel value.
#[derive(Clone, Debug, PartialEq)]
pub struct Palette {
    /// The material of occupied cells whose value is not listed.
    pub default: Material,
    /// Materials by pixel value (0–255).
    pub by_value: std::collections::BTreeMap<u8, Material>,
}

impl Palette {
    /// Every occupied cell of `material`.
    pub fn single(material: Material) -> Self {
        Palette {
            default: material,
            by_value: Default::default(),
        }
    }

    fn material(&self, value: u8) -> Material {
        self.by_value.get(&value).copied().unwrap_or(self.default)
    }
}

/// An occupancy image placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct MapImage {
    /// Size of a cell, metres: across (x) and up (y).
    pub resolution: [f64; 2],
    /// World coordinates of the lower-left corner of the image, metres.
    pub origin: [f64; 2],
    /// Cells across and up.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Whether each cell is occupied, row by row from the *top* (as the image is stored).
    pub occupied: Vec<bool>,
    /// Each cell's pixel value (grey, or the first channel for a Stage bitmap), same order.
    pub values: Vec<u8>,
}

/// Images larger than this many cells are refused (a 50 km² map at 5 cm).
const MAX_CELLS: usize = 20_000_000;

fn error(path: &Path, line: Option<usize>, field: Option<&str>, message: String) -> ConfigError {
    ConfigError {
        path: path.to_path_buf(),
        line,
        column: None,
        field: field.map(str::to_string),
        message,
        excerpt: None,
    }
}

impl MapImage {
    /// Reads `map.yaml` and the image it names (relative to the YAML file).
    pub fn load(yaml: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(yaml)
            .map_err(|e| error(yaml, None, None, format!("cannot read the file: {e}")))?;
        let mut fields = std::collections::BTreeMap::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let Some((key, value)) = line.split_once(':') else {
                return Err(error(
                    yaml,
                    Some(i + 1),
                    None,
                    format!("expected `key: value`, found `{line}`"),
                ));
            };
            fields.insert(key.trim().to_string(), (i + 1, value.trim().to_string()));
        }
        let get = |key: &'static str| {
            fields
                .get(key)
                .ok_or_else(|| error(yaml, None, Some(key), format!("`{key}` is missing")))
        };
        let number = |key: &'static str, default: Option<f64>| -> Result<f64, ConfigError> {
            match (fields.get(key), default) {
                (None, Some(d)) => Ok(d),
                (None, None) => Err(error(yaml, None, Some(key), format!("`{key}` is missing"))),
                (Some((line, v)), _) => {
                    v.parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| {
                            error(
                                yaml,
                                Some(*line),
                                Some(key),
                                format!("expected a number, found `{v}`"),
                            )
                        })
                }
            }
        };
        let resolution = number("resolution", None)?;
        if !(resolution > 0.0 && resolution <= 10.0) {
            let line = fields.get("resolution").map(|f| f.0);
            return Err(error(
                yaml,
                line,
                Some("resolution"),
                format!("expected metres per cell in (0, 10], found {resolution}"),
            ));
        }
        let (origin_line, origin_text) = get("origin")?;
        let origin: Vec<f64> = origin_text
            .trim_matches(|c| c == '[' || c == ']')
            .split(',')
            .map(|v| v.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()
            .filter(|o: &Vec<f64>| {
                o.len() == 3 && o.iter().all(|v| v.is_finite() && v.abs() <= 1e5)
            })
            .ok_or_else(|| {
                error(
                    yaml,
                    Some(*origin_line),
                    Some("origin"),
                    format!("expected [x, y, yaw] in metres and radians, found `{origin_text}`"),
                )
            })?;
        if origin[2] != 0.0 {
            return Err(error(
                yaml,
                Some(*origin_line),
                Some("origin"),
                "a rotated map (yaw ≠ 0) is not supported: rotate the image instead".to_string(),
            ));
        }
        let negate = number("negate", Some(0.0))? != 0.0;
        let occupied_thresh = number("occupied_thresh", Some(0.65))?;
        if !(0.0..1.0).contains(&occupied_thresh) {
            let line = fields.get("occupied_thresh").map(|f| f.0);
            return Err(error(
                yaml,
                line,
                Some("occupied_thresh"),
                format!("expected a probability in [0, 1), found {occupied_thresh}"),
            ));
        }
        let (image_line, image) = get("image")?;
        let image_path = resolve(yaml, image);
        let (width, height, values) = read_image(&image_path, Channel::Gray)
            .map_err(|message| error(yaml, Some(*image_line), Some("image"), message))?;
        let occupied = values
            .iter()
            .map(|&v| {
                let p = if negate {
                    f64::from(v)
                } else {
                    255.0 - f64::from(v)
                } / 255.0;
                p > occupied_thresh
            })
            .collect();
        Ok(MapImage {
            resolution: [resolution; 2],
            origin: [origin[0], origin[1]],
            width,
            height,
            occupied,
            values,
        })
    }

    /// A Stage bitmap: the image at `bitmap` stretched over `size` (x, y metres) and centred on
    /// `center`; a pixel is occupied when its first channel is 127 or darker.
    pub fn stage(bitmap: &Path, size: [f64; 2], center: [f64; 2]) -> Result<Self, String> {
        let (width, height, values) = read_image(&bitmap.to_path_buf(), Channel::First)?;
        Ok(MapImage {
            resolution: [size[0] / width as f64, size[1] / height as f64],
            origin: [center[0] - size[0] / 2.0, center[1] - size[1] / 2.0],
            width,
            height,
            occupied: values.iter().map(|&v| v <= STAGE_THRESHOLD).collect(),
            values,
        })
    }

    /// The material of the occupied cell at (`column`, `row_from_bottom`), if it is one.
    fn class(&self, palette: &Palette, column: i64, row_from_bottom: i64) -> Option<Material> {
        self.at(column, row_from_bottom).then(|| {
            let i = (self.height - 1 - row_from_bottom as usize) * self.width + column as usize;
            palette.material(self.values[i])
        })
    }

    fn at(&self, column: i64, row_from_bottom: i64) -> bool {
        if column < 0 || row_from_bottom < 0 {
            return false;
        }
        let (c, r) = (column as usize, row_from_bottom as usize);
        c < self.width && r < self.height && self.occupied[(self.height - 1 - r) * self.width + c]
    }

    /// The outline of the occupied cells as walls from `z[0]` to `z[1]`, each of the material
    /// `palette` gives the occupied cell it bounds: each border between an occupied cell and a
    /// free one (or the image's edge), merged along its row or column into the longest straight
    /// pieces of one material.
    pub fn walls(&self, palette: &Palette, z: [f64; 2]) -> Vec<Wall> {
        let [rx, ry] = self.resolution;
        let point = |c: i64, row: i64| {
            [
                self.origin[0] + c as f64 * rx,
                self.origin[1] + row as f64 * ry,
            ]
        };
        let wall = |material, a: [f64; 2], b: [f64; 2]| Wall {
            material,
            points: vec![a, b],
            closed: false,
            z,
        };
        let mut materials: Vec<Material> = std::iter::once(palette.default)
            .chain(palette.by_value.values().copied())
            .collect();
        materials.sort_by_key(|m| *m as u8);
        materials.dedup();
        let (w, h) = (self.width as i64, self.height as i64);
        let mut walls = Vec::new();
        for &m in &materials {
            // A border of material m: one side occupied by m, the other free.
            let border = |a: Option<Material>, b: Option<Material>, a_side: bool| {
                a.is_some() != b.is_some() && a.is_some() == a_side && a.or(b) == Some(m)
            };
            // Horizontal borders: between row y−1 and row y.
            for y in 0..=h {
                for below in [true, false] {
                    let at = |x| {
                        border(
                            self.class(palette, x, y - 1),
                            self.class(palette, x, y),
                            below,
                        )
                    };
                    for (start, end) in runs(w, at) {
                        walls.push(wall(m, point(start, y), point(end, y)));
                    }
                }
            }
            // Vertical borders: between column x−1 and column x.
            for x in 0..=w {
                for left in [true, false] {
                    let at = |y| {
                        border(
                            self.class(palette, x - 1, y),
                            self.class(palette, x, y),
                            left,
                        )
                    };
                    for (start, end) in runs(h, at) {
                        walls.push(wall(m, point(x, start), point(x, end)));
                    }
                }
            }
        }
        walls
    }
}

/// The maximal runs `[start, end)` of `0..n` where `border` holds.
fn runs(n: i64, border: impl Fn(i64) -> bool) -> Vec<(i64, i64)> {
    let mut found = Vec::new();
    let mut start = None;
    for k in 0..=n {
        match (k < n && border(k), start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                found.push((s, k));
                start = None;
            }
            _ => {}
        }
    }
    found
}

/// A Stage bitmap's pixel is free above this value of its first channel.
const STAGE_THRESHOLD: u8 = 127;

/// Which value of a colour pixel is read.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Channel {
    /// Its luminance (Rec. 601 weights), as map tools read colour maps.
    Gray,
    /// Its first channel (red), as Stage reads bitmaps.
    First,
}

/// Width, height and 8-bit values (top row first) of a binary PGM (`P5`) or a PNG.
fn read_image(path: &PathBuf, channel: Channel) -> Result<(usize, usize, Vec<u8>), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let name = path.display();
    if bytes.starts_with(b"P5") {
        let mut tokens = Vec::new();
        let mut i = 2;
        while tokens.len() < 3 {
            while i < bytes.len() && bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            if i < bytes.len() && bytes[i] == b'#' {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            let start = i;
            while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            let token = std::str::from_utf8(&bytes[start..i]).unwrap_or("");
            let value: usize = token.parse().map_err(|_| {
                format!("{name}: a PGM header needs width, height and maxval, found `{token}`")
            })?;
            tokens.push(value);
        }
        let (width, height, maxval) = (tokens[0], tokens[1], tokens[2]);
        if maxval != 255 {
            return Err(format!(
                "{name}: only 8-bit PGM (maxval 255) is read, found maxval {maxval}"
            ));
        }
        check_size(&name.to_string(), width, height)?;
        let data = bytes.get(i + 1..i + 1 + width * height).ok_or_else(|| {
            format!(
                "{name}: the PGM is truncated: expected {} bytes of pixels",
                width * height
            )
        })?;
        return Ok((width, height, data.to_vec()));
    }
    if bytes.starts_with(b"\x89PNG") {
        let mut decoder = png::Decoder::new(std::io::Cursor::new(&bytes));
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder.read_info().map_err(|e| format!("{name}: {e}"))?;
        let (width, height) = (reader.info().width as usize, reader.info().height as usize);
        check_size(&name.to_string(), width, height)?;
        let mut buffer = vec![0; reader.output_buffer_size().ok_or("PNG too large")?];
        let frame = reader
            .next_frame(&mut buffer)
            .map_err(|e| format!("{name}: {e}"))?;
        let channels = frame.color_type.samples();
        let gray = buffer[..frame.buffer_size()]
            .chunks(channels)
            .map(|px| match channels {
                1 | 2 => px[0],
                _ if channel == Channel::First => px[0],
                _ => {
                    ((u32::from(px[0]) * 299 + u32::from(px[1]) * 587 + u32::from(px[2]) * 114)
                        / 1000) as u8
                }
            })
            .collect();
        return Ok((width, height, gray));
    }
    Err(format!("{name}: expected a binary PGM (P5) or a PNG image"))
}

fn check_size(name: &str, width: usize, height: usize) -> Result<(), String> {
    if width == 0 || height == 0 || width.saturating_mul(height) > MAX_CELLS {
        return Err(format!(
            "{name}: {width} × {height} pixels: expected at least one and at most {MAX_CELLS}"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two occupied cells side by side, one drawn in the glass grey: each keeps its material,
    /// and no wall stands between them.
    #[test]
    fn a_palette_gives_each_cell_its_material() {
        let map = MapImage {
            resolution: [1.0, 2.0],
            origin: [0.0, 0.0],
            width: 2,
            height: 1,
            occupied: vec![true, true],
            values: vec![0, 100],
        };
        let palette = Palette {
            default: Material::Matte,
            by_value: [(100, Material::Glass)].into(),
        };
        let walls = map.walls(&palette, [0.0, 1.0]);
        let glass: Vec<_> = walls
            .iter()
            .filter(|w| w.material == Material::Glass)
            .map(|w| (w.points[0], w.points[1]))
            .collect();
        // The glass cell's right side, its bottom and top halves; nothing at x = 1 between the two.
        assert!(glass.contains(&([2.0, 0.0], [2.0, 2.0])), "{glass:?}");
        assert!(glass.contains(&([1.0, 0.0], [2.0, 0.0])), "{glass:?}");
        assert!(glass.contains(&([1.0, 2.0], [2.0, 2.0])), "{glass:?}");
        assert_eq!(glass.len(), 3);
        assert!(
            walls
                .iter()
                .all(|w| w.points[0][0] != 1.0 || w.points[1][0] != 1.0)
        );
        assert_eq!(walls.len(), 6, "{walls:?}");
    }

    #[test]
    fn a_square_block_becomes_four_walls() {
        // 4 × 3 image, a 2 × 2 block of occupied cells at columns 1–2, the two top rows.
        let map = MapImage {
            resolution: [0.5; 2],
            origin: [10.0, 20.0],
            width: 4,
            height: 3,
            occupied: vec![
                false, true, true, false, //
                false, true, true, false, //
                false, false, false, false,
            ],
            values: vec![0; 12],
        };
        let walls = map.walls(&Palette::single(Material::Matte), [0.0, 2.0]);
        assert_eq!(walls.len(), 4, "{walls:?}");
        let mut ends: Vec<_> = walls.iter().map(|w| (w.points[0], w.points[1])).collect();
        ends.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert!(ends.contains(&([10.5, 20.5], [11.5, 20.5])), "{ends:?}");
        assert!(ends.contains(&([10.5, 21.5], [11.5, 21.5])), "{ends:?}");
        assert!(ends.contains(&([10.5, 20.5], [10.5, 21.5])), "{ends:?}");
        assert!(ends.contains(&([11.5, 20.5], [11.5, 21.5])), "{ends:?}");
    }
}
