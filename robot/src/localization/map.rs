//! 2D map building by chained scan matching (thesis §3.5), seeded by odometry queued and
//! interpolated to each scan's stamp (002 §7.3.3).

use super::matcher::{MatchResult, Reference, ScanMatcher};
use super::quality::TrustRule;
use super::scan::{RangeScan, ScanPoints};
use crate::geometry::Pose2;
use crate::odometry::PoseHistory;
use crate::time::Stamp;
use std::collections::VecDeque;

/// How the map is built.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MapConfig {
    /// The laser's pose on the base.
    pub mount: Pose2,
    /// A matched scan becomes the next reference once the estimate has moved this far from the
    /// current reference, metres. 0 (the default) matches every scan to the one before, as the
    /// thesis does.
    pub keyframe_distance_m: f64,
    /// … or turned this far, radians (default 0).
    pub keyframe_angle_rad: f64,
    /// A match keeping fewer correspondences than this is not trusted: the odometry guess is used
    /// instead. Default 20.
    pub min_correspondences: usize,
    /// Odometry samples kept waiting for scans. Default 4096.
    pub odometry_capacity: usize,
    /// A match that moves the pose further from the odometry's guess than odometry can err is
    /// not trusted either (a corridor's walls slid along, a mirror image matched): the bound is
    /// this many metres plus [`correction_share`](Self::correction_share) of the distance moved
    /// since the reference. Default 0.5. (Real logs need room: odometry that stalls for a few
    /// scans while the robot turns is corrected by 10–16° a scan in the MIT CSAIL log.)
    pub max_correction_m: f64,
    /// … or turns it further than this many radians per metre moved (one metre at least) plus
    /// that share of the angle turned. Default 45°: a match that turns the robot round (a
    /// corridor matched back to front) is refused.
    pub max_correction_rad: f64,
    /// The share of a motion odometry may get wrong. Default 0.5.
    pub correction_share: f64,
    /// Only a match flagged [`converged`](MatchResult::converged) (its quality passes the
    /// [`TrustRule`]) is used; any other falls back to odometry and is counted
    /// in [`MatchStats::fallbacks`]. Default true.
    pub require_converged: bool,
    /// A match the trust rule refuses only along its free direction (a corridor whose advance
    /// the scans leave open: [`MatchQuality::held`] false, or σ along it too large;
    /// [`TrustRule::trusts_across`]) places its scan by the match across that direction and in
    /// heading, and by odometry along it, not by odometry alone; it is still a fallback,
    /// counted in [`MatchStats::held_across`]. Default true.
    ///
    /// [`MatchQuality::held`]: super::MatchQuality::held
    /// [`TrustRule::trusts_across`]: super::TrustRule::trusts_across
    pub held_across: bool,
}

impl Default for MapConfig {
    fn default() -> Self {
        MapConfig {
            mount: Pose2::IDENTITY,
            keyframe_distance_m: 0.0,
            keyframe_angle_rad: 0.0,
            min_correspondences: 20,
            odometry_capacity: 4096,
            max_correction_m: 0.5,
            max_correction_rad: 45f64.to_radians(),
            correction_share: 0.5,
            require_converged: true,
            held_across: true,
        }
    }
}

/// One scan placed by the map builder.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Placed {
    /// The scan's stamp.
    pub stamp: Stamp,
    /// The estimated pose of the base in the map (whose origin is the first scan's base pose, or
    /// the odometry's origin with [`MapBuilder::in_odometry_frame`]).
    pub estimate: Pose2,
    /// The odometry at the scan's stamp, in the odometry's own frame.
    pub odometry: Pose2,
    /// The match against the reference (`None` for the first scan).
    pub matched: Option<MatchResult>,
    /// The stamp of the reference scan it was matched against (`None` for the first scan).
    pub reference: Option<Stamp>,
    /// Whether the match was used (converged, enough correspondences, a correction within the
    /// bounds) rather than the odometry guess.
    pub trusted: bool,
    /// Whether, not trusted, the scan was placed by the match across its free direction and in
    /// heading and by odometry along it ([`MapConfig::held_across`]).
    pub held_across: bool,
    /// The laser's mount on the base when the scan was taken (a panned head's): the match's
    /// laser frame is the base's through it.
    pub mount: Pose2,
}

