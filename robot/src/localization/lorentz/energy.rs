//! The Lorentzian's energy over a search's pairs, its analytic gradient and Hessian (App. F),
//! in the thesis's product form or to the reference's lines, and the Newton–Levenberg–Marquardt
//! steps that minimise it (§3.4.2).

use super::Lorentz;
use crate::localization::matcher::solve3;

impl Lorentz {
    /// The Lorentzian error of pairs `(source moved by phi, target)` at scale σ.
    fn energy(src: &[[f64; 2]], dst: &[[f64; 2]], phi: [f64; 3], two_s2: f64) -> f64 {
        let (s, c) = phi[0].sin_cos();
        let inv = 1.0 / two_s2;
        let factor = |(p, q): (&[f64; 2], &[f64; 2])| {
            let (_, e) = moved(p, q, (s, c), phi);
            factor(e, &None, inv)
        };
        // The logarithm of a product of eight factors instead of eight logarithms: the same sum
        // but for rounding, at an eighth of the cost. A product that overflows (residuals of
        // kilometres at a σ of millimetres) is summed term by term.
        src.chunks(8)
            .zip(dst.chunks(8))
            .map(|(p, q)| {
                let product: f64 = p.iter().zip(q).map(factor).product();
                if product.is_finite() {
                    product.ln()
                } else {
                    p.iter().zip(q).map(|pq| factor(pq).ln()).sum()
                }
            })
            .sum()
    }

    /// Gradient `B` and Hessian `A` of the error (App. F, F.12–F.13, with the common factor kept).
    fn derivatives(
        src: &[[f64; 2]],
        dst: &[[f64; 2]],
        phi: [f64; 3],
        two_s2: f64,
    ) -> ([f64; 3], [[f64; 3]; 3]) {
        let (s, c) = phi[0].sin_cos();
        let (mut g, mut h) = ([0.0; 3], [[0.0; 3]; 3]);
        for (p, q) in src.iter().zip(dst) {
            // Rotated point; x' = rx + tx, ∂x'/∂θ = −ry, ∂²x'/∂θ² = −rx; ∂y'/∂θ = rx, ∂²y'/∂θ² = −ry.
            let (r, e) = moved(p, q, (s, c), phi);
            add_product_pair((&mut g, &mut h), r, e, two_s2);
        }
        h[1][0] = h[0][1];
        h[2][0] = h[0][2];
        (g, h)
    }

    /// The error of [`Lorentz::energy`] with point-to-line residuals: a pair with a normal
    /// `n` (its target a projection inside a reference line) counts `ρσ(n · e)` alone.
    fn energy_to_lines(pairs: Pairs<'_>, normals: &[Normal], phi: [f64; 3], two_s2: f64) -> f64 {
        let (src, dst) = pairs;
        let (s, c) = phi[0].sin_cos();
        let inv = 1.0 / two_s2;
        let factor = |p: &[f64; 2], q: &[f64; 2], n: &Normal| {
            let (_, e) = moved(p, q, (s, c), phi);
            factor(e, n, inv)
        };
        // Eight factors a logarithm, as in `energy`.
        src.chunks(8)
            .zip(dst.chunks(8))
            .zip(normals.chunks(8))
            .map(|((p, q), n)| {
                let each = || p.iter().zip(q).zip(n).map(|((p, q), n)| factor(p, q, n));
                let product: f64 = each().product();
                if product.is_finite() {
                    product.ln()
                } else {
                    each().map(f64::ln).sum()
                }
            })
            .sum()
    }

    /// Gradient and Hessian of [`Lorentz::energy_to_lines`].
    fn derivatives_to_lines(
        pairs: Pairs<'_>,
        normals: &[Normal],
        phi: [f64; 3],
        two_s2: f64,
    ) -> ([f64; 3], [[f64; 3]; 3]) {
        let (src, dst) = pairs;
        let (s, c) = phi[0].sin_cos();
        let (mut g, mut h) = ([0.0; 3], [[0.0; 3]; 3]);
        for ((p, q), n) in src.iter().zip(dst).zip(normals) {
            let (r, e) = moved(p, q, (s, c), phi);
            add_pair((&mut g, &mut h), r, e, n, two_s2);
        }
        h[1][0] = h[0][1];
        h[2][0] = h[0][2];
        h[2][1] = h[1][2];
        (g, h)
    }

