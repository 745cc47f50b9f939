//! Local lines of a reference scan for line-assisted association (thesis §3.4.3, App. E.3).
//!
//! Around each reference point a line is grown by principal components: it starts from the point
//! and its left and right neighbours in the scan, then looks at up to `neighbours / 2` more
//! points on each side. A neighbour joins when it lies close to the current line and does not make
//! the fit worse (its RMS distance to the line stays under the larger of the previous RMS and the
//! laser's noise floor — a strict "never grows" would refuse every point of a noisy wall).
//! A line whose final RMS is small enough is "good": the current point is then matched against
//! its orthogonal projection on the line (kept within the fitted segment), or against the sensed
//! point if that is closer.

/// Parameters of the line growth.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LineParams {
    /// Neighbours examined in total, half on each side (the thesis's `n`). Default 10.
    pub neighbours: usize,
    /// A neighbour farther than this from the current line is skipped, metres. Default 0.05.
    pub max_point_distance_m: f64,
    /// Fit errors below this do not count as growing, metres. Default 0.01 (the laser's noise).
    pub noise_floor_m: f64,
    /// A line is good when its RMS distance is below this, metres. Default 0.02.
    pub max_rms_m: f64,
    /// … and it holds at least this many points. Default 5.
    pub min_points: usize,
    /// The projection may run this far past the fitted segment's ends, metres. Default 0.05.
    pub end_margin_m: f64,
}

impl Default for LineParams {
    fn default() -> Self {
        LineParams {
            neighbours: 10,
            max_point_distance_m: 0.05,
            noise_floor_m: 0.01,
            max_rms_m: 0.02,
            min_points: 5,
            end_margin_m: 0.05,
        }
    }
}

/// A fitted segment: centroid, unit direction and the extent along it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Line {
    /// Centroid of the points.
    pub centroid: [f64; 2],
    /// Unit vector along the principal eigenvector.
    pub direction: [f64; 2],
    /// Smallest and largest position of a point along `direction`, from the centroid.
    pub extent: [f64; 2],
    /// RMS distance of the points to the line.
    pub rms: f64,
    /// Points in the fit.
    pub points: usize,
}

impl Line {
    /// The orthogonal projection of `p` on the line (E.31–E.32), held within the segment plus
    /// `margin`.
    pub fn project(&self, p: [f64; 2], margin: f64) -> [f64; 2] {
        self.projection(p, margin).0
    }

    /// [`Line::project`], and whether the projection fell inside the extended segment (not
    /// moved to one of its ends).
    pub fn projection(&self, p: [f64; 2], margin: f64) -> ([f64; 2], bool) {
        let along = (p[0] - self.centroid[0]) * self.direction[0]
            + (p[1] - self.centroid[1]) * self.direction[1];
        // max/min rather than clamp: never a panic, whatever the numbers.
        let t = along
            .max(self.extent[0] - margin)
            .min(self.extent[1] + margin);
        let point = [
            self.centroid[0] + t * self.direction[0],
            self.centroid[1] + t * self.direction[1],
        ];
        (point, t == along)
    }

    /// The line's unit normal (its direction turned a quarter left).
    pub fn normal(&self) -> [f64; 2] {
        [-self.direction[1], self.direction[0]]
    }
}

/// A fitted line: centroid, unit direction, and the mean squared distance of its points.
type Fit = ([f64; 2], [f64; 2], f64);

/// Running sums of a point set, fitted by principal components on demand.
#[derive(Copy, Clone, Debug, Default)]
struct Moments {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
}

impl Moments {
    fn with(mut self, p: [f64; 2]) -> Self {
        self.n += 1.0;
        self.sx += p[0];
        self.sy += p[1];
        self.sxx += p[0] * p[0];
        self.sxy += p[0] * p[1];
        self.syy += p[1] * p[1];
        self
    }

    /// Centroid, principal unit direction and the smaller eigenvalue (the mean squared distance
    /// to the line), from the covariance matrix (E.20–E.30), the direction by the angle as the
    /// thesis takes it: what [`Moments::fit_quick`] is tested against.
    #[cfg(test)]
    fn fit(&self) -> Fit {
        let (centroid, covariance, small, _) = self.moments();
        ([centroid[0], centroid[1]], direction(covariance), small)
    }

