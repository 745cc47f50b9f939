//! A 3D scene (thesis §4.3, Fig. 4.7): the scans of one sweep of the tilt at one pan, kept as a
//! grid whose rows are the scans in the order they were taken and whose columns are the beams.
//!
//! The grid is the point of a scene: the neighbours of the reading of beam `i` in scan `j` are
//! the readings of beams `i ± 1` in scans `j`, `j ± 1`, whatever the pan and wherever the robot
//! stands, so a mesh is built by looking at four grid cells, never by searching space.

use crate::control::SceneTag;
use crate::geometry::Pose2;
use crate::hardware::LaserScan;
use crate::mount::{LaserMount, LaserPose};
use crate::time::Stamp;

/// Why a scene cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The scene has no scan whose laser pose is known.
    #[error("scene {scene}: no scan with a known laser pose (the head's angles were unknown)")]
    Empty {
        /// The scene's number.
        scene: usize,
    },
    /// Scans of one scene differ in their beams.
    #[error(
        "scene {scene}: the scan at {stamp} has {found} beams from {angle_min} rad, the first had {expected} from {expected_min} rad"
    )]
    Beams {
        /// The scene's number.
        scene: usize,
        /// The odd scan.
        stamp: Stamp,
        /// Its beams.
        found: usize,
        /// Its first angle.
        angle_min: f64,
        /// The first scan's beams.
        expected: usize,
        /// The first scan's first angle.
        expected_min: f64,
    },
}

/// One scan of a scene: the scan, where the base stood when it was measured, and where the laser
/// was on the base (`None` when the head's angles were unknown: the scan is left out).
#[derive(Copy, Clone, Debug)]
pub struct SceneScan<'a> {
    /// The scan.
    pub scan: &'a LaserScan,
    /// The base's pose in the world at the scan's stamp.
    pub base: Pose2,
    /// The laser's pose on the base at the scan's stamp.
    pub laser: Option<LaserPose>,
}

impl<'a> SceneScan<'a> {
    /// The scan placed by the laser's `mount` with the head's angles the scan carries.
    pub fn mounted(scan: &'a LaserScan, base: Pose2, mount: &LaserMount) -> Self {
        SceneScan {
            scan,
            base,
            laser: mount.laser_on_base(scan.head),
        }
    }
}

/// Points as three arrays of coordinates, which arithmetic can run on several at a time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Points {
    /// x of every point, metres.
    pub x: Vec<f32>,
    /// y of every point, metres.
    pub y: Vec<f32>,
    /// z of every point, metres.
    pub z: Vec<f32>,
}

impl Points {
    /// Points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Point `k`.
    pub fn get(&self, k: usize) -> Option<[f32; 3]> {
        Some([*self.x.get(k)?, *self.y.get(k)?, *self.z.get(k)?])
    }

    /// Sets point `k`; panics if there is no point `k`.
    pub fn set(&mut self, k: usize, p: [f32; 3]) {
        (self.x[k], self.y[k], self.z[k]) = (p[0], p[1], p[2]);
    }

    /// Every point in order.
    pub fn iter(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        (0..self.len()).map(|k| [self.x[k], self.y[k], self.z[k]])
    }

    /// Appends a point.
    pub fn push(&mut self, p: [f32; 3]) {
        self.x.push(p[0]);
        self.y.push(p[1]);
        self.z.push(p[2]);
    }

    fn clear(&mut self) {
        self.x.clear();
        self.y.clear();
        self.z.clear();
    }

    fn reserve(&mut self, n: usize) {
        self.x.reserve(n);
        self.y.reserve(n);
        self.z.reserve(n);
    }

    fn resize(&mut self, n: usize) {
        self.x.resize(n, 0.0);
        self.y.resize(n, 0.0);
        self.z.resize(n, 0.0);
    }
}

impl FromIterator<[f32; 3]> for Points {
    fn from_iter<I: IntoIterator<Item = [f32; 3]>>(points: I) -> Self {
        let mut out = Points::default();
        for p in points {
            out.push(p);
        }
        out
    }
}

