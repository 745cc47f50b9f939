//! What a run produced, in memory: each kept scan with the odometry and the twin's truth beside
//! it, the true path, the sonar ring's last reading, the scan-matching estimate, the 3D models. The files of
//! [`crate::output`] and the checks of [`crate::commands::check`] are computed from it.

pub mod dots;

pub use dots::ScanDots;

use crate::devices::laser::LaserFrame;
use crate::world::score::Accuracy;
use robot::control::SceneTag;
use robot::hardware::{LaserScan, PanTiltStatus};
use robot::localization::{MatcherKind, Placed};
use robot::reconstruction::{MeshOptions, Model};
use robot::{Pose2, Stamp};
use serde::Serialize;

/// One scan as recorded by a run.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanRecord {
    /// The scan as the robot received it.
    pub scan: LaserScan,
    /// The robot's odometry at the scan's stamp (world frame: it starts at the start pose).
    pub odometry: Pose2,
    /// The true pose of the base at the scan's stamp.
    pub truth: Pose2,
    /// The laser's true frame at the scan's stamp (on the pan-tilt: panned and tilted).
    pub frame: LaserFrame,
    /// The 3D scene the scan belongs to, if a `scene` or `survey` step took it.
    pub scene: Option<SceneTag>,
    /// How many exchanges of the tape were noted before the tour handed the scan over, when the
    /// run kept count (one that streamed its files did): where `run.mcap` puts its topics.
    pub after_exchanges: Option<usize>,
}

/// One full reading of the sonar ring, taken at rest at the end of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct SonarRecord {
    /// The report as the robot received it.
    pub echoes: robot::hardware::SonarEchoes,
    /// The true pose of the base when it was read.
    pub truth: Pose2,
    /// Each transducer's pose on the base, by transducer number.
    pub transducers: Vec<Pose2>,
    /// Full width of a transducer's cone, radians.
    pub cone: f64,
}

/// Everything a run produced.
#[derive(Clone, Debug)]
pub struct RunRecord {
    /// The scenario's name.
    pub scenario: String,
    /// The seed used.
    pub seed: u64,
    /// Kept scans, in order.
    pub scans: Vec<ScanRecord>,
    /// Steps of the script carried out.
    pub steps: usize,
    /// Simulated time at the end.
    pub end: Stamp,
    /// Wall-clock seconds the run took.
    pub wall_seconds: f64,
    /// Length of the true path, metres.
    pub distance_m: f64,
    /// Contacts with walls.
    pub collisions: u32,
    /// Motions that ended short of their target with the motors on, stopped with `p`
    /// (`robot::control::tour::STALL`).
    pub stalled_motions: usize,
    /// The true pose at the end.
    pub final_truth: Pose2,
    /// The odometry at the end.
    pub final_odometry: Pose2,
    /// The true path, one pose per world step.
    pub true_path: Vec<(Stamp, Pose2)>,
    /// State of charge of the (logic, motor) batteries at the end.
    pub battery_charge: (f64, f64),
    /// The sonar ring's last reading, when the scenario fires it.
    pub sonar: Option<SonarRecord>,
    /// The pan-tilt's status once it reached the scenario's position, before the script.
    pub pan_tilt: Option<PanTiltStatus>,
    /// The scan-matching estimate, when the scenario localises.
    pub localisation: Option<LocalisationRecord>,
    /// The 3D models of the run's scenes, when its script took any.
    pub reconstruction: Option<Reconstruction>,
    /// Every call the controller made through the hardware contract, with its answer: what
    /// `twin run --replay` plays back.
    pub tape: Vec<robot::replay::Exchange>,
    /// What the navigating steps (`goto`, `explore`) decided, in order.
    pub decisions: Vec<DecisionRecord>,
    /// The files built beside the simulation as the scans came, when the run did
    /// (`twin run`); `None` when it did not, and they are built from the record afterwards.
    pub streamed: Option<Streamed>,
    /// The map of the world the twin cast its rays in: what the files and the checks ask their
    /// questions about the world of, without building it again.
    pub world_map: std::sync::Arc<crate::world::WorldMap>,
}

/// What a run built from its scans while it went on (`crate::output::ScanStream`).
#[derive(Clone, Debug)]
pub struct Streamed {
    /// The occupancy grid of the level scans, as built: the grid's file thread trims it
    /// ([`robot::localization::GridBuilder::grid`]; `None` there: nothing to draw).
    pub grid: robot::localization::GridBuilder,
    /// The bytes of `scans.jsonl`.
    pub scan_lines: Vec<u8>,
    /// `map.svg`'s scan points. `None` unless every kept scan was drawn from the very true pose
    /// and laser frame the record holds.
    pub dots: Option<ScanDots>,
    /// The bytes of `run.mcap`, under the same condition.
    pub run_mcap: Option<Vec<u8>>,
    /// The bytes of `truth.tum` and `odometry.tum`, under the same condition.
    pub tum: Option<[Vec<u8>; 2]>,
}

