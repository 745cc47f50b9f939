//! Controllers that sense and react: go to a goal among obstacles (`goto X Y`), and follow
//! walls to explore a room without a goal (`explore SECONDS`).
//!
//! Both drive with the firmware's own short motions — a turn in place (`i`/`d`), then a straight
//! move (`a`) no longer than the free way measured ahead — and look again at rest after each:
//! the stop-and-go pacing of the thesis's tours. The firmware ends every such motion by itself on
//! its ramp, so a motion chosen against what the robot saw cannot run on past it; `v` would
//! need the host to stop the wheels in time over the serial line, and its ramp-down quirk
//! (App. A: the ramp is only used by the motion commands) makes that stop abrupt.
//!
//! **The local method** is a vector field histogram in its simplest form (Borenstein & Koren
//! 1991, VFH+): what the laser and the sonar ring saw is kept as points around the robot; every
//! candidate heading, 5° apart all round, gets the free distance a disc of the robot's
//! footprint (plus a margin) can travel along it before touching a point; the controller takes
//! the admissible heading nearest the goal's bearing, preferring its current heading. A heading
//! outside the laser's view is only turned to, never driven along, until a scan at rest has
//! looked that way.
//!
//! **Why the sonar matters**: glass is often a window to the laser, and a black surface at an
//! angle returns nothing; the sonar ring hears both (a burst reflects off glass as off a wall).
//! Its echoes enter the same points, spread across each transducer's cone.
//!
//! **When it stops** (a [`NavOutcome`] with its reason): at the goal within the tolerance; when
//! no heading is free; when the estimate is lost (the scan matcher's last answers untrusted);
//! when the robot has made no progress towards the goal for a number of decisions (a closed way,
//! or a local minimum the local method cannot leave); when its decisions run out.

use crate::geometry::{Pose2, wrap_angle};
use crate::mount::LaserMount;
use core::f64::consts::PI;
use core::fmt;
use std::collections::VecDeque;

/// How a robot of the thesis's size navigates.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct NavConfig {
    /// Radius of the robot's round footprint, metres.
    pub radius_m: f64,
    /// The footprint's centre ahead of the wheel axle, metres (negative: behind). A turn in
    /// place swings it round the axle by this much.
    pub center_x_m: f64,
    /// Clearance kept from anything seen, metres.
    pub margin_m: f64,
    /// The smaller clearance accepted when no heading keeps `margin_m` (a narrow door), metres.
    pub tight_margin_m: f64,
    /// Longest straight move before looking again, metres.
    pub step_m: f64,
    /// Shortest move worth making, metres: a heading whose free way is shorter is not
    /// admissible.
    pub min_step_m: f64,
    /// The goal is reached within this distance, metres.
    pub tolerance_m: f64,
    /// Spacing of the candidate headings, radians.
    pub heading_step_rad: f64,
    /// Half the laser's field of view, radians: headings beyond it are turned to first.
    pub view_half_rad: f64,
    /// Largest turn in one motion, radians: consecutive scans keep enough view in common for
    /// the scan matcher (a half-turn at once leaves a 180° laser nothing to match).
    pub max_turn_rad: f64,
    /// Scans kept as obstacle points (the newest ones).
    pub memory: usize,
    /// Untrusted scan matches in a row after which the robot is lost.
    pub lost_after: usize,
    /// Decisions without coming `progress_m` nearer the goal after which the way is closed.
    pub patience: usize,
    /// Progress that resets the patience, metres.
    pub progress_m: f64,
    /// Most decisions a `goto` step may take (an `explore` step is bounded by its time).
    pub max_decisions: usize,
    /// Distance kept from the wall on the right when exploring, metres.
    pub wall_distance_m: f64,
    /// The sonar ring, when the robot fires it.
    pub sonar: Option<SonarLayout>,
    /// Where the laser is on the base: its scans become points around the robot.
    pub mount: LaserMount,
    /// How a `goto` step picks its heading.
    pub method: Method,
    /// Scans whose plane is further from level than this are not used, radians.
    pub level_tolerance_rad: f64,
}

