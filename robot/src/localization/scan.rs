//! A range scan as the matchers see it: ranges in metres, and the Cartesian points of the beams
//! that returned something.

use super::matcher::{MAX_COORDINATE_M, plausible};
use crate::hardware::LaserScan;
use crate::time::Stamp;
use serde::{Deserialize, Serialize};

/// One planar range scan in SI units, in the laser frame (x forward, y left, counter-clockwise).
///
/// Beam `i` points at `angle_min + i · angle_increment`. A range that is not finite, not positive,
/// or `>= range_max` means the beam returned nothing: such beams never enter a match.
///
/// ```
/// use robot::localization::RangeScan;
/// let scan = RangeScan::new(-0.5, 0.5, 10.0, vec![1.0, 10.0, 2.0]);
/// let points = scan.points();
/// assert_eq!(points.len(), 2); // the 10 m beam is a no-return
/// assert!((points.xy[1][0] - 2.0 * 0.5f64.cos()).abs() < 1e-12);
/// assert_eq!(points.beam, vec![0, 2]);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RangeScan {
    /// When the scan was measured.
    #[serde(default, skip_serializing)]
    pub stamp: Stamp,
    /// Angle of the first beam, radians.
    pub angle_min: f64,
    /// Angle between consecutive beams, radians.
    pub angle_increment: f64,
    /// Ranges at or beyond this are no returns, metres.
    pub range_max: f64,
    /// One range per beam, metres.
    pub ranges: Vec<f64>,
}

impl RangeScan {
    /// A scan stamped at zero.
    pub fn new(angle_min: f64, angle_increment: f64, range_max: f64, ranges: Vec<f64>) -> Self {
        RangeScan {
            stamp: Stamp::ZERO,
            angle_min,
            angle_increment,
            range_max,
            ranges,
        }
    }

    /// The same scan with a stamp.
    pub fn stamped(mut self, stamp: Stamp) -> Self {
        self.stamp = stamp;
        self
    }

    /// Whether beam `i`'s range is a real return: finite, positive, below `range_max` and
    /// within [`MAX_COORDINATE_M`].
    pub fn returned(&self, i: usize) -> bool {
        self.ranges.get(i).is_some_and(|&r| {
            r.is_finite() && r > 0.0 && r < self.range_max && r <= MAX_COORDINATE_M
        })
    }

    /// The end points of the beams that returned, in beam order (a beam whose angle is not
    /// finite has no end point).
    pub fn points(&self) -> ScanPoints {
        let mut points = ScanPoints::default();
        for (i, &r) in self.ranges.iter().enumerate() {
            let angle = self.angle_min + i as f64 * self.angle_increment;
            if self.returned(i) && angle.is_finite() {
                let (s, c) = angle.sin_cos();
                points.xy.push([r * c, r * s]);
                points.beam.push(i);
            }
        }
        points
    }
}

impl From<&LaserScan> for RangeScan {
    fn from(scan: &LaserScan) -> Self {
        RangeScan {
            stamp: scan.stamp,
            angle_min: scan.angle_min,
            angle_increment: scan.angle_increment,
            range_max: scan.range_max_m(),
            ranges: scan
                .ranges_mm
                .iter()
                .map(|&mm| f64::from(mm) * 1e-3)
                .collect(),
        }
    }
}

/// The returned points of one scan, metres, in beam order, with the beam each came from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScanPoints {
    /// `[x, y]` of each point in the laser frame.
    pub xy: Vec<[f64; 2]>,
    /// The beam index of each point.
    pub beam: Vec<usize>,
}

impl ScanPoints {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.xy.len()
    }

    /// Whether there is no point.
    pub fn is_empty(&self) -> bool {
        self.xy.is_empty()
    }

    /// Whether every point is finite and within [`MAX_COORDINATE_M`] of the laser.
    pub fn is_plausible(&self) -> bool {
        self.xy.iter().all(|&p| plausible(p))
    }
}

/// The beam step from which a scan counts as sparse: 0.75°, between the SICK's 0.5° and 1°
/// modes. [`Lorentz::with_lines`](super::Lorentz::with_lines) keeps its narrowing σ schedule
/// for scans below it, and the trust rule asks a smaller share of inliers against a reference
/// at or above it ([`Reference::is_sparse`](super::Reference::is_sparse)).
pub const SPARSE_BEAM_STEP_RAD: f64 = 0.75 * (std::f64::consts::PI / 180.0);

/// The angle between the points `a` and `b` as seen from the laser (the origin), radians: one
/// arctangent of their cross and dot products.
pub(super) fn turn_between(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] * b[1] - a[1] * b[0])
        .atan2(a[0] * b[0] + a[1] * b[1])
        .abs()
}

