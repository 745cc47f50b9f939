//! World files: walls, boxes and tables made of named materials, with heights, under a ceiling;
//! and the robot's start pose.
//!
//! ```toml
//! name = "two rooms"
//! ceiling_m = 2.6              # the floor is z = 0; the ceiling (default 2.6 m) closes the room
//! [start]                      # where the robot is put, metres and degrees
//! x = 1.0
//! y = 1.0
//! heading_deg = 0.0
//!
//! [[wall]]                     # a polyline; closed = true joins the last point to the first
//! material = "matte"           # matte (default), black, glass or metal
//! points = [[0, 0], [6, 0], [6, 4], [0, 4]]
//! closed = true
//! z = [0.0, 2.6]               # optional: from floor to ceiling by default
//!
//! [[box]]                      # a rectangle: centre, size along its own x and y, heading
//! center = [3.0, 2.0]
//! size = [1.2, 0.6]
//! heading_deg = 30
//! material = "black"
//! z = [0.0, 0.5]               # optional: a box half a metre tall
//!
//! [[table]]                    # a top (0.72 to 0.75 m by default) on four square legs
//! center = [5.0, 1.0]
//! size = [1.6, 0.8]
//! height_m = 0.75              # optional
//! material = "black"
//!
//! [optics]                     # optional: how the materials answer the laser (defaults shown)
//! grazing_deg = 85             # no surface returns a pulse beyond this incidence
//! black_full_deg = 20          # black returns always up to here…
//! black_lost_deg = 50          # …and never from here
//! glass_return_deg = 8         # glass returns the pulse itself within this incidence…
//! glass_transparent = 0.5      # …beyond, a window with this chance, else a mirror
//! metal_return_deg = 3         # metal returns within this incidence, mirrors beyond
//! max_bounces = 3
//! ```
//!
//! Frames follow REP-103: x and y in metres in the world frame, headings counter-clockwise.

use super::error::{ConfigError, Source, resolve};
use super::map_image::{MapImage, Palette};
use super::values::{Angle, UnitInterval, show};
use robot::Pose2;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// What a surface is made of; it decides how the laser's beam comes back.
///
/// The first laser model treats every material as a diffuse reflector; black surfaces, glass
/// and metal get their own optics with the sensor-realism work.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Material {
    /// Paint, plaster, wood: returns the beam at any incidence short of grazing.
    Matte,
    /// Low reflectivity (black doors, black furniture).
    Black,
    /// Glass doors and windows.
    Glass,
    /// Polished metal, mirrors.
    Metal,
}

impl Material {
    /// Every material, in the order of [`Material::NAMES`].
    pub const ALL: [Material; 4] = [
        Material::Matte,
        Material::Black,
        Material::Glass,
        Material::Metal,
    ];
    /// The names accepted in world files.
    pub const NAMES: [&'static str; 4] = ["matte", "black", "glass", "metal"];

    /// The material called `name`.
    pub fn from_name(name: &str) -> Option<Material> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| Self::ALL[i])
    }

    /// The material's name in world files.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// The optical behaviour of the world's materials. Angles are incidence angles from the
/// surface normal, radians.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Optics {
    /// Beyond this incidence no surface returns the pulse.
    pub grazing: f64,
    /// Black surfaces always return the pulse up to this incidence…
    pub black_full: f64,
    /// …and never from this incidence on.
    pub black_lost: f64,
    /// Glass returns the pulse itself below this incidence (zero: never, a perfect mirror).
    pub glass_return: f64,
    /// Beyond it, the chance that glass lets the pulse through (else it mirrors it).
    pub glass_transparent: f64,
    /// Metal returns the pulse itself below this incidence, and mirrors it from there on.
    pub metal_return: f64,
    /// Reflections and transmissions followed before the pulse is lost.
    pub max_bounces: u32,
}

impl Default for Optics {
    /// Grazing at 85°, black lost between 20° and 50°, glass returning within 8° and otherwise
    /// transparent half the time, metal returning within 3°, three bounces.
    fn default() -> Self {
        Optics {
            grazing: 85f64.to_radians(),
            black_full: 20f64.to_radians(),
            black_lost: 50f64.to_radians(),
            glass_return: 8f64.to_radians(),
            glass_transparent: 0.5,
            metal_return: 3f64.to_radians(),
            max_bounces: 3,
        }
    }
}

