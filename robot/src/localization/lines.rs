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
    /// to the line), from the covariance matrix (E.20–E.30).
    fn fit(&self) -> ([f64; 2], [f64; 2], f64) {
        let (mx, my) = (self.sx / self.n, self.sy / self.n);
        let cxx = self.sxx / self.n - mx * mx;
        let cxy = self.sxy / self.n - mx * my;
        let cyy = self.syy / self.n - my * my;
        let root = ((cxx - cyy) * (cxx - cyy) + 4.0 * cxy * cxy).sqrt();
        let small = (0.5 * (cxx + cyy - root)).max(0.0);
        // The principal direction's angle, robust where the eigenvector formulas divide by 0.
        let angle = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        ([mx, my], [angle.cos(), angle.sin()], small)
    }
}

fn distance_to(p: [f64; 2], centroid: [f64; 2], direction: [f64; 2]) -> f64 {
    ((p[0] - centroid[0]) * direction[1] - (p[1] - centroid[1]) * direction[0]).abs()
}

/// Grows the line around point `k` of `points` (in beam order); `None` when it is not good.
pub fn grow_line(points: &[[f64; 2]], k: usize, params: &LineParams) -> Option<Line> {
    if k == 0 || k + 1 >= points.len() {
        return None;
    }
    let mut moments = Moments::default()
        .with(points[k - 1])
        .with(points[k])
        .with(points[k + 1]);
    let (mut centroid, mut direction, mut mse) = moments.fit();
    let (mut first, mut last) = (k - 1, k + 1);
    let half = params.neighbours / 2;
    let floor = params.noise_floor_m * params.noise_floor_m;
    let mut consider = |j: usize, moments: &mut Moments| -> bool {
        let p = points[j];
        if distance_to(p, centroid, direction) >= params.max_point_distance_m {
            return false;
        }
        let trial = moments.with(p);
        let fit = trial.fit();
        if fit.2 > mse.max(floor) {
            return false;
        }
        *moments = trial;
        (centroid, direction, mse) = fit;
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

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn a_corner_or_scatter_gives_no_line() {
        let corner = [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 2.0]];
        assert!(grow_line(&corner, 1, &LineParams::default()).is_none());
        assert!(grow_line(&corner, 0, &LineParams::default()).is_none());
    }
}