    /// [`Lorentz::energy_to_lines`] (or [`Lorentz::energy`], without `normals`) and its
    /// gradient and Hessian at `phi` in one pass over the pairs: the same numbers to the bit
    /// as the two apart, each pair moved once. Each NLM minimisation starts with both.
    fn energy_and_derivatives(
        pairs: Pairs<'_>,
        normals: Option<&[Normal]>,
        phi: [f64; 3],
        two_s2: f64,
    ) -> (f64, [f64; 3], [[f64; 3]; 3]) {
        let (src, dst) = pairs;
        let (s, c) = phi[0].sin_cos();
        let inv = 1.0 / two_s2;
        let none = [None; 8];
        let (mut energy, mut g, mut h) = (-0.0, [0.0; 3], [[0.0; 3]; 3]);
        for (k, (p, q)) in src.chunks(8).zip(dst.chunks(8)).enumerate() {
            let n = normals.map_or(&none[..p.len()], |n| &n[8 * k..8 * k + p.len()]);
            let mut product = 1.0;
            for ((p, q), n) in p.iter().zip(q).zip(n) {
                let (r, e) = moved(p, q, (s, c), phi);
                product *= factor(e, n, inv);
                add_pair((&mut g, &mut h), r, e, n, two_s2);
            }
            // Eight factors a logarithm, as in `energy`.
            energy += if product.is_finite() {
                product.ln()
            } else {
                let each = p.iter().zip(q).zip(n);
                each.map(|((p, q), n)| factor(moved(p, q, (s, c), phi).1, n, inv).ln())
                    .sum()
            };
        }
        h[1][0] = h[0][1];
        h[2][0] = h[0][2];
        h[2][1] = h[1][2];
        (energy, g, h)
    }

    /// Newton–Levenberg–Marquardt on fixed pairs, from `phi`: with point-to-line residuals
    /// where `normals` gives a pair one, else the thesis's product form.
    pub(super) fn nlm(
        &self,
        pairs: Pairs<'_>,
        normals: Option<&[Normal]>,
        mut phi: [f64; 3],
        (sigma, steps): (f64, u32),
    ) -> [f64; 3] {
        let two_s2 = 2.0 * sigma * sigma;
        let energy = |phi| match normals {
            Some(normals) => Self::energy_to_lines(pairs, normals, phi, two_s2),
            None => Self::energy(pairs.0, pairs.1, phi, two_s2),
        };
        let tolerance = self.energy_tolerance * pairs.0.len() as f64;
        let (mut e, g, h) = Self::energy_and_derivatives(pairs, normals, phi, two_s2);
        // The derivatives at the start, taken with its energy.
        let mut at_start = Some((g, h));
        let mut lambda = self.lambda0;
        for _ in 0..steps {
            let (g, h) = match (at_start.take(), normals) {
                (Some(start), _) => start,
                (None, Some(normals)) => Self::derivatives_to_lines(pairs, normals, phi, two_s2),
                (None, None) => Self::derivatives(pairs.0, pairs.1, phi, two_s2),
            };
            let improvement = loop {
                let mut a = h;
                for (k, row) in a.iter_mut().enumerate() {
                    row[k] += lambda;
                }
                if let Some(d) = solve3(a, [-g[0], -g[1], -g[2]]) {
                    let trial = [phi[0] + d[0], phi[1] + d[1], phi[2] + d[2]];
                    let e1 = energy(trial);
                    if e1 < e {
                        lambda /= 10.0;
                        phi = trial;
                        let gain = e - e1;
                        e = e1;
                        break gain;
                    }
                }
                lambda *= 10.0;
                if lambda > self.lambda_max {
                    return phi;
                }
            };
            if improvement < tolerance {
                break;
            }
        }
        phi
    }
}