/// How the matches of a run went.
#[derive(Copy, Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct MatchStats {
    /// Matches made (every placed scan but the first).
    pub matches: usize,
    /// Matches trusted (converged, enough correspondences, a plausible correction).
    pub trusted: usize,
    /// Matches not trusted, whose scans were placed by odometry instead (along a corridor
    /// only, for those of [`held_across`](Self::held_across)).
    pub fallbacks: usize,
    /// Of the fallbacks, those placed by the match across a corridor and by odometry along it
    /// ([`MapConfig::held_across`]).
    pub held_across: usize,
    /// Matches that converged before their iteration cap.
    pub converged: usize,
    /// Mean correspondence searches per match.
    pub mean_iterations: f64,
}

impl MatchStats {
    /// The statistics of `placed` scans.
    pub fn of(placed: &[Placed]) -> Self {
        let matches: Vec<_> = placed.iter().filter_map(|p| p.matched).collect();
        MatchStats {
            matches: matches.len(),
            trusted: placed.iter().filter(|p| p.trusted).count(),
            fallbacks: placed
                .iter()
                .filter(|p| p.matched.is_some() && !p.trusted)
                .count(),
            held_across: placed.iter().filter(|p| p.held_across).count(),
            converged: matches.iter().filter(|m| m.converged).count(),
            mean_iterations: matches.iter().map(|m| f64::from(m.iterations)).sum::<f64>()
                / matches.len().max(1) as f64,
        }
    }
}

#[derive(Debug)]
struct Key {
    reference: Reference,
    /// The reference scan's stamp.
    stamp: Stamp,
    estimate: Pose2,
    /// The reference scan's laser pose on the base.
    mount: Pose2,
}

/// Chains scan matches into a trajectory and a point map.
///
/// Feed it odometry as it comes ([`push_odometry`](Self::push_odometry)) and scans as they come
/// ([`push_scan`](Self::push_scan)); a scan is placed once the odometry brackets its stamp, and
/// [`finish`](Self::finish) places the rest with the newest odometry.
///
/// ```
/// use robot::localization::{MapBuilder, MapConfig, MatcherKind, RangeScan};
/// use robot::{Pose2, Stamp};
/// let mut map = MapBuilder::new(MatcherKind::Lorentz.build(), MapConfig::default());
/// // A wall 2 m ahead, seen twice with the robot standing still.
/// let wall: Vec<f64> = (0..181).map(|i| 2.0 / ((i as f64 - 90.0).to_radians()).cos().max(0.1)).collect();
/// let scan = RangeScan::new(-std::f64::consts::FRAC_PI_2, 1f64.to_radians(), 30.0, wall);
/// map.push_odometry(Stamp::from_millis(0), Pose2::IDENTITY);
/// map.push_scan(scan.clone().stamped(Stamp::from_millis(10)));
/// map.push_odometry(Stamp::from_millis(100), Pose2::IDENTITY);
/// map.push_scan(scan.stamped(Stamp::from_millis(110)));
/// map.finish();
/// assert_eq!(map.placed().len(), 2);
/// assert!(map.placed()[1].estimate.x.abs() < 1e-3);
/// ```
#[derive(Debug)]
pub struct MapBuilder {
    matcher: Box<dyn ScanMatcher>,
    config: MapConfig,
    odometry: PoseHistory,
    /// Scans waiting for odometry: stamp, points, and the laser's pose on the base.
    pending: VecDeque<(Stamp, ScanPoints, Pose2)>,
    key: Option<Key>,
    odometry_frame: bool,
    placed: Vec<Placed>,
    map: Vec<[f64; 2]>,
}

impl MapBuilder {
    /// An empty map whose origin is the first scan's base pose (thesis §3.5).
    pub fn new(matcher: Box<dyn ScanMatcher>, config: MapConfig) -> Self {
        Self::with_anchor(matcher, config, false)
    }

    /// An empty map in the odometry's frame: the first scan is placed at its odometry pose (so a
    /// run's estimate compares with its truth when the odometry starts at the true start).
    pub fn in_odometry_frame(matcher: Box<dyn ScanMatcher>, config: MapConfig) -> Self {
        Self::with_anchor(matcher, config, true)
    }

    fn with_anchor(matcher: Box<dyn ScanMatcher>, config: MapConfig, odometry_frame: bool) -> Self {
        MapBuilder {
            matcher,
            odometry: PoseHistory::new(config.odometry_capacity),
            config,
            pending: VecDeque::new(),
            key: None,
            odometry_frame,
            placed: Vec::new(),
            map: Vec::new(),
        }
    }