    /// The fit of the thesis (E.20–E.30) with the direction by square roots instead of an
    /// arctangent, a sine and a cosine (the angle's fit, kept for the tests): the same line to
    /// the last bit or two. Those three functions, nine times a reference point, were half the
    /// instructions of [`lines_of`], itself a tenth of a `lorentz-lines` match. The line kept
    /// is this fit too since 2026-11-28: refitting it by the angle at the end took 3 % of a
    /// synthetic match (`perf`), and its answers moved by less than the tests' margins
    /// (`studies/scan-matching-notebook.md`, *Cheaper first passes and lines*).
    fn fit_quick(&self) -> Fit {
        let (centroid, [cxx, cxy, cyy], small, root) = self.moments();
        let (a, b) = (cxx - cyy, 2.0 * cxy);
        // √(a² + b²) is the eigenvalues' spread `moments` took: (2 cxy)² and 4 cxy · cxy
        // round alike, as scaling by 2 is exact.
        let r = root;
        let quick = if r > 0.0 && r.is_finite() {
            // The half angle of (a, b): cos² = (1 + a/r) / 2, sin² = (1 − a/r) / 2, each taken
            // from the larger, so neither loses its digits; the cosine stays ≥ 0 as the
            // arctangent's half angle does.
            if a >= 0.0 {
                let c = ((r + a) / (2.0 * r)).sqrt();
                [c, b / (2.0 * r * c)]
            } else {
                let s = ((r - a) / (2.0 * r)).sqrt().copysign(b);
                [b / (2.0 * r * s), s]
            }
        } else {
            direction([cxx, cxy, cyy])
        };
        (centroid, quick, small)
    }

    /// Centroid, covariance `[cxx, cxy, cyy]`, its smaller eigenvalue and the spread of its
    /// two eigenvalues (`√((cxx − cyy)² + 4 cxy²)`).
    fn moments(&self) -> ([f64; 2], [f64; 3], f64, f64) {
        // One division and five products instead of five divisions: the growth waits on the
        // divider (`studies/scan-matching-notebook.md`, *Cheaper first passes and lines*).
        let inv = 1.0 / self.n;
        let (mx, my) = (self.sx * inv, self.sy * inv);
        let cxx = self.sxx * inv - mx * mx;
        let cxy = self.sxy * inv - mx * my;
        let cyy = self.syy * inv - my * my;
        let root = ((cxx - cyy) * (cxx - cyy) + 4.0 * cxy * cxy).sqrt();
        let small = (0.5 * (cxx + cyy - root)).max(0.0);
        ([mx, my], [cxx, cxy, cyy], small, root)
    }
}

/// The principal direction of a covariance `[cxx, cxy, cyy]` by its angle, robust where the
/// eigenvector formulas divide by 0.
pub(super) fn direction([cxx, cxy, cyy]: [f64; 3]) -> [f64; 2] {
    let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
    [angle.cos(), angle.sin()]
}

fn distance_to(p: [f64; 2], centroid: [f64; 2], direction: [f64; 2]) -> f64 {
    ((p[0] - centroid[0]) * direction[1] - (p[1] - centroid[1]) * direction[0]).abs()
}

/// Grows the line around point `k` of `points` (in beam order); `None` when it is not good.
pub fn grow_line(points: &[[f64; 2]], k: usize, params: &LineParams) -> Option<Line> {
    grow(points, k, params, Moments::fit_quick)
}

