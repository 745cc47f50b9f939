//! The ring of Polaroid sonars (thesis §2.6.2): what one shot hears.
//!
//! A transducer sends a burst into a cone of about 15° and listens for the first echo. The model
//! samples the cone with a fan of rays, follows each through the world, and keeps the nearest echo
//! that comes back:
//!
//! - sound meets every material alike (glass and black surfaces echo like any wall);
//! - a smooth wall met beyond the **critical angle** reflects the burst away like a mirror — the
//!   classic specular loss of sonar — and the burst may come back after bouncing off another
//!   wall head-on, as a **long multi-bounce reading**;
//! - echoes nearer than the transducer's blanking distance (4 in) or farther than its range
//!   (40 ft) are not heard, and the firmware only listens for its echo window (`s2 Te Tr`).

use crate::config::robot_file::SonarDescription;
use crate::rng::SimRng;
use crate::world::{Hit, WorldMap};
use rand_distr::{Distribution, StandardNormal};
use robot::Pose2;

/// Reflections a burst may undergo before it is too weak to be heard.
const MAX_BOUNCES: u32 = 2;

/// The acoustic model of a ring of transducers.
#[derive(Clone, Debug)]
pub struct SonarModel {
    /// Each transducer's pose on the base (facing outward).
    transducers: Vec<Pose2>,
    /// Directions of the fan of rays relative to a transducer's axis, radians.
    fan: Vec<f64>,
    /// The fan's rays from the axis outwards: the nearest echo, which limits how far the
    /// others are followed, is most often on the axis.
    centre_first: Vec<usize>,
    min_range: f64,
    max_range: f64,
    /// Cosine of the critical angle of incidence.
    cos_critical: f64,
    sigma: f64,
    height: f64,
}