impl NavConfig {
    /// The defaults for a round footprint of `radius_m` centred `center_x_m` ahead of the axle
    /// and a laser at `mount`.
    pub fn new(radius_m: f64, center_x_m: f64, mount: LaserMount) -> Self {
        NavConfig {
            center_x_m,
            tight_margin_m: 0.04,
            mount,
            // As the 2D localisation: half a tilt position of the thesis's head.
            level_tolerance_rad: 0.3f64.to_radians(),
            method: Method::Histogram,
            radius_m,
            margin_m: 0.12,
            step_m: 0.6,
            min_step_m: 0.08,
            tolerance_m: 0.15,
            heading_step_rad: 5f64.to_radians(),
            view_half_rad: 85f64.to_radians(),
            max_turn_rad: 30f64.to_radians(),
            memory: 10,
            lost_after: 3,
            patience: 40,
            progress_m: 0.15,
            max_decisions: 400,
            wall_distance_m: 0.45,
            sonar: None,
        }
    }
}

impl Default for NavConfig {
    /// A Pioneer 3-DX: a 0.26 m body 4.55 cm behind the axle, its laser 0.16 m ahead of the
    /// axle at 0.3 m.
    fn default() -> Self {
        let mount = LaserMount::Fixed {
            pose: Pose2::new(0.16, 0.0, 0.0),
            z: 0.3,
        };
        NavConfig::new(0.26, -0.0455, mount)
    }
}

/// How a `goto` step picks its heading.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Method {
    /// The vector field histogram: the free heading nearest the goal's bearing.
    Histogram,
    /// The baseline it is measured against: straight at the goal as far as the way is free,
    /// blocked when it is not (no way round).
    Direct,
}

impl core::str::FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "histogram" => Ok(Method::Histogram),
            "direct" => Ok(Method::Direct),
            other => Err(format!(
                "unknown method {other:?}: expected \"histogram\" or \"direct\""
            )),
        }
    }
}

/// A ring of sonar transducers evenly spaced counter-clockwise from the front.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SonarLayout {
    /// Transducers on the ring.
    pub count: u8,
    /// Radius of the ring, metres.
    pub ring_radius_m: f64,
    /// The ring's centre ahead of the axle, metres.
    pub center_x_m: f64,
    /// Full width of a transducer's cone, radians.
    pub cone_rad: f64,
    /// Speed of sound used to turn echo times into distances, m/s.
    pub speed_of_sound: f64,
    /// Farthest echo worth a point, metres.
    pub max_range_m: f64,
    /// Time for the ring to fire its whole sequence once: the controller waits this long at
    /// rest before it reads the ring, so every echo was heard from where the robot stands.
    pub cycle: core::time::Duration,
}

impl SonarLayout {
    /// Where transducer `k` sits on the base, facing out.
    pub fn transducer(&self, k: u8) -> Pose2 {
        let a = 2.0 * PI * f64::from(k) / f64::from(self.count.max(1));
        Pose2::new(
            self.center_x_m + self.ring_radius_m * a.cos(),
            self.ring_radius_m * a.sin(),
            wrap_angle(a),
        )
    }

    /// Obstacle points on the base for an echo of transducer `k` at `range_m`: spread across
    /// the cone, since the burst does not say where in it the echo came from.
    pub fn echo_points(&self, k: u8, range_m: f64) -> impl Iterator<Item = [f64; 2]> + '_ {
        let t = self.transducer(k);
        let half = self.cone_rad / 2.0;
        (0..5).map(move |i| {
            let a = -half + half * f64::from(i) / 2.0;
            let (x, y) = t.transform_point(range_m * a.cos(), range_m * a.sin());
            [x, y]
        })
    }
}

/// What the robot saw lately, as points in the odometry frame: the returns of the last few
/// scans and the echoes of the last few sonar cycles. A black surface at an angle returns the
/// laser nothing and a wall at grazing incidence reflects the sonar's burst away: what was seen
/// head-on a few stops ago is remembered.
#[derive(Clone, Debug, Default)]
pub struct Surroundings {
    scans: VecDeque<Vec<[f64; 2]>>,
    sonar: VecDeque<Vec<[f64; 2]>>,
}

impl Surroundings {
    /// Adds a scan's returns (odometry frame), forgetting the oldest beyond `memory` scans.
    pub fn add_scan(&mut self, points: Vec<[f64; 2]>, memory: usize) {
        remember(&mut self.scans, points, memory);
    }

    /// Adds a sonar cycle's echoes (odometry frame), forgetting the oldest beyond `memory`.
    pub fn add_sonar(&mut self, points: Vec<[f64; 2]>, memory: usize) {
        remember(&mut self.sonar, points, memory);
    }

    /// Every point, odometry frame.
    pub fn points(&self) -> impl Iterator<Item = &[f64; 2]> {
        self.scans.iter().chain(&self.sonar).flatten()
    }