/// [`grow_line`], each neighbour tested against the line `fit` gives.
fn grow(
    points: &[[f64; 2]],
    k: usize,
    params: &LineParams,
    fit: fn(&Moments) -> Fit,
) -> Option<Line> {
    if k == 0 || k + 1 >= points.len() {
        return None;
    }
    let mut moments = Moments::default()
        .with(points[k - 1])
        .with(points[k])
        .with(points[k + 1]);
    let (mut centroid, mut direction, mut mse) = fit(&moments);
    let (mut first, mut last) = (k - 1, k + 1);
    let half = params.neighbours / 2;
    let floor = params.noise_floor_m * params.noise_floor_m;
    let mut consider = |j: usize, moments: &mut Moments| -> bool {
        let p = points[j];
        if distance_to(p, centroid, direction) >= params.max_point_distance_m {
            return false;
        }
        let trial = moments.with(p);
        let line = fit(&trial);
        if line.2 > mse.max(floor) {
            return false;
        }
        *moments = trial;
        (centroid, direction, mse) = line;
        true
    };
    for step in 1..=half {
        if let Some(j) = (k - 1).checked_sub(step)
            && consider(j, &mut moments)
        {
            first = first.min(j);
        }
        let j = k + 1 + step;
        if j < points.len() && consider(j, &mut moments) {
            last = last.max(j);
        }
    }
    let rms = mse.sqrt();
    if moments.n < params.min_points as f64 || rms >= params.max_rms_m {
        return None;
    }
    // The line kept is the growth's last fit: `fit` of the points that joined.
    let along =
        |p: [f64; 2]| (p[0] - centroid[0]) * direction[0] + (p[1] - centroid[1]) * direction[1];
    let (a, b) = (along(points[first]), along(points[last]));
    Some(Line {
        centroid,
        direction,
        extent: [a.min(b), a.max(b)],
        rms,
        points: moments.n as usize,
    })
}

/// The line of every point of a reference scan (`None` where no good line grows).
pub fn lines_of(points: &[[f64; 2]], params: &LineParams) -> Vec<Option<Line>> {
    (0..points.len())
        .map(|k| grow_line(points, k, params))
        .collect()
}

/// The lines of a reference scan's points ([`grow_line`]), each grown the first time it is
/// asked for and kept: the same lines as [`lines_of`], without growing those of the points no
/// current point comes nearest to.
#[derive(Debug)]
pub struct LazyLines<'a> {
    points: &'a [[f64; 2]],
    params: LineParams,
    grown: Vec<std::cell::OnceCell<Option<Line>>>,
}

impl<'a> LazyLines<'a> {
    /// No line grown yet, for the scan's `points` in beam order.
    pub fn new(points: &'a [[f64; 2]], params: LineParams) -> Self {
        LazyLines {
            points,
            params,
            grown: (0..points.len())
                .map(|_| std::cell::OnceCell::new())
                .collect(),
        }
    }