    /// The matcher in use.
    pub fn matcher(&self) -> &dyn ScanMatcher {
        self.matcher.as_ref()
    }

    /// An odometry sample (base pose in the odometry frame). Older samples than the newest are
    /// ignored.
    pub fn push_odometry(&mut self, stamp: Stamp, pose: Pose2) {
        self.odometry.push(stamp, pose);
        self.place_ready(false);
    }

    /// A scan taken by the laser at the configured mount. It is placed as soon as the odometry
    /// reaches its stamp.
    pub fn push_scan(&mut self, scan: RangeScan) {
        self.push_points_from(scan.stamp, scan.points(), self.config.mount);
    }

    /// A scan taken by a laser at `mount` on the base (a panned head): matched against a
    /// reference taken from another mount, its points are still compared in one frame.
    pub fn push_scan_from(&mut self, scan: RangeScan, mount: Pose2) {
        self.push_points_from(scan.stamp, scan.points(), mount);
    }

    /// A scan given as its points in the laser frame, in scan order, from the configured mount.
    pub fn push_points(&mut self, stamp: Stamp, points: ScanPoints) {
        self.push_points_from(stamp, points, self.config.mount);
    }

    /// A scan given as its points in the frame of a laser at `mount` on the base.
    pub fn push_points_from(&mut self, stamp: Stamp, points: ScanPoints, mount: Pose2) {
        self.pending.push_back((stamp, points, mount));
        self.place_ready(false);
    }

    /// Places every waiting scan, with the newest odometry for those past its end.
    pub fn finish(&mut self) {
        self.place_ready(true);
    }

    /// Scans waiting for odometry.
    pub fn waiting(&self) -> usize {
        self.pending.len()
    }

    /// Every placed scan, in order.
    pub fn placed(&self) -> &[Placed] {
        &self.placed
    }

    /// The point map: every placed scan's points in the map frame.
    pub fn map_points(&self) -> &[[f64; 2]] {
        &self.map
    }

    /// Whether a match `found` (laser frame) departs from the odometry's `guess` by no more than
    /// odometry can err over `motion` (the base's motion since the reference).
    fn plausible_correction(&self, motion: &Pose2, guess: &Pose2, found: &Pose2) -> bool {
        let c = &self.config;
        let moved = motion.x.hypot(motion.y);
        let correction = guess.relative(found);
        correction.x.hypot(correction.y) <= c.max_correction_m + c.correction_share * moved
            && correction.theta.abs()
                <= c.max_correction_rad * moved.max(1.0) + c.correction_share * motion.theta.abs()
    }

    fn place_ready(&mut self, all: bool) {
        while let Some(&(stamp, _, _)) = self.pending.front() {
            let odometry = match self.odometry.at(stamp) {
                Some(pose) => pose,
                None => match self.odometry.latest() {
                    // Before the first sample, or (finishing) after the last one.
                    Some((t, pose)) if stamp < t || all => pose,
                    _ => return,
                },
            };
            let (stamp, points, mount) = self.pending.pop_front().expect("front exists");
            self.place(stamp, points, mount, odometry);
        }
    }