    /// The points as seen from `pose` (odometry frame), in its own frame.
    pub fn around(&self, pose: Pose2) -> Vec<[f64; 2]> {
        let inv = pose.inverse();
        self.points()
            .map(|p| {
                let (x, y) = inv.transform_point(p[0], p[1]);
                [x, y]
            })
            .collect()
    }
}

fn remember(list: &mut VecDeque<Vec<[f64; 2]>>, points: Vec<[f64; 2]>, memory: usize) {
    list.push_back(points);
    while list.len() > memory.max(1) {
        list.pop_front();
    }
}

/// How far a disc of radius `r` centred at the origin can travel along `heading` (radians, the
/// robot's frame) before it touches one of `points` (robot frame); `f64::INFINITY` if never.
/// Points behind the disc's path do not block it, nor do points it is already moving away from.
pub fn free_distance(points: impl IntoIterator<Item = [f64; 2]>, heading: f64, r: f64) -> f64 {
    let (s, c) = heading.sin_cos();
    let r2 = r * r;
    let mut free = f64::INFINITY;
    for p in points {
        let along = p[0] * c + p[1] * s;
        if along <= 0.0 {
            continue;
        }
        let across = -p[0] * s + p[1] * c;
        let a2 = across * across;
        if a2 < r2 {
            free = free.min((along - (r2 - a2).sqrt()).max(0.0));
        }
    }
    free
}

/// One decision of a controller.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Decision {
    /// Turn in place by `turn_rad` (positive left), then advance `advance_m` (may be 0: turn
    /// first and look).
    Motion {
        /// Turn, radians.
        turn_rad: f64,
        /// Straight move after the turn, metres.
        advance_m: f64,
        /// The free way measured along the chosen heading, metres.
        free_m: f64,
    },
    /// The step is over.
    Done(NavOutcome),
}

/// How a `goto` or `explore` step ended.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum NavOutcome {
    /// Within the tolerance of the goal (by the estimate), `distance_m` from it.
    Reached {
        /// Distance left, metres.
        distance_m: f64,
    },
    /// Explored for the time asked.
    Explored,
    /// No heading is free: everything within reach is closer than the footprint and margin.
    Blocked {
        /// The nearest point seen, metres from the axle's centre.
        nearest_m: f64,
    },
    /// No progress towards the goal for the controller's patience: a closed way.
    NoWay {
        /// Distance still to go, metres.
        distance_m: f64,
    },
    /// The scan matcher's answers were untrusted this many times in a row.
    Lost {
        /// Untrusted answers in a row.
        untrusted: usize,
    },
    /// The step took its most decisions.
    OutOfDecisions {
        /// Distance still to go (0 when exploring), metres.
        distance_m: f64,
    },
}

impl NavOutcome {
    /// Whether the step did what it was asked.
    pub fn succeeded(&self) -> bool {
        matches!(self, NavOutcome::Reached { .. } | NavOutcome::Explored)
    }
}

impl fmt::Display for NavOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NavOutcome::Reached { distance_m } => {
                write!(f, "reached: {distance_m:.3} m from the goal")
            }
            NavOutcome::Explored => write!(f, "explored for the time asked"),
            NavOutcome::Blocked { nearest_m } => write!(
                f,
                "blocked: no heading is free (nearest obstacle {nearest_m:.2} m from the axle)"
            ),
            NavOutcome::NoWay { distance_m } => write!(
                f,
                "no way: no progress towards the goal, {distance_m:.2} m away, for the controller's patience"
            ),
            NavOutcome::Lost { untrusted } => write!(
                f,
                "lost: the last {untrusted} scan matches were not trusted"
            ),
            NavOutcome::OutOfDecisions { distance_m } => {
                write!(f, "out of decisions with {distance_m:.2} m to go")
            }
        }
    }
}

/// Free way reported for a heading nothing blocks, metres (files carry no infinity).
pub const FAR_M: f64 = 100.0;

/// How far the robot's footprint, inflated by `margin`, can go along `heading` (its frame)
/// after turning to it in place: the footprint's centre swings round the axle with the turn.
fn free_along(points: &[[f64; 2]], heading: f64, margin: f64, config: &NavConfig) -> f64 {
    let (cx, cy) = (
        config.center_x_m * heading.cos(),
        config.center_x_m * heading.sin(),
    );
    let shifted = points.iter().map(|p| [p[0] - cx, p[1] - cy]);
    free_distance(shifted, heading, config.radius_m + margin).min(FAR_M)
}