    /// The line around point `k` (`None` where no good line grows, or past the scan's end).
    pub fn get(&self, k: usize) -> Option<&Line> {
        let cell = self.grown.get(k)?;
        cell.get_or_init(|| grow_line(self.points, k, &self.params))
            .as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Asked in any order, and again, the lazy lines are the lines grown all at once.
    #[test]
    fn lazy_lines_are_the_lines_grown_at_once() {
        // A wall, a corner onto another, and a few scattered points.
        let mut points: Vec<[f64; 2]> = (0..20).map(|i| [i as f64 * 0.1, 2.0]).collect();
        points.extend((1..15).map(|i| [1.9, 2.0 - i as f64 * 0.1]));
        points.extend([[0.3, 0.4], [-1.0, 0.7], [2.5, -0.2]]);
        let params = LineParams::default();
        let all = lines_of(&points, &params);
        assert!(all.iter().filter(|l| l.is_some()).count() > 20);
        let lazy = LazyLines::new(&points, params);
        for k in (0..points.len()).rev().chain(0..points.len() + 2) {
            assert_eq!(
                lazy.get(k),
                all.get(k).and_then(Option::as_ref),
                "point {k}"
            );
        }
    }

    #[test]
    fn a_wall_gives_a_good_line_and_an_exact_projection() {
        // Points on y = 2 with ±5 mm of alternating noise, and one outlier beside them.
        let mut points: Vec<[f64; 2]> = (0..15)
            .map(|i| {
                [
                    i as f64 * 0.1,
                    2.0 + if i % 2 == 0 { 0.005 } else { -0.005 },
                ]
            })
            .collect();
        points[9] = [0.9, 2.6];
        let line = grow_line(&points, 7, &LineParams::default()).unwrap();
        assert!(line.direction[1].abs() < 0.02, "{line:?}");
        assert!(line.rms < 0.01);
        assert!(
            line.points >= 9,
            "the outlier stays out, the rest joins: {line:?}"
        );
        let q = line.project([0.73, 1.5], 0.05);
        assert!(
            (q[0] - 0.73).abs() < 0.01 && (q[1] - 2.0).abs() < 0.01,
            "{q:?}"
        );
        // Projections stay on the segment.
        let end = line.project([10.0, 2.0], 0.05);
        assert!(end[0] < 1.5 + 0.06, "{end:?}");
    }

    /// The growth tests each neighbour against a line whose direction comes from square roots
    /// ([`Moments::fit_quick`]); the lines are those of the arctangent's direction throughout,
    /// over walls at every heading with range noise, corners and outliers: the same points
    /// join, the same RMS to the last bit, and the directions, centroids and extents the same
    /// but for roundings; and the two directions agree to 1e-15 at every angle, the axes'
    /// included.
    #[test]
    fn the_quick_direction_grows_the_same_lines() {
        let mut rng = crate::test_rng::XorShift(0x2545_f491_4f6c_dd1d);
        let mut uniform = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let params = LineParams::default();
        let (mut lines, mut points_seen) = (0, 0);
        for scan in 0..200 {
            // A wall at a random heading (the axes every tenth scan), bent into a corner halfway
            // on every third, ±1 cm of noise, a far outlier now and then.
            let heading = if scan % 10 == 0 {
                f64::from(scan / 10 % 4) * std::f64::consts::FRAC_PI_2
            } else {
                uniform() * std::f64::consts::TAU
            };
            let step = 0.01 + 0.04 * uniform();
            let mut p = [4.0 * uniform() - 2.0, 4.0 * uniform() - 2.0];
            let mut points = Vec::new();
            for i in 0..120 {
                let h = if scan % 3 == 0 && i > 60 {
                    heading + std::f64::consts::FRAC_PI_2
                } else {
                    heading
                };
                p = [p[0] + step * h.cos(), p[1] + step * h.sin()];
                let noise = if scan % 2 == 0 {
                    0.02 * uniform() - 0.01
                } else {
                    0.0
                };
                let q = [p[0] - noise * h.sin(), p[1] + noise * h.cos()];
                points.push(if uniform() < 0.03 {
                    [q[0] + 3.0 * uniform(), q[1] - 3.0 * uniform()]
                } else {
                    q
                });
            }
            for k in 0..points.len() {
                let quick = grow_line(&points, k, &params);
                let angle = grow(&points, k, &params, Moments::fit);
                match (quick, angle) {
                    (Some(q), Some(a)) => {
                        assert_eq!((q.points, q.rms), (a.points, a.rms), "scan {scan}, {k}");
                        let close = |x: &[f64], y: &[f64]| {
                            x.iter().zip(y).all(|(u, v)| (u - v).abs() < 1e-12)
                        };
                        assert!(
                            close(&q.direction, &a.direction)
                                && close(&q.centroid, &a.centroid)
                                && close(&q.extent, &a.extent),
                            "scan {scan}, point {k}: {q:?} {a:?}"
                        );
                    }
                    (q, a) => assert_eq!(q, a, "scan {scan}, point {k}"),
                }
                lines += usize::from(quick.is_some());
                points_seen += 1;
            }
        }
        assert!(
            lines > points_seen / 2,
            "{lines} lines of {points_seen} points"
        );
        for i in 0..=720 {
            let a = f64::from(i) * std::f64::consts::PI / 360.0;
            let moments = [
                [0.0, 0.0],
                [a.cos(), a.sin()],
                [2.0 * a.cos(), 2.0 * a.sin()],
            ]
            .into_iter()
            .fold(Moments::default(), Moments::with);
            let (quick, angle) = (moments.fit_quick().1, moments.fit().1);
            // One line, two ways round: compare the directions up to their sign.
            let dot = quick[0] * angle[0] + quick[1] * angle[1];
            assert!((dot.abs() - 1.0).abs() < 1e-15, "{i}: {quick:?} {angle:?}");
            assert!(
                quick[0] >= 0.0 && angle[0] >= -1e-15,
                "{i}: {quick:?} {angle:?}"
            );
        }
    }

    #[test]
    fn a_corner_or_scatter_gives_no_line() {
        let corner = [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 2.0]];
        assert!(grow_line(&corner, 1, &LineParams::default()).is_none());
        assert!(grow_line(&corner, 0, &LineParams::default()).is_none());
    }
}