/// A polyline of wall surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// What the wall is made of.
    pub material: Material,
    /// Vertices, metres, world frame.
    pub points: Vec<[f64; 2]>,
    /// Whether the last point joins the first.
    pub closed: bool,
    /// Bottom and top, metres above the floor.
    pub z: [f64; 2],
}

impl Wall {
    /// The wall's straight pieces.
    pub fn segments(&self) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
        let n = self.points.len();
        let count = if self.closed { n } else { n.saturating_sub(1) };
        (0..count).map(move |i| (self.points[i], self.points[(i + 1) % n]))
    }
}

/// A validated world.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldDescription {
    /// Short name.
    pub name: String,
    /// What the world represents and where it comes from.
    pub description: String,
    /// Where the robot starts.
    pub start: Pose2,
    /// Every surface, boxes and tables included (as closed walls).
    pub walls: Vec<Wall>,
    /// Height of the ceiling, metres (the floor is at zero).
    pub ceiling: f64,
    /// How the materials answer the laser.
    pub optics: Optics,
    /// The file it was read from.
    pub path: PathBuf,
}

impl WorldDescription {
    /// Reads and validates a world file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        Self::from_source(&Source::read(path.as_ref())?)
    }

    /// Parses and validates world-file text; `path` only names it in errors.
    pub fn parse(text: &str, path: impl AsRef<Path>) -> Result<Self, ConfigError> {
        Self::from_source(&Source::text(text, path.as_ref()))
    }

    fn from_source(source: &Source) -> Result<Self, ConfigError> {
        let file: WorldFile = source.parse()?;
        let ceiling = *file.ceiling_m.get_ref();
        if !(ceiling > 0.0 && ceiling <= MAX_HEIGHT_M) {
            return Err(source.error(
                file.ceiling_m.span(),
                Some("ceiling_m".into()),
                format!(
                    "expected a positive height up to {MAX_HEIGHT_M} m, found {}",
                    show(ceiling)
                ),
            ));
        }
        let heights = |z: &Option<Spanned<[f64; 2]>>, field: Option<String>| match z {
            None => Ok([0.0, ceiling]),
            Some(z) => {
                let [lo, hi] = *z.get_ref();
                if lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi && hi <= ceiling {
                    Ok([lo, hi])
                } else {
                    Err(source.error(
                        z.span(),
                        field,
                        format!("expected [bottom, top] with 0 <= bottom < top <= ceiling ({ceiling}), found [{lo}, {hi}]"),
                    ))
                }
            }
        };
        let mut walls = Vec::new();
        for (i, wall) in file.walls.iter().enumerate() {
            let field = |name: &str| Some(format!("wall[{i}].{name}"));
            let material = material(source, &wall.material, field("material"))?;
            let points = wall.points.get_ref();
            if points.len() < 2 {
                return Err(source.error(
                    wall.points.span(),
                    field("points"),
                    format!("a wall needs at least 2 points, found {}", points.len()),
                ));
            }
            let values: Vec<f64> = points.iter().flatten().copied().collect();
            check_coordinates(source, wall.points.span(), &values, field("points"))?;
            walls.push(Wall {
                material,
                points: points.clone(),
                closed: wall.closed,
                z: heights(&wall.z, field("z"))?,
            });
        }
        for (i, b) in file.boxes.iter().enumerate() {
            let field = |name: &str| Some(format!("box[{i}].{name}"));
            let material = material(source, &b.material, field("material"))?;
            let rect = rectangle(source, &b.center, &b.size, b.heading_deg, &field)?;
            walls.push(Wall {
                material,
                points: rect.corners(),
                closed: true,
                z: heights(&b.z, field("z"))?,
            });
        }
        for (i, t) in file.tables.iter().enumerate() {
            let field = |name: &str| Some(format!("table[{i}].{name}"));
            let material = material(source, &t.material, field("material"))?;
            let rect = rectangle(source, &t.center, &t.size, t.heading_deg, &field)?;
            let height = *t.height_m.get_ref();
            if !(height > TABLE_TOP && height < ceiling) {
                return Err(source.error(
                    t.height_m.span(),
                    field("height_m"),
                    format!(
                        "expected a height between {TABLE_TOP} m and the ceiling, found {height}"
                    ),
                ));
            }
            walls.push(Wall {
                material,
                points: rect.corners(),
                closed: true,
                z: [height - TABLE_TOP, height],
            });
            // Four square legs inside the corners.
            let leg = TABLE_LEG.min(rect.size[0] / 4.0).min(rect.size[1] / 4.0);
            for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
                let (cx, cy) = rect.pose.transform_point(
                    sx * (rect.size[0] / 2.0 - leg / 2.0),
                    sy * (rect.size[1] / 2.0 - leg / 2.0),
                );
                let leg_pose = Pose2::new(cx, cy, rect.pose.theta);
                walls.push(Wall {
                    material,
                    points: Rectangle {
                        pose: leg_pose,
                        size: [leg, leg],
                    }
                    .corners(),
                    closed: true,
                    z: [0.0, height - TABLE_TOP],
                });
            }
        }
        if let Some(map) = &file.map {
            let material = material(source, &map.material, Some("map.material".into()))?;
            let height = map.height_m.as_ref().map_or(ceiling, |h| *h.get_ref());
            if !(height > 0.0 && height <= ceiling) {
                let span = map.height_m.as_ref().map_or(0..0, |h| h.span());
                return Err(source.error(
                    span,
                    Some("map.height_m".into()),
                    format!("expected a height in (0, ceiling = {ceiling}], found {height}"),
                ));
            }
            let mut palette = Palette::single(material);
            for (value, name) in map.materials.iter().flatten() {
                let field = format!("map.materials.{value}");
                let v = value.parse::<u8>().map_err(|_| {
                    source.error(
                        name.span(),
                        Some(field.clone()),
                        format!("`{value}` is not a pixel value: expected 0 to 255"),
                    )
                })?;
                palette
                    .by_value
                    .insert(v, self::material(source, name, Some(field))?);
            }
            let image = match (&map.yaml, &map.bitmap) {
                (Some(yaml), None) => {
                    if let Some(size) = &map.size {
                        return Err(source.error(
                            size.span(),
                            Some("map.size".into()),
                            "`size` is for a Stage `bitmap`; a map.yaml gives its own resolution",
                        ));
                    }
                    MapImage::load(&resolve(&source.path, yaml.get_ref()))?
                }
                (None, Some(bitmap)) => {
                    let size = map.size.as_ref().ok_or_else(|| {
                        source.error(
                            bitmap.span(),
                            Some("map.size".into()),
                            "a Stage `bitmap` needs `size = [x, y, z]` in metres (Stage's floorplan size)",
                        )
                    })?;
                    let [sx, sy, sz] = *size.get_ref();
                    if ![sx, sy, sz]
                        .iter()
                        .all(|v| *v > 0.0 && *v <= MAX_COORDINATE_M)
                    {
                        return Err(source.error(
                            size.span(),
                            Some("map.size".into()),
                            format!("expected three sizes in (0, {MAX_COORDINATE_M}] metres, found {:?}", [sx, sy, sz]),
                        ));
                    }
                    let pose = map.pose.as_ref().map_or([0.0; 4], |p| *p.get_ref());
                    if pose[3] != 0.0
                        || pose[..2]
                            .iter()
                            .any(|v| v.is_nan() || v.abs() > MAX_COORDINATE_M)
                    {
                        let span = map.pose.as_ref().map_or(0..0, |p| p.span());
                        return Err(source.error(
                            span,
                            Some("map.pose".into()),
                            format!("expected [x, y, z, yaw] with yaw 0 and x, y within {MAX_COORDINATE_M} m, found {pose:?}"),
                        ));
                    }
                    let path = resolve(&source.path, bitmap.get_ref());
                    MapImage::stage(&path, [sx, sy], [pose[0], pose[1]]).map_err(|message| {
                        source.error(bitmap.span(), Some("map.bitmap".into()), message)
                    })?
                }
                _ => {
                    return Err(source.error_in_file(
                        Some("map".into()),
                        "give either `yaml` (a ROS map.yaml) or `bitmap` with `size` (a Stage bitmap), not both or neither",
                    ));
                }
            };
            // A Stage bitmap's height is its size's z unless `height_m` says otherwise.
            let height = match (&map.bitmap, &map.height_m, &map.size) {
                (Some(_), None, Some(size)) => size.get_ref()[2].min(ceiling),
                _ => height,
            };
            walls.extend(image.walls(&palette, [0.0, height]));
        }
        let optics = file
            .optics
            .map_or_else(Optics::default, |o| o.into_optics());
        let mut world = WorldDescription {
            name: file.name,
            description: file.description,
            start: Pose2::IDENTITY,
            walls,
            ceiling,
            optics,
            path: source.path.clone(),
        };
        world.start = world
            .check_start(&file.start)
            .map_err(|message| source.error_in_file(Some("start".into()), message))?;
        Ok(world)
    }

    /// `start` as a pose, if it lies within the world's extent with a plausible heading: the
    /// same rule for a world's `[start]` and a scenario's. (The twin checks it is clear of
    /// walls when it places the robot.)
    pub(super) fn check_start(&self, start: &StartFile) -> Result<Pose2, String> {
        let (lo, hi) = self.wall_bounds();
        let inside = |v: f64, k: usize| v.is_finite() && v >= lo[k] && v <= hi[k];
        if inside(start.x, 0) && inside(start.y, 1) && start.heading_deg.abs() <= 3600.0 {
            Ok(Pose2::new(start.x, start.y, start.heading_deg.to_radians()))
        } else {
            Err(format!(
                "expected x in [{}, {}], y in [{}, {}] (the world's walls and 20 m around) and a heading within ±3600 degrees, found x = {}, y = {}, heading_deg = {}",
                lo[0],
                hi[0],
                lo[1],
                hi[1],
                show(start.x),
                show(start.y),
                show(start.heading_deg)
            ))
        }
    }

    /// Every straight piece of surface with its material.
    pub fn segments(&self) -> impl Iterator<Item = ([f64; 2], [f64; 2], Material)> + '_ {
        self.walls
            .iter()
            .flat_map(|w| w.segments().map(move |(a, b)| (a, b, w.material)))
    }

    /// The smallest axis-aligned box holding every wall, grown by [`START_MARGIN_M`] (the
    /// coordinate limits when there is no wall), `(min, max)`.
    fn wall_bounds(&self) -> ([f64; 2], [f64; 2]) {
        let points = self.walls.iter().flat_map(|w| w.points.iter());
        let (lo, hi) = points.fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            },
        );
        if lo[0] <= hi[0] {
            // Open space around the walls is still the world (a test rig of one wall).
            (
                lo.map(|v| v - START_MARGIN_M),
                hi.map(|v| v + START_MARGIN_M),
            )
        } else {
            ([-MAX_COORDINATE_M; 2], [MAX_COORDINATE_M; 2])
        }
    }

    /// The smallest axis-aligned box holding every wall and the start, `(min, max)`.
    pub fn bounds(&self) -> ([f64; 2], [f64; 2]) {
        let mut min = [self.start.x, self.start.y];
        let mut max = min;
        for p in self.walls.iter().flat_map(|w| w.points.iter()) {
            for k in 0..2 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        (min, max)
    }
}