/// The candidate headings all round, robot frame, straight ahead first.
fn headings(config: &NavConfig) -> impl Iterator<Item = f64> {
    let n = (2.0 * PI / config.heading_step_rad).round().max(8.0) as i32;
    let step = 2.0 * PI / f64::from(n);
    (0..n).map(move |i| {
        // 0, +1, -1, +2, -2, ...: ties go to the smaller turn, left first.
        let k = if i % 2 == 1 { (i + 1) / 2 } else { -(i / 2) };
        wrap_angle(f64::from(k) * step)
    })
}

/// The motion towards `heading` (robot frame) with `free` metres of free way: at most
/// `max_turn_rad` at once; turn first and look when the heading is outside the laser's view,
/// else turn and go.
fn motion(heading: f64, free: f64, want: f64, config: &NavConfig) -> Decision {
    let free = free.min(FAR_M);
    if heading.abs() > config.max_turn_rad {
        // Part of the way round, then look again.
        return Decision::Motion {
            turn_rad: config.max_turn_rad.copysign(heading),
            advance_m: 0.0,
            free_m: free,
        };
    }
    let advance = if heading.abs() > config.view_half_rad {
        0.0
    } else {
        want.min(free).min(config.step_m).max(0.0)
    };
    Decision::Motion {
        turn_rad: heading,
        advance_m: advance,
        free_m: free,
    }
}

/// The next decision towards `goal` (map frame) from `pose` (the estimate, map frame), with
/// `points` seen around the robot (its own frame).
///
/// Straight at the goal when that way is free; otherwise the heading nearest the goal's bearing
/// (and the least turn) that is free for two steps with the full margin, then for one, then
/// for one with the tight margin, then for a short step; blocked when none is.
pub fn goto_decision(
    pose: Pose2,
    goal: [f64; 2],
    points: &[[f64; 2]],
    config: &NavConfig,
) -> Decision {
    let (dx, dy) = (goal[0] - pose.x, goal[1] - pose.y);
    let distance = dx.hypot(dy);
    if distance <= config.tolerance_m {
        return Decision::Done(NavOutcome::Reached {
            distance_m: distance,
        });
    }
    let bearing = wrap_angle(dy.atan2(dx) - pose.theta);
    let full = distance.min(config.step_m);
    let direct = free_along(points, bearing, config.margin_m, config);
    if direct >= full {
        return motion(bearing, direct, distance, config);
    }
    if config.method == Method::Direct {
        return if direct >= config.min_step_m {
            motion(bearing, direct, distance, config)
        } else {
            Decision::Done(NavOutcome::Blocked {
                nearest_m: nearest(points),
            })
        };
    }
    let cost = |h: f64| wrap_angle(h - bearing).abs() + 0.25 * h.abs();
    // The free way all round, once per margin (the tight one only when the full one fails).
    let histogram = |margin: f64| -> Vec<(f64, f64)> {
        headings(config)
            .map(|h| (h, free_along(points, h, margin, config)))
            .collect()
    };
    let pick = |histogram: &[(f64, f64)], least: f64| {
        histogram
            .iter()
            .copied()
            .filter(|&(_, free)| free >= least)
            .min_by(|a, b| cost(a.0).total_cmp(&cost(b.0)))
    };
    // A way open for two steps first: one step into a dead end is no way round.
    let long = distance.min(2.0 * config.step_m);
    let roomy = histogram(config.margin_m);
    let best = pick(&roomy, long)
        .or_else(|| pick(&roomy, full))
        .or_else(|| {
            let tight = histogram(config.tight_margin_m);
            pick(&tight, full).or_else(|| pick(&tight, config.min_step_m))
        });
    if let Some((h, free)) = best {
        return motion(h, free, distance, config);
    }
    Decision::Done(NavOutcome::Blocked {
        nearest_m: nearest(points),
    })
}