/// What the localisation made of a run's scans.
#[derive(Clone, Debug)]
pub struct LocalisationRecord {
    /// The matcher used.
    pub matcher: MatcherKind,
    /// One placed scan per level scan, in order (world frame: it starts at the start pose);
    /// tilted scans are left to the 3D reconstruction.
    pub placed: Vec<Placed>,
    /// The point map, world frame.
    pub map: Vec<[f64; 2]>,
    /// Wall-clock seconds spent localising.
    pub wall_seconds: f64,
}

impl LocalisationRecord {
    /// Position and heading errors of the estimate against the truth at each scan.
    pub fn errors<'a>(&'a self, scans: &'a [ScanRecord]) -> impl Iterator<Item = (f64, f64)> + 'a {
        self.placed.iter().filter_map(|p| {
            let s = &scans[scans
                .binary_search_by_key(&p.stamp, |s| s.scan.stamp)
                .ok()?];
            Some((
                p.estimate.distance(&s.truth),
                robot::geometry::wrap_angle(p.estimate.theta - s.truth.theta).abs(),
            ))
        })
    }

    /// How far each trusted match's answer lies from the truth, metres and radians
    /// ([`trusted_match_errors`]), the truth taken from `scans`.
    pub fn trusted_match_errors<'a>(
        &'a self,
        scans: &'a [ScanRecord],
    ) -> impl Iterator<Item = (f64, f64)> + 'a {
        trusted_match_errors(&self.placed, move |stamp| truth_at(scans, stamp))
    }

    /// The trusted matches whose answer lies more than `metres` or `radians` from the truth
    /// ([`trusted_match_errors`](Self::trusted_match_errors)): trusted, and wrong.
    pub fn wrong_trusted(&self, scans: &[ScanRecord], tolerance: (f64, f64)) -> usize {
        self.judge_trusted(scans, tolerance).wrong
    }

    /// Every trusted match judged against the truth in `scans`, wrong beyond `tolerance`
    /// (metres, radians).
    pub fn judge_trusted(&self, scans: &[ScanRecord], tolerance: (f64, f64)) -> TrustedJudged {
        TrustedJudged::of(self.trusted_match_errors(scans), tolerance)
    }

    /// Every match relied on across a corridor ([`Placed::held_across`]) judged against the
    /// truth in `scans` ([`held_across_match_errors`]), wrong beyond `tolerance`.
    pub fn judge_held_across(&self, scans: &[ScanRecord], tolerance: (f64, f64)) -> TrustedJudged {
        TrustedJudged::of(
            held_across_match_errors(&self.placed, move |stamp| truth_at(scans, stamp)),
            tolerance,
        )
    }
}

/// The base's true pose at `stamp`, if a scan of `scans` (in order) was taken then.
fn truth_at(scans: &[ScanRecord], stamp: Stamp) -> Option<Pose2> {
    scans
        .binary_search_by_key(&stamp, |s| s.scan.stamp)
        .ok()
        .map(|i| scans[i].truth)
}

/// A run's trusted matches against the truth: how many, how many wrong, and the worst.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct TrustedJudged {
    /// Trusted matches whose scans have a truth.
    pub trusted: usize,
    /// Those more than the tolerance from the true motion.
    pub wrong: usize,
    /// The largest distance of an answer from the true motion, metres (0 with none) …
    pub worst_m: f64,
    /// … and the largest heading difference, radians (each over every trusted match).
    pub worst_rad: f64,
}

impl TrustedJudged {
    /// The judgement of `errors` (metres, radians), wrong beyond `(metres, radians)`.
    pub fn of(errors: impl Iterator<Item = (f64, f64)>, (metres, radians): (f64, f64)) -> Self {
        errors.fold(TrustedJudged::default(), |j, (m, r)| TrustedJudged {
            trusted: j.trusted + 1,
            wrong: j.wrong + usize::from(m > metres || r > radians),
            worst_m: j.worst_m.max(m),
            worst_rad: j.worst_rad.max(r),
        })
    }
}

/// The scan of `placed` (in order of stamp) taken at `stamp`, if any.
fn placed_at(placed: &[Placed], stamp: Stamp) -> Option<&Placed> {
    placed
        .binary_search_by_key(&stamp, |p| p.stamp)
        .ok()
        .map(|i| &placed[i])
}

