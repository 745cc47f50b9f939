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
        let mut best = match hint.and_then(|h| self.original.get(h).map(|&p| (h, p))) {
            Some((h, p)) => {
                let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
                (h, dx * dx + dy * dy)
            }
            None => (usize::MAX, f64::INFINITY),
        };
        let mut others = f64::INFINITY;
        if self.points.is_empty() {
            return None;
        }
        self.search_bounded(0, self.points.len(), q, &mut best, &mut others);
        if best.0 == usize::MAX {
            return None; // (only without a hint: `last` was `None`)
        }
        // Every other point is at least √others from q, the answer √d² from it: while q moves
        // less than half the difference, nothing can overtake the answer. A nanometre and a
        // relative 10⁻¹² are kept back for the roundings of the squared distances.
        let (near, far) = (best.1.sqrt(), others.sqrt());
        let reach = 0.5 * (far - near) - 1e-9 - 1e-12 * far;
        *last = Some(LastNearest {
            query: q,
            index: best.0,
            reach2: if reach > 0.0 { reach * reach } else { 0.0 },
        });
        Some(best)
    }

    /// [`search`](Self::search) by Euclidean distance, visiting the same nodes in the same order
    /// (so it finds the same point), that also keeps in `others` a lower bound on the squared
    /// distance from `q` of every point but the best: the other points it measured, and the
    /// squared gap to each range it did not enter.
    fn search_bounded(
        &self,
        lo: usize,
        hi: usize,
        q: [f64; 2],
        best: &mut (usize, f64),
        others: &mut f64,
    ) {
        let visit = |k: usize, best: &mut (usize, f64), others: &mut f64| {
            let original = self.index[k] as usize;
            let p = self.points[k];
            let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
            let d = dx * dx + dy * dy;
            if original == best.0 {
                return; // the hint, met again in the tree
            }
            if d < best.1 {
                *others = others.min(best.1);
                *best = (original, d);
            } else {
                *others = others.min(d);
            }
        };
        if hi - lo <= LEAF {
            for k in lo..hi {
                visit(k, best, others);
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let a = usize::from(self.axis[mid]);
        let gap = q[a] - self.points[mid][a];
        visit(mid, best, others);
        let (near, far) = if gap < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search_bounded(near.0, near.1, q, best, others);
        if gap * gap < best.1 {
            self.search_bounded(far.0, far.1, q, best, others);
        } else if far.0 < far.1 {
            // Every point beyond the splitting line is at least the gap away.
            *others = others.min(gap * gap);
        }
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
        mut metric: impl FnMut(usize, [f64; 2]) -> f64,
    ) -> Option<(usize, f64)> {
        if self.points.is_empty() {
            return None;
        }
        let mut best = match hint.and_then(|h| self.original.get(h).map(|&p| (h, p))) {
            Some((h, p)) => (h, metric(h, p)),
            None => (usize::MAX, f64::INFINITY),
        };
        self.search(0, self.points.len(), q, bound_scale, &mut metric, &mut best);
        // No point at a finite distance (a query or points at infinity, a metric of NaN).
        (best.0 != usize::MAX).then_some(best)
    }

    fn search(
        &self,
        lo: usize,
        hi: usize,
        q: [f64; 2],
        bound_scale: f64,
        metric: &mut impl FnMut(usize, [f64; 2]) -> f64,
        best: &mut (usize, f64),
    ) {
        if hi - lo <= LEAF {
            for k in lo..hi {
                let original = self.index[k] as usize;
                let d = metric(original, self.points[k]);
                if d < best.1 {
                    *best = (original, d);
                }
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let a = usize::from(self.axis[mid]);
        let gap = q[a] - self.points[mid][a];
        let original = self.index[mid] as usize;
        let d = metric(original, self.points[mid]);
        if d < best.1 {
            *best = (original, d);
        }
        let (near, far) = if gap < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, q, bound_scale, metric, best);
        if bound_scale * gap * gap < best.1 {
            self.search(far.0, far.1, q, bound_scale, metric, best);
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

    #[test]
    fn empty_and_tiny_trees() {
        assert!(KdTree::new(&[]).nearest([0.0, 0.0]).is_none());
        let tree = KdTree::new(&[[1.0, 1.0]]);
        assert_eq!(tree.nearest([0.0, 0.0]), Some((0, 2.0)));
    }
}