/// The next decision of a right-hand wall follower with `points` around the robot (its own
/// frame): with no wall within reach on the right it goes straight to find one; with a wall
/// it takes the rightmost free heading (at most 60° right), so it keeps the wall at
/// `wall_distance_m` on its right and turns left at corners.
pub fn explore_decision(points: &[[f64; 2]], config: &NavConfig) -> Decision {
    let hug = config.wall_distance_m;
    let right_wall = points
        .iter()
        .filter(|p| {
            let a = p[1].atan2(p[0]);
            (-120f64.to_radians()..=-45f64.to_radians()).contains(&a)
        })
        .map(|p| p[0].hypot(p[1]))
        .fold(f64::INFINITY, f64::min);
    let ahead = free_along(points, 0.0, config.margin_m, config);
    if right_wall > 2.0 * (config.radius_m + hug) && ahead >= config.step_m {
        return motion(0.0, ahead, config.step_m, config);
    }
    let n = (PI / config.heading_step_rad).round() as i32;
    // From 60° right to 90° left: the first heading free of the wall by `hug` for a step.
    for i in -(n / 3)..=n / 2 {
        let h = f64::from(i) * config.heading_step_rad;
        if free_along(points, h, hug, config) >= config.step_m {
            let free = free_along(points, h, config.margin_m, config);
            return motion(h, free, config.step_m, config);
        }
    }
    // A dead end: the freest heading all round, or nothing.
    match headings(config)
        .map(|h| (h, free_along(points, h, config.tight_margin_m, config)))
        .filter(|&(_, free)| free >= config.min_step_m)
        .max_by(|a, b| a.1.total_cmp(&b.1))
    {
        Some((h, free)) => motion(h, free, config.step_m, config),
        None => Decision::Done(NavOutcome::Blocked {
            nearest_m: nearest(points),
        }),
    }
}

fn nearest(points: &[[f64; 2]]) -> f64 {
    points
        .iter()
        .map(|p| p[0].hypot(p[1]))
        .fold(FAR_M, f64::min)
}

/// Watches a goal-seeking step for progress.
#[derive(Clone, Debug)]
pub struct Progress {
    best: f64,
    since: usize,
}

impl Progress {
    /// A step starting `distance` metres from its goal.
    pub fn new(distance: f64) -> Self {
        Progress {
            best: distance,
            since: 0,
        }
    }

