//! A static 2D k-d tree for the correspondence search.
//!
//! Why a tree and not a projective window: the nearest point on a wall seen at a grazing angle
//! can be tens of beams away from the beam that points at the query, and after a 25° turn the
//! whole scan shifts by 50 beams; a window wide enough for both costs more than the tree
//! (`cargo bench --bench matchers` measures both sides of a match). The tree answers the exact
//! nearest neighbour, for any metric whose distance to a point beyond a splitting line is at
//! least a known multiple of the Euclidean gap (MbICP's metric is one).
//!
//! The tree is implicit: the points are reordered so that every sub-range `[lo, hi)` keeps its
//! median at `(lo + hi) / 2`, split along the axis of larger extent. Small ranges are scanned.

/// Sub-ranges this short are searched point by point.
const LEAF: usize = 6;

/// The far sides a search keeps waiting in a tree of up to [`SHORT_STACK_POINTS`] points: a
/// range of `n` points splits into two of at most `n / 2`, so below a range of `LEAF · 2^k`
/// points lie at most `k` splits, and one far side waits for each.
const SHORT_STACK: usize = 12;

/// The most points a tree may hold for a search to keep [`SHORT_STACK`]: ten splits, and two
/// to spare.
const SHORT_STACK_POINTS: usize = LEAF << 10;

/// … and in any tree: it holds fewer than 2³² points (their indices are `u32`), so 33 levels
/// hold any.
const LONG_STACK: usize = 34;

/// A k-d tree over a fixed set of points.
///
/// ```
/// use robot::localization::KdTree;
/// let tree = KdTree::new(&[[0.0, 0.0], [1.0, 0.0], [0.0, 2.0], [5.0, 5.0]]);
/// let (i, d2) = tree.nearest([0.9, 0.2]).unwrap();
/// assert_eq!(i, 1);
/// assert!((d2 - 0.05).abs() < 1e-12);
/// ```
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    /// The points, reordered into tree order.
    points: Vec<[f64; 2]>,
    /// For each point in tree order, its index in the caller's slice.
    index: Vec<u32>,
    /// For each node (the median of a range), its splitting axis.
    axis: Vec<u8>,
    /// The points in the caller's order, for hints.
    original: Vec<[f64; 2]>,
}