/// How far each trusted match of `placed` (in order, as a map builder placed them) lies from
/// the truth, metres and radians: the motion it put between its reference scan and its scan
/// (the estimate's: a trusted match sets it) against the true motion between them, `truth`
/// giving the base's true pose at a stamp. A match whose scans have no truth is left out.
pub fn trusted_match_errors<'a>(
    placed: &'a [Placed],
    truth: impl Fn(Stamp) -> Option<Pose2> + 'a,
) -> impl Iterator<Item = (f64, f64)> + 'a {
    placed.iter().filter(|p| p.trusted).filter_map(move |p| {
        let reference = p.reference?;
        let answered = placed_at(placed, reference)?.estimate.relative(&p.estimate);
        let true_motion = truth(reference)?.relative(&truth(p.stamp)?);
        let off = true_motion.relative(&answered);
        Some((off.x.hypot(off.y), off.theta.abs()))
    })
}

/// How far each match the map builder relied on across a corridor ([`Placed::held_across`]: it
/// placed the scan by the match across the match's free direction and in heading, by odometry
/// along it) lies from the truth in what it was relied on for: across that direction, metres,
/// and in heading, radians. The match's answer (the current laser frame in the reference's)
/// against the laser's true motion between the scans (the base's, through each scan's
/// [mount](Placed::mount)), `truth` giving the base's true pose at a stamp. A match whose
/// scans have no truth is left out.
pub fn held_across_match_errors<'a>(
    placed: &'a [Placed],
    truth: impl Fn(Stamp) -> Option<Pose2> + 'a,
) -> impl Iterator<Item = (f64, f64)> + 'a {
    placed
        .iter()
        .filter(|p| p.held_across)
        .filter_map(move |p| {
            let (found, reference) = (p.matched.as_ref()?, p.reference?);
            let from = truth(reference)?.compose(&placed_at(placed, reference)?.mount);
            let true_motion = from.relative(&truth(p.stamp)?.compose(&p.mount));
            // Across the free direction: the free direction turned a quarter.
            let free = found.quality.free;
            let across =
                (found.pose.x - true_motion.x) * free[1] - (found.pose.y - true_motion.y) * free[0];
            let heading = robot::geometry::wrap_angle(found.pose.theta - true_motion.theta);
            Some((across.abs(), heading.abs()))
        })
}

/// When a trusted match counts as wrong in a run of the twin
/// ([`LocalisationRecord::wrong_trusted`]): 5 cm or 1° from the true motion, the line of
/// success of `twin matchers` on the twin's pairs.
pub const WRONG_MATCH: (f64, f64) = (0.05, 1.0 * std::f64::consts::PI / 180.0);

/// How a navigating step (`goto`, `explore`) ended, against the truth.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NavigationResult {
    /// When it ended, seconds.
    pub t: f64,
    /// Its goal (none when exploring).
    pub goal: Option<[f64; 2]>,
    /// What the controller said.
    pub outcome: robot::control::NavOutcome,
    /// The true distance to the goal then, metres (none when exploring).
    pub true_distance_m: Option<f64>,
}

/// Where the robot's footprint came closest to the world.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct Approach {
    /// Clearance between the footprint and the nearest wall or box, metres (0 or less: touching).
    pub clearance_m: f64,
    /// When, seconds.
    pub t: f64,
    /// Where the base was then (truth).
    pub pose: [f64; 3],
}

impl RunRecord {
    /// The true pose at `stamp` (the last one recorded at or before it).
    pub fn truth_at(&self, stamp: Stamp) -> Pose2 {
        let i = self.true_path.partition_point(|(t, _)| *t <= stamp);
        self.true_path
            .get(i.saturating_sub(1))
            .map_or(self.final_truth, |(_, p)| *p)
    }

    /// How each navigating step ended, in order.
    pub fn navigation_results(&self) -> Vec<NavigationResult> {
        self.decisions
            .iter()
            .filter_map(|d| match d.decision {
                robot::control::Decision::Done(outcome) => {
                    let truth = self.truth_at(Stamp::from_secs_f64(d.t));
                    Some(NavigationResult {
                        t: d.t,
                        goal: d.goal,
                        outcome,
                        true_distance_m: d.goal.map(|g| (g[0] - truth.x).hypot(g[1] - truth.y)),
                    })
                }
                robot::control::Decision::Motion { .. } => None,
            })
            .collect()
    }