impl SonarModel {
    /// The ring described by `desc`: `count` transducers evenly spaced counter-clockwise from
    /// the front on a circle of `ring_radius_m` around a centre `center_x_m` ahead of the axle.
    pub fn new(desc: &SonarDescription) -> Self {
        let n = usize::from(desc.count);
        let transducers = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                let r = desc.ring_radius_m.get();
                Pose2::new(desc.center_x_m.get() + r * a.cos(), r * a.sin(), a)
            })
            .collect();
        let half = desc.cone_deg.get().to_radians() / 2.0;
        let rays = usize::from(desc.rays.max(1));
        let fan: Vec<f64> = (0..rays)
            .map(|i| {
                if rays == 1 {
                    0.0
                } else {
                    -half + 2.0 * half * i as f64 / (rays - 1) as f64
                }
            })
            .collect();
        let mut centre_first: Vec<usize> = (0..fan.len()).collect();
        centre_first.sort_by(|&a, &b| f64::abs(fan[a]).total_cmp(&f64::abs(fan[b])));
        SonarModel {
            transducers,
            centre_first,
            fan,
            min_range: desc.min_range_m.get(),
            max_range: desc.max_range_m.get(),
            cos_critical: desc.critical_deg.get().to_radians().cos(),
            sigma: desc.sigma_m.get(),
            height: desc.height_m.get(),
        }
    }

    /// Number of transducers.
    pub fn len(&self) -> usize {
        self.transducers.len()
    }

    /// Whether the ring has no transducer.
    pub fn is_empty(&self) -> bool {
        self.transducers.is_empty()
    }

    /// Full width of a transducer's cone, radians.
    pub fn cone(&self) -> f64 {
        let (lo, hi) = self
            .fan
            .iter()
            .fold((0.0f64, 0.0f64), |(lo, hi), a| (lo.min(*a), hi.max(*a)));
        hi - lo
    }

    /// Transducer `k`'s pose on the base.
    pub fn transducer(&self, k: usize) -> Option<Pose2> {
        self.transducers.get(k).copied()
    }

    /// The distance transducer `k` hears with the base at `base`, or `None` for no echo.
    pub fn echo(&self, map: &WorldMap, base: Pose2, k: usize, rng: &mut SimRng) -> Option<f64> {
        let (origin, dirs) = self.rays(base, k)?;
        // Each ray followed only as far as the nearest echo so far (a longer path cannot bring
        // a nearer one), the axis first, where the nearest echo most often is.
        let mut nearest = f64::INFINITY;
        for &k in &self.centre_first {
            let first = map.cast(origin, dirs[k], self.max_range.min(nearest));
            if let Some(r) = self.follow(map, origin, dirs[k], first, nearest, false) {
                nearest = nearest.min(r);
            }
        }
        self.heard(nearest, rng)
    }

    /// [`SonarModel::echo`] with each ray of the cone followed to its end, every leg cast down
    /// the world's tree instead of walking the plan's grid: the reference the early stop and
    /// the walk are tested and benchmarked against.
    pub fn echo_per_ray(
        &self,
        map: &WorldMap,
        base: Pose2,
        k: usize,
        rng: &mut SimRng,
    ) -> Option<f64> {
        let (origin, dirs) = self.rays(base, k)?;
        let nearest = dirs
            .iter()
            .filter_map(|&dir| {
                let first = map.cast_down_tree(origin, dir, self.max_range);
                self.follow(map, origin, dir, first, f64::INFINITY, true)
            })
            .fold(f64::INFINITY, f64::min);
        self.heard(nearest, rng)
    }

    /// Transducer `k`'s origin and its cone's rays with the base at `base`.
    fn rays(&self, base: Pose2, k: usize) -> Option<([f64; 3], Vec<[f64; 3]>)> {
        let sensor = base.compose(self.transducers.get(k)?);
        let dirs = self
            .fan
            .iter()
            .map(|offset| {
                let (s, c) = (sensor.theta + offset).sin_cos();
                [c, s, 0.0]
            })
            .collect();
        Some(([sensor.x, sensor.y, self.height], dirs))
    }

    /// What the receiver reports for the nearest path heard: the distance with its noise.
    fn heard(&self, nearest: f64, rng: &mut SimRng) -> Option<f64> {
        if !nearest.is_finite() {
            return None;
        }
        let noise: f64 = StandardNormal.sample(rng);
        Some((nearest + self.sigma * noise).max(self.min_range))
    }

    /// Follows one ray of the burst from `origin` along `dir`, `first` being what its first leg
    /// meets; the one-way path length of the echo it brings back, if it is heard and not longer
    /// than `limit`. Later legs go down the tree with `down_tree`.
    fn follow(
        &self,
        map: &WorldMap,
        origin: [f64; 3],
        dir: [f64; 3],
        first: Option<Hit>,
        limit: f64,
        down_tree: bool,
    ) -> Option<f64> {
        let (mut o, mut d) = ([origin[0], origin[1]], [dir[0], dir[1]]);
        let mut travelled = 0.0;
        let reach = self.max_range.min(limit);
        for leg in 0..=MAX_BOUNCES {
            let hit = if leg == 0 {
                first.filter(|h| h.distance <= reach)?
            } else {
                let max = reach - travelled;
                if down_tree {
                    map.cast_down_tree([o[0], o[1], self.height], [d[0], d[1], 0.0], max)?
                } else {
                    map.cast_level(o, self.height, d, max)?
                }
            };
            travelled += hit.distance;
            let n = [hit.normal[0], hit.normal[1]];
            let cos_incidence = -(d[0] * n[0] + d[1] * n[1]);
            if cos_incidence >= self.cos_critical {
                return (travelled >= self.min_range).then_some(travelled);
            }
            // Specular: the burst goes on, mirrored.
            let k = 2.0 * (d[0] * n[0] + d[1] * n[1]);
            let p = [o[0] + d[0] * hit.distance, o[1] + d[1] * hit.distance];
            d = [d[0] - k * n[0], d[1] - k * n[1]];
            o = [p[0] + n[0] * 1e-5, p[1] + n[1] * 1e-5];
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::WorldDescription;
    use crate::config::values::{Angle, Finite, Positive, Sigma};

    fn ring() -> SonarModel {
        SonarModel::new(&SonarDescription {
            count: 16,
            ring_radius_m: Positive(0.2),
            center_x_m: Finite(0.0),
            cone_deg: Positive(15.0),
            rays: 7,
            min_range_m: Positive(0.1016),
            max_range_m: Positive(12.19),
            critical_deg: Angle(25.0),
            sigma_m: Sigma(0.0),
            height_m: Positive(0.2),
        })
    }

    fn map(text: &str) -> WorldMap {
        WorldMap::new(&WorldDescription::parse(text, "t.toml").unwrap())
    }

    const WALL_AHEAD: &str =
        "name = \"w\"\n[start]\nx = 0\ny = 0\n[[wall]]\npoints = [[2, -20], [2, 20]]\n";

    #[test]
    fn transducers_are_numbered_counter_clockwise_from_the_front() {
        let r = ring();
        assert_eq!(r.len(), 16);
        let front = r.transducer(0).unwrap();
        assert!((front.x - 0.2).abs() < 1e-12 && front.y.abs() < 1e-12 && front.theta == 0.0);
        let left = r.transducer(4).unwrap();
        assert!(
            left.x.abs() < 1e-12 && (left.y - 0.2).abs() < 1e-12,
            "{left:?}"
        );
    }

    #[test]
    fn facing_a_wall_the_front_sonar_hears_its_distance() {
        let d = ring()
            .echo(
                &map(WALL_AHEAD),
                Pose2::IDENTITY,
                0,
                &mut crate::rng::substream(1, 0),
            )
            .unwrap();
        assert!((d - 1.8).abs() < 1e-5, "{d}");
        // The one facing away hears nothing (no wall behind).
        assert_eq!(
            ring().echo(
                &map(WALL_AHEAD),
                Pose2::IDENTITY,
                8,
                &mut crate::rng::substream(1, 0)
            ),
            None
        );
    }

    #[test]
    fn a_wall_at_45_degrees_reflects_the_burst_away() {
        let turned = Pose2::new(0.0, 0.0, 45f64.to_radians());
        let e = ring().echo(
            &map(WALL_AHEAD),
            turned,
            0,
            &mut crate::rng::substream(1, 0),
        );
        assert_eq!(e, None);
    }

    #[test]
    fn a_wall_met_after_a_reflection_gives_a_long_multi_bounce_echo() {
        // The wall x = 2, met at 45°, mirrors the burst up-left onto the wall y = x + 6, which it
        // meets head-on: the echo returns the same way, after 2.63 m + 4.24 m.
        let walls = "name = \"c\"\n[start]\nx = 0\ny = 0\n[[wall]]\npoints = [[2, -20], [2, 20]]\n[[wall]]\npoints = [[-2, 4], [1, 7]]\n";
        let turned = Pose2::new(0.0, 0.0, 45f64.to_radians());
        let d = ring()
            .echo(&map(walls), turned, 0, &mut crate::rng::substream(1, 0))
            .unwrap();
        assert!(d > 6.0 && d < 7.0, "{d}");
    }

    #[test]
    fn the_early_stop_hears_what_every_ray_followed_to_its_end_hears() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let robot =
            crate::config::RobotDescription::load(root.join("scenarios/robots/pioneer-3dx.toml"))
                .unwrap();
        let ring = SonarModel::new(robot.sonar.as_ref().unwrap());
        for world in ["lab", "glass-door", "sonar-wall", "black-door-corridor"] {
            let desc =
                WorldDescription::load(root.join("worlds").join(format!("{world}.toml"))).unwrap();
            let map = WorldMap::new(&desc);
            let (min, max) = desc.bounds();
            let mut heard = 0;
            for i in 0..400u32 {
                let f = |k: u32, n: u32| f64::from(k % n) / f64::from(n);
                let base = Pose2::new(
                    min[0] + (max[0] - min[0]) * f(i * 7, 23),
                    min[1] + (max[1] - min[1]) * f(i * 11, 19),
                    std::f64::consts::TAU * f(i * 13, 29),
                );
                let k = (i % 16) as usize;
                let fast = ring.echo(&map, base, k, &mut crate::rng::substream(1, u64::from(i)));
                let reference =
                    ring.echo_per_ray(&map, base, k, &mut crate::rng::substream(1, u64::from(i)));
                assert_eq!(fast, reference, "{world}, {base:?}, transducer {k}");
                heard += usize::from(fast.is_some());
            }
            assert!(heard > 100, "{world}: {heard} of 400 heard");
        }
    }
}