    /// Notes the distance after a decision; whether the patience has run out.
    pub fn stalled(&mut self, distance: f64, config: &NavConfig) -> bool {
        if distance < self.best - config.progress_m {
            self.best = distance;
            self.since = 0;
        } else {
            self.since += 1;
        }
        self.since >= config.patience
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall(x: f64, from: f64, to: f64) -> Vec<[f64; 2]> {
        let n = ((to - from) / 0.02) as usize;
        (0..=n).map(|i| [x, from + 0.02 * i as f64]).collect()
    }

    #[test]
    fn free_distance_is_where_the_disc_touches() {
        let pts = wall(2.0, -1.0, 1.0);
        assert!((free_distance(pts.iter().copied(), 0.0, 0.4) - 1.6).abs() < 1e-9);
        // Moving away, or alongside beyond the radius, nothing blocks.
        assert!(free_distance(pts.iter().copied(), PI, 0.4).is_infinite());
        assert!(free_distance([[0.0, 0.5]], 0.0, 0.4).is_infinite());
        // A point already inside the disc ahead stops it at once.
        assert_eq!(free_distance([[0.1, 0.0]], 0.0, 0.4), 0.0);
    }

    #[test]
    fn the_footprint_swings_round_the_axle_and_takes_a_narrow_door() {
        let c = NavConfig::default();
        // A point 0.5 m ahead: the body's centre is 4.55 cm behind the axle.
        let ahead = free_along(&[[0.5, 0.0]], 0.0, 0.0, &c);
        assert!(
            (ahead - (0.5 - c.center_x_m - c.radius_m)).abs() < 1e-9,
            "{ahead}"
        );
        // A door 0.65 m wide, 1 m ahead: too narrow for the full margin, through with the
        // tight one.
        let mut door = wall(1.0, -2.0, -0.325);
        door.extend(wall(1.0, 0.325, 2.0));
        assert!(free_along(&door, 0.0, c.margin_m, &c) < 1.0);
        assert!(free_along(&door, 0.0, c.tight_margin_m, &c) == FAR_M);
        let d = goto_decision(Pose2::IDENTITY, [3.0, 0.0], &door, &c);
        assert!(
            matches!(d, Decision::Motion { turn_rad, advance_m, .. } if turn_rad == 0.0 && advance_m == c.step_m),
            "{d:?}"
        );
    }

    #[test]
    fn goes_straight_when_free_and_stops_at_the_goal() {
        let c = NavConfig::default();
        match goto_decision(Pose2::IDENTITY, [3.0, 0.0], &[], &c) {
            Decision::Motion {
                turn_rad,
                advance_m,
                ..
            } => {
                assert_eq!(turn_rad, 0.0);
                assert_eq!(advance_m, c.step_m);
            }
            d => panic!("{d:?}"),
        }
        let near = goto_decision(Pose2::new(2.9, 0.0, 1.0), [3.0, 0.0], &[], &c);
        assert!(matches!(near, Decision::Done(NavOutcome::Reached { .. })));
    }

    #[test]
    fn goes_round_a_wall_in_the_way_and_turns_before_driving_blind() {
        let c = NavConfig::default();
        let pts = wall(0.7, -0.3, 2.0); // a wall across, open to the right
        let Decision::Motion {
            turn_rad,
            advance_m,
            ..
        } = goto_decision(Pose2::IDENTITY, [3.0, 0.0], &pts, &c)
        else {
            panic!("a way round exists")
        };
        assert!(turn_rad < 0.0, "round the open end, right: {turn_rad}");
        // Either on its way, or turning as far as one motion may before looking again.
        assert!(
            advance_m > 0.0 || turn_rad == -c.max_turn_rad,
            "{advance_m} {turn_rad}"
        );
        // A goal behind: turn part of the way to look first, no advance.
        let d = goto_decision(Pose2::IDENTITY, [-3.0, 0.0], &[], &c);
        assert!(
            matches!(d, Decision::Motion { advance_m, turn_rad, .. } if advance_m == 0.0 && turn_rad.abs() == c.max_turn_rad)
        );
    }

    #[test]
    fn the_direct_baseline_has_no_way_round() {
        let c = NavConfig {
            method: Method::Direct,
            ..NavConfig::default()
        };
        let pts = wall(0.4, -0.3, 2.0);
        let d = goto_decision(Pose2::IDENTITY, [3.0, 0.0], &pts, &c);
        assert!(
            matches!(d, Decision::Done(NavOutcome::Blocked { .. })),
            "{d:?}"
        );
        assert_eq!("direct".parse(), Ok(Method::Direct));
        assert!("astar".parse::<Method>().unwrap_err().contains("histogram"));
    }

    #[test]
    fn boxed_in_is_blocked() {
        let c = NavConfig::default();
        let ring: Vec<[f64; 2]> = (0..360)
            .map(|i| {
                let a = f64::from(i).to_radians();
                [0.3 * a.cos(), 0.3 * a.sin()]
            })
            .collect();
        let d = goto_decision(Pose2::IDENTITY, [3.0, 0.0], &ring, &c);
        assert!(
            matches!(d, Decision::Done(NavOutcome::Blocked { nearest_m }) if (nearest_m - 0.3).abs() < 1e-9)
        );
    }

    #[test]
    fn the_wall_follower_keeps_the_wall_on_its_right() {
        let c = NavConfig::default();
        // A wall along the right, 0.8 m away: go on along it.
        let side: Vec<[f64; 2]> = (0..200)
            .map(|i| [-1.0 + 0.02 * f64::from(i), -0.8])
            .collect();
        let Decision::Motion { turn_rad, .. } = explore_decision(&side, &c) else {
            panic!()
        };
        assert!(turn_rad.abs() <= 20f64.to_radians(), "{turn_rad}");
        // A corner: the wall ahead too; turn left.
        let mut corner = side.clone();
        corner.extend(wall(0.8, -0.8, 1.5));
        let Decision::Motion { turn_rad, .. } = explore_decision(&corner, &c) else {
            panic!()
        };
        assert!(turn_rad > 0.3, "{turn_rad}");
    }

    #[test]
    fn sonar_echoes_spread_over_the_cone() {
        let ring = SonarLayout {
            count: 16,
            ring_radius_m: 0.2,
            center_x_m: 0.0,
            cone_rad: 15f64.to_radians(),
            speed_of_sound: 343.0,
            max_range_m: 5.0,
            cycle: core::time::Duration::from_millis(1000),
        };
        let pts: Vec<_> = ring.echo_points(4, 1.0).collect(); // facing left
        assert_eq!(pts.len(), 5);
        for p in &pts {
            assert!((p[0].hypot(p[1] - 0.2) - 1.0).abs() < 1e-9);
        }
        assert!(pts[0][0] > 0.1 && pts[4][0] < -0.1);
    }

    #[test]
    fn patience_runs_out_without_progress() {
        let c = NavConfig::default();
        let mut p = Progress::new(5.0);
        for _ in 0..c.patience - 1 {
            assert!(!p.stalled(5.0, &c));
        }
        assert!(!p.stalled(4.0, &c), "progress resets it");
        assert!((0..c.patience).any(|_| p.stalled(4.0, &c)));
    }
}