/// Thickness of a table's top, metres.
const TABLE_TOP: f64 = 0.03;
/// Side of a table's square legs, metres.
const TABLE_LEG: f64 = 0.05;

/// A rectangle of the world file: centre, size along its own axes, heading.
struct Rectangle {
    pose: Pose2,
    size: [f64; 2],
}

impl Rectangle {
    /// The corners, counter-clockwise.
    fn corners(&self) -> Vec<[f64; 2]> {
        let [w, h] = self.size;
        [(0.5, 0.5), (-0.5, 0.5), (-0.5, -0.5), (0.5, -0.5)]
            .map(|(a, b)| {
                let (x, y) = self.pose.transform_point(a * w, b * h);
                [x, y]
            })
            .to_vec()
    }
}

fn rectangle(
    source: &Source,
    center: &Spanned<[f64; 2]>,
    size: &Spanned<[f64; 2]>,
    heading_deg: f64,
    field: &dyn Fn(&str) -> Option<String>,
) -> Result<Rectangle, ConfigError> {
    let [w, h] = *size.get_ref();
    let size_ok = |v: f64| (1e-3..=MAX_COORDINATE_M).contains(&v);
    if !(size_ok(w) && size_ok(h)) {
        return Err(source.error(
            size.span(),
            field("size"),
            format!(
                "expected a size from 0.001 to {MAX_COORDINATE_M} m each way, found [{w}, {h}]"
            ),
        ));
    }
    let c = *center.get_ref();
    check_coordinates(source, center.span(), &c, field("center"))?;
    // NaN is not within the range either.
    if !(-3600.0..=3600.0).contains(&heading_deg) {
        return Err(source.error(
            center.span(),
            field("heading_deg"),
            format!(
                "expected a heading within ±3600 degrees, found {}",
                show(heading_deg)
            ),
        ));
    }
    Ok(Rectangle {
        pose: Pose2::new(c[0], c[1], heading_deg.to_radians()),
        size: [w, h],
    })
}