    fn place(&mut self, stamp: Stamp, points: ScanPoints, mount: Pose2, odometry: Pose2) {
        let reference = self.key.as_ref().map(|key| key.stamp);
        let (estimate, matched, trusted, held_across) = match (&self.key, self.placed.last()) {
            (Some(key), Some(last)) => {
                // Dead-reckon from the last placed scan, then express it in the reference: the
                // current laser frame seen from the reference's laser frame.
                let predicted = last.estimate.compose(&last.odometry.relative(&odometry));
                let base_guess = key.estimate.relative(&predicted);
                let laser_guess = key.mount.inverse().compose(&base_guess).compose(&mount);
                let result = self.matcher.align(&key.reference, &points, laser_guess);
                let usable = |pose: &Pose2| {
                    result.correspondences >= self.config.min_correspondences
                        && pose.x.is_finite()
                        && pose.y.is_finite()
                        && pose.theta.is_finite()
                        && self.plausible_correction(&base_guess, &laser_guess, pose)
                };
                let trusted =
                    (result.converged || !self.config.require_converged) && usable(&result.pose);
                // Trusted across a corridor but not along it: the match across it and in
                // heading, the odometry along it.
                let across = (!trusted
                    && self.config.held_across
                    && TrustRule::default().trusts_across(&result.quality))
                .then(|| across_only(&result.pose, &laser_guess, result.quality.free))
                .filter(|pose| usable(pose));
                let laser = match (trusted, across) {
                    (true, _) => result.pose,
                    (false, Some(pose)) => pose,
                    (false, None) => laser_guess,
                };
                let base = key.mount.compose(&laser).compose(&mount.inverse());
                (
                    key.estimate.compose(&base),
                    Some(result),
                    trusted,
                    across.is_some(),
                )
            }
            _ if self.odometry_frame => (odometry, None, false, false),
            _ => (Pose2::IDENTITY, None, false, false),
        };
        let laser_pose = estimate.compose(&mount);
        self.map.extend(points.xy.iter().map(|p| {
            let (x, y) = laser_pose.transform_point(p[0], p[1]);
            [x, y]
        }));
        let new_key = match &self.key {
            None => true,
            Some(key) => {
                let moved = key.estimate.relative(&estimate);
                moved.x.hypot(moved.y) >= self.config.keyframe_distance_m
                    || moved.theta.abs() >= self.config.keyframe_angle_rad
            }
        };
        if new_key && !points.is_empty() {
            self.key = Some(Key {
                reference: Reference::new(points),
                stamp,
                estimate,
                mount,
            });
        }
        self.placed.push(Placed {
            stamp,
            estimate,
            odometry,
            reference: matched.as_ref().and(reference),
            matched,
            trusted,
            held_across,
            mount,
        });
    }
}