impl KdTree {
    /// Builds the tree (O(n log n)).
    pub fn new(points: &[[f64; 2]]) -> Self {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut axis = vec![0u8; points.len()];
        build(points, &mut order, &mut axis);
        KdTree {
            points: order.iter().map(|&i| points[i as usize]).collect(),
            index: order,
            axis,
            original: points.to_vec(),
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the tree holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The nearest point to `q` by Euclidean distance: its index in the slice the tree was built
    /// from, and the squared distance.
    pub fn nearest(&self, q: [f64; 2]) -> Option<(usize, f64)> {
        self.nearest_from(q, None)
    }

    /// [`nearest`](Self::nearest), starting from the point `hint` (an index into the caller's
    /// slice, e.g. the last answer for this query): a good hint prunes most of the tree.
    pub fn nearest_from(&self, q: [f64; 2], hint: Option<usize>) -> Option<(usize, f64)> {
        self.nearest_by(q, 1.0, hint, |_, p| {
            let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
            dx * dx + dy * dy
        })
    }

    /// [`nearest_from`](Self::nearest_from) for a query that moves little from one call to the
    /// next (a point of a scan being aligned, from one iteration to the next): the same answer,
    /// to the last bit, without a search while the query stays so near where it was last
    /// searched that no other point can have come nearer. `last` holds what that search found;
    /// start it as `None`, and give each query its own.
    pub fn nearest_cached(
        &self,
        q: [f64; 2],
        last: &mut Option<LastNearest>,
    ) -> Option<(usize, f64)> {
        let hint = last.map(|c| c.index);
        self.nearest_cached_from(q, last, hint)
    }

    /// [`nearest_cached`](Self::nearest_cached) answering [`nearest_from`](Self::nearest_from)
    /// with another `hint` (a neighbouring query's answer), which only decides between points
    /// exactly as near: the search is skipped only when one point is nearest by a margin.
    pub fn nearest_cached_from(
        &self,
        q: [f64; 2],
        last: &mut Option<LastNearest>,
        hint: Option<usize>,
    ) -> Option<(usize, f64)> {
        if let Some(c) = last {
            let (mx, my) = (q[0] - c.query[0], q[1] - c.query[1]);
            if mx * mx + my * my < c.reach2 {
                // Still the unique nearest point: its squared distance as the search takes it.
                let p = self.original[c.index];
                let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
                return Some((c.index, dx * dx + dy * dy));
            }
        }
        let (index, d2, others) = self.nearest_bounded(q, 1.0, hint, |_, p| {
            let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
            dx * dx + dy * dy
        })?;
        // Every other point is at least √others from q, the answer √d² from it: while q moves
        // less than half the difference, nothing can overtake the answer. A nanometre and a
        // relative 10⁻¹² are kept back for the roundings of the squared distances.
        let (near, far) = (d2.sqrt(), others.sqrt());
        let reach = 0.5 * (far - near) - 1e-9 - 1e-12 * far;
        *last = Some(LastNearest {
            query: q,
            index,
            reach2: if reach > 0.0 { reach * reach } else { 0.0 },
        });
        Some((index, d2))
    }

    /// The point minimising `metric(index, point)` (a squared distance), given that for any point
    /// on the far side of a splitting line at gap `g` from `q`, `metric >= bound_scale · g²`;
    /// the search starts from `hint` when given.
    ///
    /// `metric` receives the point's index in the slice the tree was built from and the point,
    /// so it may look at other data for that point (MbICP measures in another frame).
    pub fn nearest_by(
        &self,
        q: [f64; 2],
        bound_scale: f64,
        hint: Option<usize>,
        metric: impl FnMut(usize, [f64; 2]) -> f64,
    ) -> Option<(usize, f64)> {
        self.nearest_with(q, bound_scale, hint, metric, ())
            .map(|(index, d, ())| (index, d))
    }

    /// [`nearest_by`](Self::nearest_by), and a lower bound on the metric of every other point.
    fn nearest_bounded(
        &self,
        q: [f64; 2],
        bound_scale: f64,
        hint: Option<usize>,
        metric: impl FnMut(usize, [f64; 2]) -> f64,
    ) -> Option<(usize, f64, f64)> {
        self.nearest_with(q, bound_scale, hint, metric, f64::INFINITY)
    }

    /// The search, `others` keeping what it learns of the points that are not the best (or
    /// nothing, for `()`).
    fn nearest_with<M: FnMut(usize, [f64; 2]) -> f64, O: Others>(
        &self,
        q: [f64; 2],
        bound_scale: f64,
        hint: Option<usize>,
        mut metric: M,
        mut others: O,
    ) -> Option<(usize, f64, O)> {
        if self.points.is_empty() {
            return None;
        }
        let mut best = match hint.and_then(|h| self.original.get(h).map(|&p| (h, p))) {
            Some((h, p)) => (h, metric(h, p)),
            None => (usize::MAX, f64::INFINITY),
        };
        let mut search = Search {
            q,
            bound_scale,
            metric: &mut metric,
            best: &mut best,
            others: &mut others,
        };
        // A scan's tree is shallow: its search keeps the short stack, which costs less to set
        // up (the long one, zeroed on every search, was 3 % of a match).
        if self.points.len() <= SHORT_STACK_POINTS {
            self.search::<_, _, SHORT_STACK>(0, self.points.len(), &mut search);
        } else {
            self.search::<_, _, LONG_STACK>(0, self.points.len(), &mut search);
        }
        // No point at a finite distance (a query or points at infinity, a metric of NaN).
        (best.0 != usize::MAX).then_some((best.0, best.1, others))
    }

    /// Searches the range `[lo, hi)`: near side first, the far side only when the splitting
    /// line is nearer than the best so far (found on the near side included). A loop with the
    /// far sides waiting on a stack, in the order a recursion would take them: the same points
    /// visited in the same order, without a call per node.
    fn search<M: FnMut(usize, [f64; 2]) -> f64, O: Others, const DEPTH: usize>(
        &self,
        lo: usize,
        hi: usize,
        s: &mut Search<M, O>,
    ) {
        // A far side waiting: its range and the squared gap to its splitting line (scaled), one
        // for each level above the current range (`DEPTH` as [`SHORT_STACK`] and
        // [`LONG_STACK`] say).
        let mut waiting = [(0u32, 0u32, 0.0f64); DEPTH];
        let mut top = 0;
        let (mut lo, mut hi) = (lo, hi);
        loop {
            while hi - lo > LEAF {
                let mid = (lo + hi) / 2;
                let a = usize::from(self.axis[mid]);
                let gap = s.q[a] - self.points[mid][a];
                s.visit(self.index[mid] as usize, self.points[mid]);
                let (near, far) = if gap < 0.0 {
                    ((lo, mid), (mid + 1, hi))
                } else {
                    ((mid + 1, hi), (lo, mid))
                };
                waiting[top] = (far.0 as u32, far.1 as u32, s.bound_scale * gap * gap);
                top += 1;
                (lo, hi) = near;
            }
            for k in lo..hi {
                s.visit(self.index[k] as usize, self.points[k]);
            }
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let (far_lo, far_hi, bound) = waiting[top];
                let (far_lo, far_hi) = (far_lo as usize, far_hi as usize);
                if bound < s.best.1 {
                    (lo, hi) = (far_lo, far_hi);
                    break;
                } else if far_lo < far_hi {
                    // Every point beyond the splitting line is at least that far.
                    s.others.at_least(bound);
                }
            }
        }
    }
}

/// What a search keeps of the points that are not the best: a lower bound on their metric
/// (`f64`), or nothing (`()`, costing nothing).
trait Others {
    /// Some other point is this far (or farther).
    fn at_least(&mut self, d: f64);
}

impl Others for () {
    #[inline(always)]
    fn at_least(&mut self, _: f64) {}
}

impl Others for f64 {
    #[inline(always)]
    fn at_least(&mut self, d: f64) {
        *self = self.min(d);
    }
}

/// One search's query, metric and findings: the best point so far, and what is known of every
/// other point (those measured, and the bound of each range not entered).
struct Search<'a, M, O> {
    q: [f64; 2],
    bound_scale: f64,
    metric: &'a mut M,
    best: &'a mut (usize, f64),
    others: &'a mut O,
}

