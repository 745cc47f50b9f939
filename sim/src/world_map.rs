//! The world's static surfaces as one parry polyline, for ray casts.
//!
//! Every wall segment becomes a parry [`Segment`] under one parry bounding-volume tree, built with
//! the PLOC strategy (a tighter tree than a `Polyline`'s default, measured 1.3x faster per scan in
//! the lab); a ray visits only the few segments it can hit, nearest first, and parry intersects
//! it with each.

use crate::config::{Material, WorldDescription};
use crate::laser::beam::Optics;
use parry2d::bounding_volume::BoundingVolume;
use parry2d::math::Vector;
use parry2d::partitioning::{Bvh, BvhBuildStrategy};
use parry2d::query::{Ray, RayCast};
use parry2d::shape::Segment;

/// The first surface a ray meets.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, metres.
    pub distance: f64,
    /// Index of the segment hit.
    pub segment: usize,
    /// What the surface is made of.
    pub material: Material,
    /// Unit normal of the surface at the hit, facing the ray's origin.
    pub normal: [f64; 2],
}

/// Static world geometry with its materials.
#[derive(Clone)]
pub struct WorldMap {
    optics: Optics,
    tree: Bvh,
    shapes: Vec<Segment>,
    segments: Vec<([f64; 2], [f64; 2])>,
    materials: Vec<Material>,
}

impl WorldMap {
    /// The surfaces of a world. Segments shorter than 0.1 mm are dropped.
    pub fn new(world: &WorldDescription) -> Self {
        let mut segments = Vec::new();
        let mut materials = Vec::new();
        for (a, b, material) in world.segments() {
            if (a[0] - b[0]).hypot(a[1] - b[1]) >= 1e-4 {
                segments.push((a, b));
                materials.push(material);
            }
        }
        let shapes: Vec<Segment> = segments
            .iter()
            .map(|(a, b)| Segment::new(vector(*a), vector(*b)))
            .collect();
        let tree = Bvh::from_iter(
            BvhBuildStrategy::Ploc,
            shapes
                .iter()
                .map(|s| s.local_aabb().loosened(1e-4))
                .enumerate(),
        );
        WorldMap {
            optics: world.optics,
            tree,
            shapes,
            segments,
            materials,
        }
    }

    /// How the world's materials answer the laser.
    pub fn optics(&self) -> &Optics {
        &self.optics
    }

    /// The segments, metres.
    pub fn segments(&self) -> &[([f64; 2], [f64; 2])] {
        &self.segments
    }

    /// The material of each segment.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The vertices and index pairs of the polyline, for building a collider.
    pub fn polyline_parts(&self) -> (Vec<Vector>, Vec<[u32; 2]>) {
        polyline_parts(&self.segments)
    }

    /// The first surface along the ray from `origin` in the unit direction `dir`, within `max`
    /// metres.
    pub fn cast(&self, origin: [f64; 2], dir: [f64; 2], max: f64) -> Option<Hit> {
        let ray = Ray::new(vector(origin), vector(dir));
        let (segment, toi) = self.tree.find_best(
            max as f32,
            |node, best| node.cast_ray(&ray, best),
            |leaf, best| self.shapes[leaf as usize].cast_local_ray(&ray, best, true),
        )?;
        let segment = segment as usize;
        let (a, b) = self.segments[segment];
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        let mut normal = [(a[1] - b[1]) / length, (b[0] - a[0]) / length];
        if normal[0] * dir[0] + normal[1] * dir[1] > 0.0 {
            normal = [-normal[0], -normal[1]];
        }
        Some(Hit {
            distance: f64::from(toi),
            segment,
            material: self.materials[segment],
            normal,
        })
    }

    /// Distance from `point` to the nearest segment, metres (infinite for an empty world).
    pub fn clearance(&self, point: [f64; 2]) -> f64 {
        self.segments
            .iter()
            .map(|(a, b)| point_segment_distance(point, *a, *b))
            .fold(f64::INFINITY, f64::min)
    }
}

fn vector(p: [f64; 2]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32)
}

fn polyline_parts(segments: &[([f64; 2], [f64; 2])]) -> (Vec<Vector>, Vec<[u32; 2]>) {
    let mut vertices = Vec::with_capacity(2 * segments.len());
    let mut indices = Vec::with_capacity(segments.len());
    for (i, (a, b)) in segments.iter().enumerate() {
        vertices.push(Vector::new(a[0] as f32, a[1] as f32));
        vertices.push(Vector::new(b[0] as f32, b[1] as f32));
        indices.push([2 * i as u32, 2 * i as u32 + 1]);
    }
    (vertices, indices)
}

/// Distance from `p` to the segment `a`–`b`.
pub fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> WorldMap {
        let text = r#"
name = "square"
[start]
x = 0
y = 0
[[wall]]
points = [[-2, -1], [3, -1], [3, 4], [-2, 4]]
closed = true
[[wall]]
material = "glass"
points = [[1, 0.5], [1, 1.5]]
"#;
        WorldMap::new(&WorldDescription::parse(text, "square.toml").unwrap())
    }

    #[test]
    fn rays_meet_walls_at_analytic_distances() {
        let map = square();
        let hit = map.cast([0.0, 0.0], [1.0, 0.0], 32.0).unwrap();
        assert!((hit.distance - 3.0).abs() < 1e-5, "{hit:?}");
        assert_eq!(hit.normal, [-1.0, 0.0]);
        let s = 0.5f64.sqrt();
        let hit = map.cast([0.0, 0.0], [-s, -s], 32.0).unwrap();
        assert!((hit.distance - 2f64.sqrt()).abs() < 1e-5, "{hit:?}");
        let glass = map.cast([0.0, 1.0], [1.0, 0.0], 32.0).unwrap();
        assert_eq!(glass.material, Material::Glass);
        assert!((glass.distance - 1.0).abs() < 1e-6);
    }

    #[test]
    fn nothing_within_range_is_no_hit() {
        assert!(square().cast([0.0, 0.0], [1.0, 0.0], 2.5).is_none());
        assert!(square().cast([10.0, 10.0], [1.0, 0.0], 32.0).is_none());
    }

    #[test]
    fn clearance_is_the_distance_to_the_nearest_wall() {
        assert!((square().clearance([0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((square().clearance([1.0, 1.0]) - 0.0).abs() < 1e-12);
    }
}
