//! A 3D model: the scenes of a run merged into one set of points with normals and one triangle
//! mesh, in the world frame (thesis §5.3.2–5.3.3). As in the thesis the scenes are placed side by
//! side — each by the base pose at its scans — and overlaid, not fused.

use super::mesh::{MeshOptions, MeshOut, mesh_into, triangle_area};
use super::scene::Scene;
use crate::control::SceneTag;
use crate::geometry::Pose2;

/// What one scene contributed to a model.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SceneStats {
    /// Which scene and station.
    pub tag: SceneTag,
    /// The base's pose the scene was placed at.
    pub base: Pose2,
    /// The head's pan, radians.
    pub pan: f64,
    /// Scans (grid rows).
    pub scans: usize,
    /// Readings that returned: the scene's vertices.
    pub points: usize,
    /// Valid quadrilaterals, and how many the grid offers.
    pub quads: (usize, usize),
    /// Valid triangles, and how many the grid offers.
    pub triangles: (usize, usize),
}

/// Points, normals and triangles of one or more scenes, world frame, metres, z up.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    /// The readings that returned.
    pub vertices: Vec<[f32; 3]>,
    /// A unit normal per vertex, facing the laser that saw it: across × along the scans, over
    /// the neighbours the mesh's rule joins to it.
    pub normals: Vec<[f32; 3]>,
    /// Which scene (index into `scenes`) each vertex comes from.
    pub vertex_scene: Vec<u16>,
    /// Triangles as vertex indices, wound counter-clockwise seen from the laser.
    pub triangles: Vec<[u32; 3]>,
    /// Per scene, in order.
    pub scenes: Vec<SceneStats>,
}

impl Model {
    /// Meshes every scene by `options` and merges them.
    pub fn build(scenes: &[Scene], options: &MeshOptions) -> Model {
        let mut model = Model::default();
        model.rebuild(scenes, options);
        model
    }

    /// As [`build`](Model::build), into this model's arrays: their memory is reused, which is
    /// what a robot rebuilding its model scene after scene wants.
    pub fn rebuild(&mut self, scenes: &[Scene], options: &MeshOptions) {
        self.vertices.clear();
        self.normals.clear();
        self.vertex_scene.clear();
        self.triangles.clear();
        self.scenes.clear();
        // Room for every reading, and for two triangles per grid cell.
        let readings: usize = scenes.iter().map(|s| s.points.len()).sum();
        self.vertices.reserve(readings);
        self.normals.reserve(readings);
        self.vertex_scene.reserve(readings);
        self.triangles.reserve(2 * readings);
        for scene in scenes {
            self.add(scene, options);
        }
    }

    /// Meshes one more scene by `options` and adds it: its readings that returned become
    /// vertices (in grid order), with their normals and the scene's valid triangles.
    pub fn add(&mut self, scene: &Scene, options: &MeshOptions) {
        let index = self.scenes.len() as u16;
        let counts = mesh_into(
            scene,
            options,
            MeshOut {
                vertices: &mut self.vertices,
                normals: &mut self.normals,
                triangles: &mut self.triangles,
            },
        );
        self.vertex_scene.resize(self.vertices.len(), index);
        self.scenes.push(SceneStats {
            tag: scene.tag,
            base: scene.base,
            pan: scene.pan,
            scans: scene.rows,
            points: counts.vertices,
            quads: (counts.quads, counts.quads_possible),
            triangles: (counts.triangles, 2 * counts.quads_possible),
        });
    }

    /// Total surface of the mesh, square metres.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| f64::from(triangle_area(&self.vertices, t)))
            .sum()
    }

    /// Valid quadrilaterals and triangles over all scenes, with how many were possible:
    /// `((quads, of), (triangles, of))`.
    pub fn counts(&self) -> ((usize, usize), (usize, usize)) {
        self.scenes.iter().fold(((0, 0), (0, 0)), |(q, t), s| {
            (
                (q.0 + s.quads.0, q.1 + s.quads.1),
                (t.0 + s.triangles.0, t.1 + s.triangles.1),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::SceneTag;
    use crate::hardware::{HeadAngles, LaserScan};
    use crate::mount::{HeadGeometry, LaserMount};
    use crate::reconstruction::scene::SceneScan;
    use crate::time::Stamp;

    #[test]
    fn a_sweep_of_a_room_becomes_a_mesh_whose_normals_face_the_robot() {
        // A box room 4 m each way around the robot, swept from −20° to +20°: every reading at
        // the analytic range of the walls.
        let head = HeadGeometry::THESIS;
        let mount = LaserMount::Head(head);
        let scans: Vec<LaserScan> = (0..41)
            .map(|j| {
                let angles = HeadAngles {
                    pan: 0.0,
                    tilt: ((j as f64) - 20.0).to_radians(),
                };
                let laser = head.laser_on_base(angles);
                let o = laser.origin();
                let ranges = (0..361)
                    .map(|i| {
                        let a = (i as f64 * 0.5 - 90.0).to_radians();
                        let p = laser.point(a, 1.0);
                        let d = [p[0] - o[0], p[1] - o[1]];
                        // Distance to the square |x| = 4, |y| = 4 along the beam.
                        let t = [(4.0 - o[0]) / d[0], (-4.0 - o[0]) / d[0]]
                            .into_iter()
                            .chain([(4.0 - o[1]) / d[1], (-4.0 - o[1]) / d[1]])
                            .filter(|t| *t > 0.0)
                            .fold(f64::INFINITY, f64::min);
                        (t * 1000.0).round() as u16
                    })
                    .collect();
                let mut s = LaserScan::sick_lms_half_degree(Stamp::from_millis(j), ranges);
                s.head = Some(angles);
                s
            })
            .collect();
        let rows: Vec<SceneScan<'_>> = scans
            .iter()
            .map(|scan| SceneScan::mounted(scan, Pose2::IDENTITY, &mount))
            .collect();
        let tag = SceneTag {
            scene: 0,
            station: 0,
        };
        let scene = Scene::build(tag, &rows).unwrap();
        let model = Model::build(std::slice::from_ref(&scene), &MeshOptions::default());
        assert_eq!(model.vertices.len(), 41 * 361);
        let ((quads, of), (triangles, _)) = model.counts();
        assert_eq!(of, 40 * 360);
        // Only the polygons straddling a room corner (or too long at the far corners) fail.
        assert!(quads as f64 > 0.9 * of as f64, "{quads} of {of}");
        assert!(triangles >= 2 * quads - 80);
        for (v, n) in model.vertices.iter().zip(&model.normals) {
            let back = -(v[0] * n[0] + v[1] * n[1]);
            assert!(
                back > 0.0,
                "normal {n:?} at {v:?} faces away from the robot"
            );
        }
    }
}