    /// Where the round footprint (`radius` m, centred `center_x` m ahead of the axle) came
    /// closest to the walls and boxes of `map` along the true path.
    pub fn closest_approach(
        &self,
        map: &crate::world::WorldMap,
        radius: f64,
        center_x: f64,
    ) -> Option<Approach> {
        self.true_path
            .iter()
            .map(|(t, p)| {
                let (x, y) = p.transform_point(center_x, 0.0);
                Approach {
                    clearance_m: map.clearance([x, y]) - radius,
                    t: t.secs_f64(),
                    pose: [p.x, p.y, p.theta],
                }
            })
            .min_by(|a, b| a.clearance_m.total_cmp(&b.clearance_m))
    }

    /// Simulated seconds.
    pub fn sim_seconds(&self) -> f64 {
        self.end.secs_f64()
    }

    /// Simulated seconds per wall-clock second.
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_seconds > 0.0 {
            self.sim_seconds() / self.wall_seconds
        } else {
            f64::INFINITY
        }
    }

    /// Distance between the final odometry and the final true pose, metres.
    pub fn final_odometry_error_m(&self) -> f64 {
        self.final_odometry.distance(&self.final_truth)
    }

    /// Heading difference between the final odometry and the final true pose, degrees.
    pub fn final_odometry_error_deg(&self) -> f64 {
        robot::geometry::wrap_angle(self.final_odometry.theta - self.final_truth.theta)
            .to_degrees()
            .abs()
    }
}

/// Where a model's scenes were placed.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Placement {
    /// By the 2D localisation of the level scans.
    Estimate,
    /// By the odometry.
    Odometry,
    /// By the twin's true pose.
    Truth,
}

impl Placement {
    /// Its name in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Placement::Estimate => "estimate",
            Placement::Odometry => "odometry",
            Placement::Truth => "truth",
        }
    }
}

/// A model and, when the world is known, its scores.
#[derive(Clone, Debug)]
pub struct PlacedModel {
    /// How its scenes were placed.
    pub placement: Placement,
    /// The points, normals and mesh.
    pub model: Model,
    /// Its accuracy against the true surfaces.
    pub accuracy: Option<Accuracy>,
}

/// One validity rule tried on the model of the sweep.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RuleTrial {
    /// The rule, readably.
    pub rule: String,
    /// Valid triangles over those the grids offer.
    pub valid_share: f64,
    /// Mesh area, square metres.
    pub mesh_area_m2: f64,
    /// The part of it farther than 5 cm from every true surface.
    pub phantom_area_m2: f64,
    /// The part of the phantom area that bridges readings lying on true surfaces (the rule's
    /// doing, not the sensor's ghosts).
    pub bridge_area_m2: f64,
    /// The part within 5 cm of a true surface.
    pub true_area_m2: f64,
}

/// The 3D reconstruction of a run.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    /// How the scenes were meshed.
    pub options: MeshOptions,
    /// The models: by the estimate (if the run localised), by odometry, by the truth (twin).
    pub models: Vec<PlacedModel>,
    /// Validity rules tried on the best-placed model (truth, else estimate), with the world.
    pub sweep: Vec<RuleTrial>,
    /// Wall-clock seconds building the models (machine-dependent).
    pub build_seconds: f64,
    /// Wall-clock seconds scoring them (machine-dependent).
    pub score_seconds: f64,
}

impl Reconstruction {
    /// The model people look at: placed by the estimate if there is one, else by odometry.
    pub fn main(&self) -> &PlacedModel {
        self.models
            .iter()
            .find(|m| m.placement == Placement::Estimate)
            .unwrap_or(&self.models[0])
    }

    /// The model placed by `placement`, if built.
    pub fn placed(&self, placement: Placement) -> Option<&PlacedModel> {
        self.models.iter().find(|m| m.placement == placement)
    }
}