/// Whether `beams` beams `increment` radians apart (either sign) fan out within a turn: a
/// closing beam on the first one's bearing allowed, and the beams apart unless there is only
/// one. A scan that winds round more than once, or stands on one bearing, is malformed.
pub fn fan_within_a_turn(increment: f64, beams: usize) -> bool {
    let step = increment.abs();
    let span = step * beams.saturating_sub(1) as f64;
    (step > 0.0 || beams <= 1) && span <= std::f64::consts::TAU + step
}

/// The angle between a scan's neighbouring beams: the median, over points of consecutive
/// beams, of the angle between them seen from the laser (one arctangent of their cross and dot
/// products). `None` with no two such points.
pub fn beam_step(current: &ScanPoints) -> Option<f64> {
    let mut steps: Vec<f64> = current
        .xy
        .windows(2)
        .zip(current.beam.windows(2))
        .filter(|(_, beams)| beams[1] == beams[0] + 1)
        .map(|(p, _)| turn_between(p[0], p[1]))
        .filter(|step| step.is_finite())
        .collect();
    if steps.is_empty() {
        return None;
    }
    let middle = steps.len() / 2;
    Some(*steps.select_nth_unstable_by(middle, f64::total_cmp).1)
}

/// Whether [`beam_step`] is below `limit` (radians, under a quarter turn), without its
/// arctangents and its selection: the median lies below `limit` when more than half the steps
/// do, and a step between `a` and `b` does when `a · b > 0` and `|a × b| < tan(limit) a · b`.
/// `None` with no two points of consecutive beams, as [`beam_step`]. Asked of every reference
/// and every current scan, the arctangents were 2–3 % of a `lorentz-lines` match.
pub fn beam_step_below(scan: &ScanPoints, limit: f64) -> Option<bool> {
    let tan = limit.tan();
    let (mut steps, mut below) = (0usize, 0usize);
    for (p, beams) in scan.xy.windows(2).zip(scan.beam.windows(2)) {
        if beams[1] != beams[0] + 1 {
            continue;
        }
        let (a, b) = (p[0], p[1]);
        let (cross, dot) = (a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1]);
        let is_below = if cross.is_finite() && dot.is_finite() {
            dot > 0.0 && cross.abs() < tan * dot
        } else {
            // Infinite or not a number: as `beam_step` takes it, by the arctangent.
            let step = turn_between(a, b);
            if !step.is_finite() {
                continue;
            }
            step < limit
        };
        steps += 1;
        below += usize::from(is_below);
    }
    (steps > 0).then_some(below > steps / 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`beam_step_below`] answers as [`beam_step`] compared with the limit does: on scans of
    /// 0.25–2° beams with beams missing, ranges jumping, points behind the laser and points at
    /// infinity, at limits between, just beside and on the steps; `None` where `beam_step` is.
    #[test]
    fn the_step_is_below_a_limit_as_the_median_says() {
        let mut rng = crate::test_rng::XorShift(0x9e37_79b9_7f4a_7c15);
        let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let mut answered = 0;
        for scan in 0..400 {
            let step_deg = [0.25, 0.5, 0.5, 1.0, 2.0][scan % 5];
            let beams = 1 + (360.0 * uniform()) as usize;
            let mut points = ScanPoints::default();
            for k in 0..beams {
                if uniform() < [0.0, 0.3, 0.9][scan % 3] {
                    continue; // no return
                }
                let a = (k as f64 * step_deg - 90.0).to_radians();
                let r = if uniform() < 0.1 {
                    0.05
                } else {
                    1.0 + 9.0 * uniform()
                };
                let mut p = [r * a.cos(), r * a.sin()];
                if scan % 7 == 0 && k % 11 == 0 {
                    p = [-p[0], p[1]]; // behind
                }
                if scan % 13 == 0 && k % 17 == 0 {
                    p = [f64::INFINITY, p[1]];
                }
                points.xy.push(p);
                points.beam.push(k);
            }
            let median = beam_step(&points);
            for limit_deg in [0.1, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 10.0, 89.0] {
                let limit = (limit_deg * (1.0 + 1e-9 * (uniform() - 0.5))).to_radians();
                let expected = median.map(|step| step < limit);
                assert_eq!(
                    beam_step_below(&points, limit),
                    expected,
                    "scan {scan}, limit {limit_deg}°, median {median:?}"
                );
                answered += usize::from(expected.is_some());
            }
        }
        assert!(answered > 2000, "{answered}");
    }
}