/// `found` (a match's pose of the current laser frame in the reference's) with its position
/// along `free` (a unit direction in the reference's frame) taken from `guess`: what the scans
/// hold of a match in a corridor (across it, and the heading) and what odometry gives (the
/// advance along it).
fn across_only(found: &Pose2, guess: &Pose2, free: [f64; 2]) -> Pose2 {
    let along = (guess.x - found.x) * free[0] + (guess.y - found.y) * free[1];
    Pose2::new(
        found.x + along * free[0],
        found.y + along * free[1],
        found.theta,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::localization::MatcherKind;

    /// A room 8 m × 6 m seen from `pose` (laser at the base), 1° beams over 360°.
    fn room_scan(pose: Pose2, stamp: Stamp) -> RangeScan {
        let ranges = (0..360)
            .map(|i| {
                let a = pose.theta + (i as f64).to_radians();
                let (s, c) = a.sin_cos();
                let mut best = f64::INFINITY;
                for (wall, along_x) in [(4.0, true), (-4.0, true), (3.0, false), (-3.0, false)] {
                    let (o, d) = if along_x { (pose.x, c) } else { (pose.y, s) };
                    let t = (wall - o) / d;
                    if t > 0.0 {
                        best = best.min(t);
                    }
                }
                best
            })
            .collect();
        RangeScan::new(0.0, 1f64.to_radians(), 30.0, ranges).stamped(stamp)
    }

    #[test]
    fn odometry_is_interpolated_to_the_scan_and_the_scan_waits_for_it() {
        let mut map = MapBuilder::new(MatcherKind::Lorentz.build(), MapConfig::default());
        let at = |ms| Stamp::from_millis(ms);
        map.push_odometry(at(0), Pose2::IDENTITY);
        map.push_scan(room_scan(Pose2::IDENTITY, at(0)));
        // The second scan is measured at 150 ms, between odometry at 100 and 200 ms.
        map.push_scan(room_scan(Pose2::new(0.15, 0.0, 0.0), at(150)));
        map.push_odometry(at(100), Pose2::new(0.1, 0.0, 0.0));
        assert_eq!(
            map.waiting(),
            1,
            "the scan waits for odometry past its stamp"
        );
        map.push_odometry(at(200), Pose2::new(0.2, 0.0, 0.0));
        assert_eq!(map.waiting(), 0);
        let placed = map.placed()[1];
        assert!((placed.odometry.x - 0.15).abs() < 1e-12);
        // Point-to-point matching of 1° scans is exact to the spacing of the points, not better.
        assert!((placed.estimate.x - 0.15).abs() < 5e-3, "{placed:?}");
        assert_eq!(map.map_points().len(), 720);
    }

    #[test]
    fn matching_corrects_a_wrong_odometry() {
        let mut map = MapBuilder::new(MatcherKind::Lorentz.build(), MapConfig::default());
        let truth = [
            Pose2::IDENTITY,
            Pose2::new(0.3, 0.1, 0.1),
            Pose2::new(0.6, 0.1, 0.3),
            Pose2::new(0.9, 0.3, 0.5),
        ];
        for (k, pose) in truth.iter().enumerate() {
            // Odometry that drifts: 10 % long and 0.02 rad per step off.
            let odo = Pose2::new(pose.x * 1.1, pose.y * 1.1, pose.theta + 0.02 * k as f64);
            let t = Stamp::from_millis(100 * k as u64);
            map.push_odometry(t, odo);
            map.push_scan(room_scan(*pose, t));
        }
        map.finish();
        let last = map.placed().last().unwrap();
        assert!(last.trusted);
        assert!(last.estimate.distance(&truth[3]) < 0.01, "{last:?}");
        assert!((last.estimate.theta - truth[3].theta).abs() < 0.005);
    }

    /// A corridor 2 m wide whose walls run past the laser's 32 m, seen by a SICK's 361 beams
    /// with a centimetre of noise or none: nothing says how far the robot advanced along it.
    /// Odometry says 0.25 m where it went 0.3 m, and puts it 3 cm to the side and 1.5° off. The
    /// match is not trusted (with noise the scans do not hold it along the corridor; without,
    /// the walls' information leaves σ along it infinite), so the scan is placed by the match
    /// across the corridor and in heading, and by odometry along it; without `held_across`, by
    /// odometry alone.
    #[test]
    fn a_corridor_places_its_scan_by_the_match_across_and_odometry_along() {
        for noise in [0.02, 0.0] {
            corridor_placed(noise);
        }
    }

    /// [`a_corridor_places_its_scan_by_the_match_across_and_odometry_along`] with noise
    /// uniform over `noise` metres.
    fn corridor_placed(noise: f64) {
        let scan = |pose: Pose2, stamp: Stamp, first: usize| {
            let ranges = (0..361)
                .map(|i| {
                    let a = pose.theta + (i as f64 * 0.5 - 90.0).to_radians();
                    let s = a.sin();
                    let wall = if s > 0.0 { 1.0 } else { -1.0 };
                    let t = (wall - pose.y) / s;
                    let noise = noise * (((first + i) as f64 * 0.754_877_666).fract() - 0.5);
                    if t.is_finite() && t > 0.0 && t < 32.0 {
                        t + noise
                    } else {
                        f64::INFINITY
                    }
                })
                .collect();
            RangeScan::new(-90f64.to_radians(), 0.5f64.to_radians(), 32.0, ranges).stamped(stamp)
        };
        // The map's frame is the first scan's: the corridor runs along its x.
        let truth = [Pose2::IDENTITY, Pose2::new(0.3, 0.02, 0.03)];
        let odometry = [truth[0], Pose2::new(0.25, 0.05, 0.03 + 1.5f64.to_radians())];
        let run = |held_across: bool| {
            let config = MapConfig {
                held_across,
                ..MapConfig::default()
            };
            let mut map = MapBuilder::new(MatcherKind::LorentzLines.build(), config);
            for k in 0..2 {
                let t = Stamp::from_millis(100 * k as u64);
                map.push_odometry(t, odometry[k]);
                map.push_scan(scan(truth[k], t, 1000 * k));
            }
            map.finish();
            *map.placed().last().unwrap()
        };
        let last = run(true);
        let result = last.matched.unwrap();
        assert!(!result.converged, "noise {noise}: {result:?}");
        assert!(
            !last.trusted && last.held_across,
            "noise {noise}: {result:?}"
        );
        // Across the corridor (y) and in heading, as the truth; along it (x), as odometry.
        let placed = last.estimate;
        assert!(
            (placed.y - truth[1].y).abs() < 0.01,
            "noise {noise}: {placed:?}"
        );
        assert!(
            (placed.theta - truth[1].theta).abs() < 0.2f64.to_radians(),
            "noise {noise}: {placed:?}"
        );
        assert!(
            (placed.x - odometry[1].x).abs() < 0.01,
            "noise {noise}: {placed:?}"
        );
        assert_eq!(MatchStats::of(&[last]).held_across, 1);
        let alone = run(false);
        assert!(!alone.trusted && !alone.held_across);
        assert!(alone.estimate.distance(&odometry[1]) < 1e-9, "{alone:?}");
    }
}