/// The readings of one scene as a grid of 3D points in the world frame (z up).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Which scene and station.
    pub tag: SceneTag,
    /// Scans (grid rows).
    pub rows: usize,
    /// Beams per scan (grid columns).
    pub cols: usize,
    /// Row-major points, metres; a reading with no return is `NaN` in every coordinate.
    pub points: Points,
    /// Each row's laser optical centre, world frame, metres: where the readings were seen from.
    pub origins: Vec<[f32; 3]>,
    /// Each row's middle beam direction, world frame (unit).
    pub forwards: Vec<[f32; 3]>,
    /// Each row's scan-plane normal, world frame (unit): the laser's z axis.
    pub planes: Vec<[f32; 3]>,
    /// The base's pose at the first scan.
    pub base: Pose2,
    /// The head's pan at the first scan, radians (0 for a fixed laser).
    pub pan: f64,
    /// Scans left out because their laser pose was unknown.
    pub skipped: usize,
}

impl Scene {
    /// Builds the grid of `scans`, in the order they were taken, each placed by its laser pose
    /// on the base pose given beside it.
    pub fn build(tag: SceneTag, scans: &[SceneScan<'_>]) -> Result<Scene, SceneError> {
        let mut scene = Scene {
            tag,
            rows: 0,
            cols: 0,
            points: Points::default(),
            origins: Vec::new(),
            forwards: Vec::new(),
            planes: Vec::new(),
            base: Pose2::IDENTITY,
            pan: 0.0,
            skipped: 0,
        };
        scene.rebuild(tag, scans)?;
        Ok(scene)
    }

    /// As [`build`](Scene::build), into this scene's arrays: their memory is reused.
    pub fn rebuild(&mut self, tag: SceneTag, scans: &[SceneScan<'_>]) -> Result<(), SceneError> {
        let mut placed = scans.iter().filter_map(|s| Some((s, s.laser?.on(s.base))));
        let Some((first, _)) = placed.clone().next() else {
            return Err(SceneError::Empty { scene: tag.scene });
        };
        let cols = first.scan.len();
        let (angle_min, increment) = (first.scan.angle_min, first.scan.angle_increment);
        // The beams' directions in the laser's plane, once for the scene.
        let (sin, cos): (Vec<f32>, Vec<f32>) = (0..cols)
            .map(|i| {
                let (s, c) = (angle_min + i as f64 * increment).sin_cos();
                (s as f32, c as f32)
            })
            .unzip();
        self.tag = tag;
        self.rows = 0;
        self.cols = cols;
        self.points.clear();
        self.points.reserve(scans.len() * cols);
        self.origins.clear();
        self.forwards.clear();
        self.planes.clear();
        self.base = first.base;
        self.pan = first.scan.head.map_or(0.0, |h| h.pan);
        self.skipped = scans.len();
        for (s, laser) in placed.by_ref() {
            let scan = s.scan;
            if scan.len() != cols
                || scan.angle_min != angle_min
                || scan.angle_increment != increment
            {
                return Err(SceneError::Beams {
                    scene: tag.scene,
                    stamp: scan.stamp,
                    found: scan.len(),
                    angle_min: scan.angle_min,
                    expected: cols,
                    expected_min: angle_min,
                });
            }
            let r = laser.rotation();
            let column = |c: usize| [r[0][c] as f32, r[1][c] as f32, r[2][c] as f32];
            let (forward, left, plane) = (column(0), column(1), column(2));
            let o = laser.origin().map(|v| v as f32);
            let max = scan.range_max_mm;
            // Single precision: millimetre readings over tens of metres keep micrometres. A
            // reading with no return is scaled by NaN, without a branch.
            let start = self.points.len();
            self.points.resize(start + cols);
            let Points { x, y, z } = &mut self.points;
            let (x, y, z) = (
                &mut x[start..start + cols],
                &mut y[start..start + cols],
                &mut z[start..start + cols],
            );
            let (ranges, sin, cos) = (&scan.ranges_mm[..cols], &sin[..cols], &cos[..cols]);
            for i in 0..cols {
                let mm = ranges[i];
                let scale = if mm == 0 || mm >= max { f32::NAN } else { 1e-3 };
                let d = f32::from(mm) * scale;
                let (a, b) = (d * cos[i], d * sin[i]);
                x[i] = o[0] + a * forward[0] + b * left[0];
                y[i] = o[1] + a * forward[1] + b * left[1];
                z[i] = o[2] + a * forward[2] + b * left[2];
            }
            self.origins.push(o);
            self.forwards.push(forward);
            self.planes.push(plane);
            self.rows += 1;
        }
        self.skipped -= self.rows;
        Ok(())
    }

    /// The scenes of a run: `rows` are its scene scans in the order they were taken, each with
    /// its scene's tag; consecutive rows of one scene make one grid.
    pub fn group(rows: &[(SceneTag, SceneScan<'_>)]) -> Result<Vec<Scene>, SceneError> {
        let mut scenes = Vec::new();
        let mut start = 0;
        while start < rows.len() {
            let tag = rows[start].0;
            let end = start
                + rows[start..]
                    .iter()
                    .take_while(|(t, _)| t.scene == tag.scene)
                    .count();
            let scans: Vec<SceneScan<'_>> = rows[start..end].iter().map(|(_, s)| *s).collect();
            scenes.push(Scene::build(tag, &scans)?);
            start = end;
        }
        Ok(scenes)
    }

    /// The point of beam `col` in scan `row`, if it returned.
    pub fn point(&self, row: usize, col: usize) -> Option<[f32; 3]> {
        if col >= self.cols {
            return None;
        }
        let p = self.points.get(row * self.cols + col)?;
        (!p[0].is_nan()).then_some(p)
    }

    /// Readings that returned.
    pub fn returned(&self) -> usize {
        self.points.x.iter().filter(|x| !x.is_nan()).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::HeadAngles;
    use crate::mount::HeadGeometry;

    #[test]
    fn a_scene_is_a_grid_of_world_points_with_holes_for_no_returns() {
        let mount = LaserMount::Head(HeadGeometry::THESIS);
        let base = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
        let scans: Vec<LaserScan> = (0..3)
            .map(|j| {
                let mut s = LaserScan::sick_lms_half_degree(
                    Stamp::from_millis(100 * j as u64),
                    vec![2000; 361],
                );
                s.ranges_mm[0] = 32_000;
                s.head = Some(HeadAngles {
                    pan: 0.0,
                    tilt: (j as f64 * 10.0).to_radians(),
                });
                s
            })
            .collect();
        let mut rows: Vec<SceneScan<'_>> = scans
            .iter()
            .map(|scan| SceneScan::mounted(scan, base, &mount))
            .collect();
        let tag = SceneTag {
            scene: 0,
            station: 0,
        };
        let scene = Scene::build(tag, &rows).unwrap();
        assert_eq!((scene.rows, scene.cols), (3, 361));
        assert_eq!(scene.point(0, 0), None, "no return");
        assert_eq!(scene.returned(), 3 * 360);
        // The middle beam of the level scan: 2 m ahead of the laser, which looks along +y.
        let p = scene.point(0, 180).unwrap();
        assert!((p[0] - 1.0).abs() < 1e-5, "{p:?}");
        assert!((p[1] - (2.0 + 0.045 + 2.0)).abs() < 1e-5, "{p:?}");
        assert!((p[2] - 1.05).abs() < 1e-5, "{p:?}");
        // Tilted 20° up, it rises by 2 sin 20° above the swung laser centre.
        let q = scene.point(2, 180).unwrap();
        let o = scene.origins[2];
        assert!((q[2] - o[2] - 2.0 * 20f32.to_radians().sin()).abs() < 1e-5);
        // A scan whose head is unknown is left out; one with other beams is refused.
        let mut lost = scans[1].clone();
        lost.head = None;
        rows[1] = SceneScan::mounted(&lost, base, &mount);
        assert_eq!(Scene::build(tag, &rows).unwrap().skipped, 1);
        let short = LaserScan {
            ranges_mm: vec![1000; 181],
            ..scans[2].clone()
        };
        rows[2].scan = &short;
        assert!(matches!(
            Scene::build(tag, &rows),
            Err(SceneError::Beams { .. })
        ));
    }
}