fn material(
    source: &Source,
    name: &Spanned<String>,
    field: Option<String>,
) -> Result<Material, ConfigError> {
    Material::from_name(name.get_ref()).ok_or_else(|| {
        source.error(
            name.span(),
            field,
            format!(
                "unknown material {:?}: expected one of {}",
                name.get_ref(),
                Material::NAMES.join(", ")
            ),
        )
    })
}

/// The farthest a world's point may lie from its origin, metres: 100 km is any building, and
/// keeps every coordinate exact enough in the single precision of the collision engine.
pub const MAX_COORDINATE_M: f64 = 1e5;
/// How far outside the box of its walls a robot may start, metres.
pub const START_MARGIN_M: f64 = 20.0;
/// The highest ceiling, metres.
pub const MAX_HEIGHT_M: f64 = 1e3;

fn check_coordinates(
    source: &Source,
    span: std::ops::Range<usize>,
    values: &[f64],
    field: Option<String>,
) -> Result<(), ConfigError> {
    let within = |v: &f64| (-MAX_COORDINATE_M..=MAX_COORDINATE_M).contains(v);
    match values.iter().find(|v| !within(v)) {
        Some(v) => Err(source.error(
            span,
            field,
            format!(
                "expected coordinates within ±{MAX_COORDINATE_M} m, found {}",
                show(*v)
            ),
        )),
        None => Ok(()),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WorldFile {
    name: String,
    #[serde(default)]
    description: String,
    start: StartFile,
    #[serde(default, rename = "wall")]
    walls: Vec<WallFile>,
    #[serde(default, rename = "box")]
    boxes: Vec<BoxFile>,
    #[serde(default, rename = "table")]
    tables: Vec<TableFile>,
    #[serde(default = "default_ceiling")]
    ceiling_m: Spanned<f64>,
    optics: Option<OpticsFile>,
    map: Option<MapFile>,
}

/// `[map]`: walls from an occupancy image and its `map.yaml` (ROS `map_server` convention).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    /// The `map.yaml`, relative to the world file.
    yaml: Option<Spanned<String>>,
    /// Or a Stage bitmap, relative to the world file…
    bitmap: Option<Spanned<String>>,
    /// …stretched over this size `[x, y, z]`, metres…
    size: Option<Spanned<[f64; 3]>>,
    /// …centred on this pose `[x, y, z, yaw]` (yaw 0).
    pose: Option<Spanned<[f64; 4]>>,
    /// Materials by pixel value (`"100" = "glass"`).
    materials: Option<std::collections::BTreeMap<String, Spanned<String>>>,
    #[serde(default = "matte")]
    material: Spanned<String>,
    /// Height of the walls, metres (default: the ceiling).
    height_m: Option<Spanned<f64>>,
}

fn default_ceiling() -> Spanned<f64> {
    Spanned::new(0..0, 2.6)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TableFile {
    #[serde(default = "matte")]
    material: Spanned<String>,
    center: Spanned<[f64; 2]>,
    size: Spanned<[f64; 2]>,
    #[serde(default)]
    heading_deg: f64,
    #[serde(default = "table_height")]
    height_m: Spanned<f64>,
}

fn table_height() -> Spanned<f64> {
    Spanned::new(0..0, 0.75)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OpticsFile {
    grazing_deg: Option<Angle>,
    black_full_deg: Option<Angle>,
    black_lost_deg: Option<Angle>,
    glass_return_deg: Option<Angle>,
    glass_transparent: Option<UnitInterval>,
    metal_return_deg: Option<Angle>,
    max_bounces: Option<u32>,
}

impl OpticsFile {
    fn into_optics(self) -> Optics {
        let d = Optics::default();
        let rad = |v: Option<Angle>, default: f64| v.map_or(default, |a| a.get().to_radians());
        Optics {
            grazing: rad(self.grazing_deg, d.grazing),
            black_full: rad(self.black_full_deg, d.black_full),
            black_lost: rad(self.black_lost_deg, d.black_lost),
            glass_return: rad(self.glass_return_deg, d.glass_return),
            glass_transparent: self
                .glass_transparent
                .map_or(d.glass_transparent, UnitInterval::get),
            metal_return: rad(self.metal_return_deg, d.metal_return),
            max_bounces: self.max_bounces.unwrap_or(d.max_bounces),
        }
    }
}

/// `[start]`: where the robot is put, metres and degrees (also a scenario's override).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct StartFile {
    pub(super) x: f64,
    pub(super) y: f64,
    #[serde(default)]
    pub(super) heading_deg: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WallFile {
    #[serde(default = "matte")]
    material: Spanned<String>,
    points: Spanned<Vec<[f64; 2]>>,
    #[serde(default)]
    closed: bool,
    z: Option<Spanned<[f64; 2]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxFile {
    #[serde(default = "matte")]
    material: Spanned<String>,
    center: Spanned<[f64; 2]>,
    size: Spanned<[f64; 2]>,
    #[serde(default)]
    heading_deg: f64,
    z: Option<Spanned<[f64; 2]>>,
}

fn matte() -> Spanned<String> {
    Spanned::new(0..0, "matte".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "room"
[start]
x = 1
y = 1
[[wall]]
points = [[0, 0], [4, 0], [4, 3], [0, 3]]
closed = true
[[box]]
center = [2.0, 1.5]
size = [1.0, 0.5]
material = "black"
"#;

    #[test]
    fn a_good_world_has_walls_and_boxes() {
        let w = WorldDescription::parse(GOOD, "room.toml").unwrap();
        assert_eq!(w.walls.len(), 2);
        assert_eq!(w.segments().count(), 8);
        assert_eq!(w.walls[1].material, Material::Black);
        assert_eq!(w.bounds(), ([0.0, 0.0], [4.0, 3.0]));
    }

    #[test]
    fn an_unknown_material_names_line_field_and_choices() {
        let text = GOOD.replace("\"black\"", "\"velvet\"");
        let err = WorldDescription::parse(&text, "room.toml").unwrap_err();
        assert_eq!(err.line, Some(12), "{err}");
        assert_eq!(err.field.as_deref(), Some("box[0].material"));
        assert!(err.message.contains("matte, black, glass, metal"), "{err}");
    }

    #[test]
    fn a_one_point_wall_is_refused_where_it_is() {
        let text = GOOD.replace("[[0, 0], [4, 0], [4, 3], [0, 3]]", "[[0, 0]]");
        let err = WorldDescription::parse(&text, "room.toml").unwrap_err();
        assert_eq!(
            (err.line, err.field.as_deref()),
            (Some(7), Some("wall[0].points")),
            "{err}"
        );
    }

    #[test]
    fn a_missing_start_coordinate_is_named() {
        let text = GOOD.replace("y = 1\n", "");
        let err = WorldDescription::parse(&text, "room.toml").unwrap_err();
        assert_eq!(err.field.as_deref(), Some("y"), "{err}");
    }
}