/// Adds one pair's terms of the product form's gradient and Hessian (upper triangle and
/// diagonal): the current point rotated, `r`, and its residual `e`.
#[inline(always)]
fn add_product_pair(
    (g, h): (&mut [f64; 3], &mut [[f64; 3]; 3]),
    [rx, ry]: [f64; 2],
    [ex, ey]: [f64; 2],
    two_s2: f64,
) {
    let (dx, dy) = (two_s2 + ex * ex, two_s2 + ey * ey);
    // ρ'(e) = 2e / D, ρ''(e) = 2 (2σ² − e²) / D².
    let (wx1, wy1) = (2.0 * ex / dx, 2.0 * ey / dy);
    let (wx2, wy2) = (
        2.0 * (two_s2 - ex * ex) / (dx * dx),
        2.0 * (two_s2 - ey * ey) / (dy * dy),
    );
    g[0] += -wx1 * ry + wy1 * rx;
    g[1] += wx1;
    g[2] += wy1;
    h[0][0] += wx2 * ry * ry - wx1 * rx + wy2 * rx * rx - wy1 * ry;
    h[0][1] += -wx2 * ry;
    h[0][2] += wy2 * rx;
    h[1][1] += wx2;
    h[2][2] += wy2;
}

/// One pair under `phi` (its sine and cosine given): the current point `p` rotated, and its
/// residual from the target `q`.
#[inline(always)]
fn moved(p: &[f64; 2], q: &[f64; 2], (s, c): (f64, f64), phi: [f64; 3]) -> ([f64; 2], [f64; 2]) {
    let rx = c * p[0] - s * p[1];
    let ry = s * p[0] + c * p[1];
    ([rx, ry], [rx + phi[1] - q[0], ry + phi[2] - q[1]])
}

/// One pair's factor in the product whose logarithm is the error: `1 + (n · e)² / 2σ²` with a
/// line normal `n`, else `(1 + e_x² / 2σ²)(1 + e_y² / 2σ²)`; `inv` is `1 / 2σ²`.
#[inline(always)]
fn factor([ex, ey]: [f64; 2], n: &Normal, inv: f64) -> f64 {
    match n {
        Some(n) => {
            let e = n[0] * ex + n[1] * ey;
            1.0 + e * e * inv
        }
        None => (1.0 + ex * ex * inv) * (1.0 + ey * ey * inv),
    }
}

/// Adds one pair's terms of the gradient and Hessian (upper triangle and diagonal): by its
/// distance to a line with the normal `n`, else by the product form.
#[inline(always)]
fn add_pair(
    (g, h): (&mut [f64; 3], &mut [[f64; 3]; 3]),
    [rx, ry]: [f64; 2],
    [ex, ey]: [f64; 2],
    n: &Normal,
    two_s2: f64,
) {
    match n {
        Some(n) => {
            // e = n · (R p + t − q): ∂e/∂Φ = (n × R p, nx, ny), ∂²e/∂θ² = −n · R p.
            let e = n[0] * ex + n[1] * ey;
            let d = two_s2 + e * e;
            let (w1, w2) = (2.0 * e / d, 2.0 * (two_s2 - e * e) / (d * d));
            let j = [-n[0] * ry + n[1] * rx, n[0], n[1]];
            for a in 0..3 {
                g[a] += w1 * j[a];
                for b in a..3 {
                    h[a][b] += w2 * j[a] * j[b];
                }
            }
            h[0][0] -= w1 * (n[0] * rx + n[1] * ry);
        }
        None => add_product_pair((g, h), [rx, ry], [ex, ey], two_s2),
    }
}

/// Pairs of points: the current ones (in their own frame) and their targets in the
/// reference's.
type Pairs<'a> = (&'a [[f64; 2]], &'a [[f64; 2]]);