/// What a navigating step decided, and where it believed the robot was.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DecisionRecord {
    /// The stamp of the last status report, seconds.
    pub t: f64,
    /// The estimate steered by, map frame: x, y (m), heading (rad).
    pub estimate: [f64; 3],
    /// The odometry then.
    pub odometry: [f64; 3],
    /// The goal of a `goto` step, map frame (none when exploring).
    pub goal: Option<[f64; 2]>,
    /// The decision.
    pub decision: robot::control::Decision,
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::localization::MatchResult;

    /// A scan placed at `estimate`, matched against the scan at `reference` (seconds) when given.
    fn placed(t: u64, estimate: Pose2, reference: Option<u64>, trusted: bool) -> Placed {
        Placed {
            stamp: Stamp::from_millis(t * 1000),
            estimate,
            odometry: estimate,
            matched: reference.map(|_| MatchResult::unmatched(Pose2::IDENTITY)),
            reference: reference.map(|r| Stamp::from_millis(r * 1000)),
            trusted,
            held_across: false,
            mount: Pose2::IDENTITY,
        }
    }

    #[test]
    fn a_trusted_match_is_judged_by_the_motion_it_put_between_its_scans() {
        // The truth: 1 m forward a scan, turning 10° at the second.
        let truth = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(1.0, 0.0, 0.0),
            Pose2::new(2.0, 0.0, 10f64.to_radians()),
            Pose2::new(
                2.0 + 10f64.to_radians().cos(),
                10f64.to_radians().sin(),
                0.2,
            ),
        ];
        // The estimate starts 0.5 m and 5° off (an error carried over is no match's fault),
        // the second match answers 0.2 m short, the third is wrong but not trusted (odometry
        // placed it), and the last trusted one is right again from there.
        let origin = Pose2::new(0.5, 0.0, 5f64.to_radians());
        let at = |p: Pose2| origin.compose(&p);
        let short = at(truth[1]).compose(
            &truth[1]
                .relative(&truth[2])
                .compose(&Pose2::new(-0.2, 0.0, 0.0)),
        );
        let wrong = short.compose(&Pose2::new(3.0, 0.0, 1.0));
        let placed = vec![
            placed(0, at(truth[0]), None, false),
            placed(1, at(truth[1]), Some(0), true),
            placed(2, short, Some(1), true),
            placed(3, wrong, Some(2), false),
        ];
        let truth_at = |stamp: Stamp| truth.get(stamp.secs_f64().round() as usize).copied();
        let errors: Vec<(f64, f64)> = trusted_match_errors(&placed, truth_at).collect();
        assert_eq!(errors.len(), 2, "{errors:?}");
        assert!(errors[0].0 < 1e-9 && errors[0].1 < 1e-9, "{errors:?}");
        assert!(
            (errors[1].0 - 0.2).abs() < 1e-9 && errors[1].1 < 1e-9,
            "{errors:?}"
        );
        let wrong = TrustedJudged::of(errors.iter().copied(), WRONG_MATCH).wrong;
        assert_eq!(wrong, 1);
        // A scan without truth leaves its match out.
        let none = |_: Stamp| None;
        assert_eq!(trusted_match_errors(&placed, none).count(), 0);
    }

    /// A match relied on across a corridor is judged across its free direction and in heading,
    /// in the laser's frame (the laser 0.2 m ahead of the base and turned 90°): its error along
    /// the corridor is what odometry answered for, not the match.
    #[test]
    fn a_match_relied_on_across_a_corridor_is_judged_across_it() {
        let mount = Pose2::new(0.2, 0.0, 90f64.to_radians());
        let truth = [Pose2::new(1.0, 2.0, 0.3), Pose2::new(1.5, 2.1, 0.35)];
        let true_laser = truth[0].compose(&mount).relative(&truth[1].compose(&mount));
        // The corridor runs along the reference laser's y: 0.3 m wrong along it, 4 mm across
        // and 0.1° in heading.
        let mut found = MatchResult::unmatched(Pose2::new(
            true_laser.x + 0.004,
            true_laser.y + 0.3,
            true_laser.theta + 0.1f64.to_radians(),
        ));
        found.quality.free = [0.0, 1.0];
        let mut second = placed(1, truth[1], Some(0), false);
        second.matched = Some(found);
        second.held_across = true;
        let placed = vec![
            Placed {
                mount,
                ..placed(0, truth[0], None, false)
            },
            Placed { mount, ..second },
        ];
        let truth_at = |stamp: Stamp| truth.get(stamp.secs_f64().round() as usize).copied();
        let errors: Vec<(f64, f64)> = held_across_match_errors(&placed, truth_at).collect();
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!((errors[0].0 - 0.004).abs() < 1e-9, "{errors:?}");
        assert!(
            (errors[0].1 - 0.1f64.to_radians()).abs() < 1e-9,
            "{errors:?}"
        );
        // Across the other way it is 0.3 m wrong; and a match not relied on is not judged.
        let mut along = placed.clone();
        along[1].matched.as_mut().unwrap().quality.free = [1.0, 0.0];
        let errors: Vec<(f64, f64)> = held_across_match_errors(&along, truth_at).collect();
        assert!((errors[0].0 - 0.3).abs() < 1e-9, "{errors:?}");
        along[1].held_across = false;
        assert_eq!(held_across_match_errors(&along, truth_at).count(), 0);
    }
}