impl<M: FnMut(usize, [f64; 2]) -> f64, O: Others> Search<'_, M, O> {
    fn visit(&mut self, original: usize, p: [f64; 2]) {
        if original == self.best.0 {
            return; // the hint, met again in the tree
        }
        let d = (self.metric)(original, p);
        if d < self.best.1 {
            self.others.at_least(self.best.1);
            *self.best = (original, d);
        } else {
            self.others.at_least(d);
        }
    }
}

/// What [`KdTree::nearest_cached`] found for a query the last time it searched.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LastNearest {
    /// The query searched for.
    query: [f64; 2],
    /// The nearest point's index in the caller's slice.
    index: usize,
    /// How far (squared) the query may move from there with that point staying the nearest.
    reach2: f64,
}

fn build(points: &[[f64; 2]], order: &mut [u32], axis: &mut [u8]) {
    if order.len() <= LEAF {
        return;
    }
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &i in order.iter() {
        let p = points[i as usize];
        for a in 0..2 {
            min[a] = min[a].min(p[a]);
            max[a] = max[a].max(p[a]);
        }
    }
    let a = usize::from(max[1] - min[1] > max[0] - min[0]);
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&i, &j| {
        points[i as usize][a].total_cmp(&points[j as usize][a])
    });
    axis[mid] = a as u8;
    let (left, rest) = order.split_at_mut(mid);
    let (left_axis, rest_axis) = axis.split_at_mut(mid);
    build(points, left, left_axis);
    build(points, &mut rest[1..], &mut rest_axis[1..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(points: &[[f64; 2]], q: [f64; 2]) -> f64 {
        points
            .iter()
            .map(|p| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2))
            .fold(f64::INFINITY, f64::min)
    }

    /// A deterministic scatter: a scan-like arc plus a grid whose columns are `column` apart.
    fn arc_and_grid(column: f64) -> Vec<[f64; 2]> {
        let mut points = Vec::new();
        for i in 0..361 {
            let a = (i as f64 * 0.5 - 90.0).to_radians();
            let r = 2.0 + (i as f64 * 0.37).sin();
            points.push([r * a.cos(), r * a.sin()]);
        }
        for i in 0..20 {
            for j in 0..7 {
                points.push([i as f64 * column - 3.0, j as f64 * 0.5 - 1.0]);
            }
        }
        points
    }

    #[test]
    fn nearest_matches_brute_force() {
        let points = arc_and_grid(0.3);
        let tree = KdTree::new(&points);
        for k in 0..500 {
            let q = [
                (k as f64 * 0.731).sin() * 4.0,
                (k as f64 * 1.37).cos() * 3.0,
            ];
            let (i, d) = tree.nearest(q).unwrap();
            assert_eq!(d, brute(&points, q), "query {q:?}");
            assert_eq!(tree.nearest_from(q, Some(k % points.len())), Some((i, d)));
            let p = points[i];
            assert_eq!((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2), d);
        }
    }

    /// Queries that walk in small and large steps, as a scan's points do while it is aligned,
    /// over a scan-like arc, a grid with exact ties and repeated points: the cached search
    /// answers what the search from the last answer does, index and squared distance to the
    /// bit, and skips most searches on small steps.
    #[test]
    fn the_cached_search_answers_as_the_search_from_the_last_answer() {
        let mut points = arc_and_grid(0.25);
        points.extend_from_slice(&[[0.5, 0.5], [0.5, 0.5], [1.0, -1.0]]);
        let tree = KdTree::new(&points);
        let mut skipped = 0;
        let mut total = 0;
        for walk in 0..60 {
            let mut q = [
                (walk as f64 * 0.731).sin() * 4.0,
                (walk as f64 * 1.37).cos() * 3.0,
            ];
            if walk % 10 == 0 {
                q = [-3.0 + 0.125, 0.0]; // halfway between two grid points: a tie
            }
            let (mut last, mut hint, mut other) = (None, None, None);
            for step in 0..200 {
                // Shrinking steps (an alignment converging), then a jump now and then.
                let size = if step % 50 == 49 {
                    0.5
                } else {
                    0.05 / (1 + step % 50) as f64
                };
                let turn = (walk * 31 + step) as f64 * 0.618;
                q = [q[0] + size * turn.cos(), q[1] + size * turn.sin()];
                let before = last;
                let cached = tree.nearest_cached(q, &mut last);
                let searched = tree.nearest_from(q, hint);
                assert_eq!(cached, searched, "walk {walk} step {step} at {q:?}");
                // With another hint (a neighbour's answer): what the search from it answers.
                let foreign = Some((walk * 7 + step * 13) % points.len());
                assert_eq!(
                    tree.nearest_cached_from(q, &mut other, foreign),
                    tree.nearest_from(q, foreign),
                    "walk {walk} step {step}, hint {foreign:?}"
                );
                hint = searched.map(|(j, _)| j);
                total += 1;
                if before.is_some() && before == last {
                    skipped += 1;
                }
            }
        }
        assert!(skipped * 2 > total, "{skipped} of {total} searches skipped");
        // Not a number: no skip, and the search's own answer.
        let mut last = None;
        let q = [0.4, 0.4];
        let first = tree.nearest_cached(q, &mut last);
        assert_eq!(first, tree.nearest_from(q, None));
        let nan = [f64::NAN, 0.0];
        assert_eq!(
            tree.nearest_cached(nan, &mut last).map(|(j, _)| j),
            tree.nearest_from(nan, first.map(|(j, _)| j))
                .map(|(j, _)| j)
        );
    }

    /// Trees of every size around the largest one a search keeps its short stack for (and a
    /// line of points, which splits the most evenly) answer as brute force: the short stack
    /// is deep enough wherever it is used.
    #[test]
    fn trees_either_side_of_the_short_stack_answer_as_brute_force() {
        for n in [
            1,
            LEAF,
            LEAF + 1,
            361,
            SHORT_STACK_POINTS - 1,
            SHORT_STACK_POINTS,
            SHORT_STACK_POINTS + 1,
        ] {
            let scattered: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    let k = i as f64;
                    [(k * 0.618).fract() * 10.0, (k * 0.414).fract() * 10.0]
                })
                .collect();
            let line: Vec<[f64; 2]> = (0..n).map(|i| [i as f64 * 0.01, 0.0]).collect();
            for points in [scattered, line] {
                let tree = KdTree::new(&points);
                for k in 0..200 {
                    let q = [
                        (k as f64 * 0.37).sin() * 12.0,
                        (k as f64 * 0.91).cos() * 0.5,
                    ];
                    let (_, d) = tree.nearest(q).unwrap();
                    assert_eq!(d, brute(&points, q), "{n} points, query {q:?}");
                }
            }
        }
    }

    /// A large tree with long runs of repeated points and two clusters far apart: the walk's
    /// stack holds every level, and the answers are brute force's.
    #[test]
    fn a_large_tree_with_repeated_points_answers_as_brute_force() {
        let mut points = Vec::new();
        for i in 0..120_000 {
            let k = f64::from(i / 7); // seven copies of each point
            points.push([(k * 0.618).fract() * 10.0, (k * 0.414).fract() * 10.0]);
        }
        points.extend((0..1000).map(|i| [1e4 + f64::from(i), -1e4]));
        let tree = KdTree::new(&points);
        for k in 0..300 {
            let q = [
                (k as f64 * 0.37).sin() * 12.0,
                (k as f64 * 0.91).cos() * 12.0,
            ];
            let (i, d) = tree.nearest(q).unwrap();
            assert_eq!(d, brute(&points, q), "query {q:?}");
            assert_eq!(tree.nearest_from(q, Some(i)), Some((i, d)));
        }
        let far = [1e4 + 500.2, -1e4 + 0.1];
        assert_eq!(tree.nearest(far).map(|(i, _)| i), Some(120_000 + 500));
    }

    #[test]
    fn empty_and_tiny_trees() {
        assert!(KdTree::new(&[]).nearest([0.0, 0.0]).is_none());
        let tree = KdTree::new(&[[1.0, 1.0]]);
        assert_eq!(tree.nearest([0.0, 0.0]), Some((0, 2.0)));
    }
}