/// A pair's reference line normal, where its target is a projection inside a line.
pub(super) type Normal = Option<[f64; 2]>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The energy, a logarithm per eight points, is the sum of every point's logarithm to
    /// rounding — also with residuals so large against σ that eight factors overflow.
    #[test]
    fn the_energy_is_the_sum_of_the_logarithms() {
        let src: Vec<[f64; 2]> = (0..53)
            .map(|i| [1.0 + 0.1 * i as f64, (i as f64 * 0.7).sin()])
            .collect();
        let mut dst: Vec<[f64; 2]> = src
            .iter()
            .enumerate()
            .map(|(i, p)| [p[0] + 0.03 * (i as f64).cos(), p[1] - 0.02])
            .collect();
        let phi: [f64; 3] = [0.05, 0.02, -0.01];
        let each = |dst: &[[f64; 2]], two_s2: f64| {
            let (s, c) = phi[0].sin_cos();
            src.iter()
                .zip(dst)
                .map(|(p, q)| {
                    let ex = c * p[0] - s * p[1] + phi[1] - q[0];
                    let ey = s * p[0] + c * p[1] + phi[2] - q[1];
                    ((1.0 + ex * ex / two_s2) * (1.0 + ey * ey / two_s2)).ln()
                })
                .sum::<f64>()
        };
        let two_s2 = 2.0 * 0.005f64.powi(2);
        let (chunked, summed) = (Lorentz::energy(&src, &dst, phi, two_s2), each(&dst, two_s2));
        assert!(
            (chunked - summed).abs() <= 1e-12 * summed.abs(),
            "{chunked} {summed}"
        );
        // Points 100 km off at σ 1 µm: each factor near 10³⁰⁶, a product of two overflows.
        for q in dst.iter_mut().step_by(3) {
            *q = [1e5, -1e5];
        }
        let two_s2 = 2.0 * 1e-6f64.powi(2);
        let (chunked, summed) = (Lorentz::energy(&src, &dst, phi, two_s2), each(&dst, two_s2));
        assert!(chunked.is_finite() && summed.is_finite());
        assert!(
            (chunked - summed).abs() <= 1e-12 * summed.abs(),
            "{chunked} {summed}"
        );
    }

    /// Points and targets for the derivative tests, and a mix of line normals.
    /// The energy and derivatives taken in one pass are those taken apart, to the bit: in the
    /// product form and with line normals on some pairs, at σ 5 mm and at σ 1 µm with points
    /// 100 km off (products of eight factors that overflow), over pair counts that are and are
    /// not a multiple of eight.
    #[test]
    fn one_pass_gives_the_energy_and_derivatives_of_two() {
        let (src, mut dst, normals) = pairs_for_derivatives();
        let phi = [0.05, 0.02, -0.01];
        let mut compared = 0;
        for far in [false, true] {
            if far {
                for q in dst.iter_mut().step_by(3) {
                    *q = [1e5, -1e5];
                }
            }
            let two_s2 = 2.0 * if far { 1e-6f64 } else { 0.005 }.powi(2);
            for len in [40, 37, 8, 1] {
                let pairs = (&src[..len], &dst[..len]);
                let normals = &normals[..len];
                let apart = [
                    (
                        Lorentz::energy(pairs.0, pairs.1, phi, two_s2),
                        Lorentz::derivatives(pairs.0, pairs.1, phi, two_s2),
                    ),
                    (
                        Lorentz::energy_to_lines(pairs, normals, phi, two_s2),
                        Lorentz::derivatives_to_lines(pairs, normals, phi, two_s2),
                    ),
                ];
                for (normals, (energy, (g, h))) in [None, Some(normals)].into_iter().zip(apart) {
                    let (e1, g1, h1) = Lorentz::energy_and_derivatives(pairs, normals, phi, two_s2);
                    assert!(energy.is_finite(), "{far} {len}: {energy}");
                    assert_eq!(e1.to_bits(), energy.to_bits(), "{far} {len}");
                    assert_eq!((g1, h1), (g, h), "{far} {len}");
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 16);
    }

    fn pairs_for_derivatives() -> (Vec<[f64; 2]>, Vec<[f64; 2]>, Vec<Normal>) {
        let src: Vec<[f64; 2]> = (0..40)
            .map(|i| [1.0 + 0.1 * i as f64, (i as f64 * 0.7).sin()])
            .collect();
        let dst: Vec<[f64; 2]> = src
            .iter()
            .enumerate()
            .map(|(i, p)| {
                [
                    p[0] + 0.03 * (i as f64).cos(),
                    p[1] - 0.02 + 0.01 * (i % 3) as f64,
                ]
            })
            .collect();
        let normals = (0..40)
            .map(|i| {
                let a = 0.4 * i as f64;
                (i % 4 != 0).then(|| [a.cos(), a.sin()])
            })
            .collect();
        (src, dst, normals)
    }

    /// `g` and `h` are the gradient and Hessian of `e` at `phi`, by central differences
    /// (`grad` gives the gradient elsewhere).
    fn assert_derivatives(
        phi: [f64; 3],
        (g, h): ([f64; 3], [[f64; 3]; 3]),
        e: impl Fn([f64; 3]) -> f64,
        grad: impl Fn([f64; 3]) -> [f64; 3],
    ) {
        let eps = 1e-6;
        for k in 0..3 {
            let (mut up, mut down) = (phi, phi);
            up[k] += eps;
            down[k] -= eps;
            let numeric = (e(up) - e(down)) / (2.0 * eps);
            assert!(
                (numeric - g[k]).abs() < 1e-4 * g[k].abs().max(1.0),
                "g[{k}]: {numeric} vs {}",
                g[k]
            );
            let (gu, gd) = (grad(up), grad(down));
            for m in 0..3 {
                let numeric = (gu[m] - gd[m]) / (2.0 * eps);
                assert!(
                    (numeric - h[m][k]).abs() < 1e-3 * h[m][k].abs().max(1.0),
                    "h[{m}][{k}]: {numeric} vs {}",
                    h[m][k]
                );
            }
        }
    }

    /// The analytic gradient and Hessian agree with finite differences of the energy.
    #[test]
    fn derivatives_match_finite_differences() {
        let (src, dst, _) = pairs_for_derivatives();
        let phi = [0.05, 0.02, -0.01];
        let two_s2 = 2.0 * 0.03f64.powi(2);
        assert_derivatives(
            phi,
            Lorentz::derivatives(&src, &dst, phi, two_s2),
            |p| Lorentz::energy(&src, &dst, p, two_s2),
            |p| Lorentz::derivatives(&src, &dst, p, two_s2).0,
        );
    }

    /// With point-to-line residuals for some pairs the derivatives agree with finite
    /// differences too; with none, both forms give the same figures to the last bit.
    #[test]
    fn point_to_line_derivatives_match_finite_differences() {
        let (src, dst, normals) = pairs_for_derivatives();
        let phi = [0.05, 0.02, -0.01];
        for sigma in [0.005, 0.03, 0.2] {
            let two_s2 = 2.0 * sigma * sigma;
            let pairs = (src.as_slice(), dst.as_slice());
            assert_derivatives(
                phi,
                Lorentz::derivatives_to_lines(pairs, &normals, phi, two_s2),
                |p| Lorentz::energy_to_lines(pairs, &normals, p, two_s2),
                |p| Lorentz::derivatives_to_lines(pairs, &normals, p, two_s2).0,
            );
            let none = vec![None; src.len()];
            assert_eq!(
                Lorentz::energy_to_lines(pairs, &none, phi, two_s2).to_bits(),
                Lorentz::energy(&src, &dst, phi, two_s2).to_bits()
            );
            assert_eq!(
                Lorentz::derivatives_to_lines(pairs, &none, phi, two_s2),
                Lorentz::derivatives(&src, &dst, phi, two_s2)
            );
        }
    }
}
