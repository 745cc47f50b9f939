//! Random outliers: readings that have nothing to do with the surface the beam met.
//!
//! Real scans carry them (the thesis's lab, §5.2: "a great number of outliers that follow no
//! particular distribution"); its simulated study added **uniformly distributed outliers at 2 %
//! and 20 %** of the readings (Table 5.1). Each beam independently becomes, with the given
//! probabilities, a reading drawn uniformly over the whole range, a short reading (uniform between
//! zero and the true range, as from dust or a passing leg), or a dropout (the maximum, as if
//! nothing came back).

use super::beam::Echo;
use crate::config::Outliers;
use crate::rng::SimRng;
use rand::{Rng, RngExt};

impl Outliers {
    /// The probabilities summed once, for many readings.
    pub fn cuts(&self) -> OutlierCuts {
        let (uniform, short) = (self.uniform, self.uniform + self.short);
        let dropout = short + self.dropout;
        OutlierCuts {
            any: self.any(),
            uniform: below(uniform),
            short: below(short),
            dropout: below(dropout),
        }
    }
}

/// The uniform draw `k / 2^53` (the standard one, `k` the top 53 bits of a 64-bit draw) is
/// below `p` exactly when `k` is below `⌈p · 2^53⌉`: both sides scaled by a power of two
/// exactly, and a whole number is below `x` exactly when it is below `⌈x⌉`.
fn below(p: f64) -> u64 {
    // A saturating conversion: 2^64 and above (p > 2048) to u64::MAX, negative to zero.
    (p * (1u64 << 53) as f64).ceil() as u64
}

/// [`Outliers`] as the cumulative probabilities one uniform draw is compared with: below
/// `uniform` a uniform reading, then a short one, then a dropout. Each is kept as the
/// whole number the draw's 53 bits are compared with (`below`), so a reading that is no
/// outlier costs one comparison of integers.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct OutlierCuts {
    any: bool,
    uniform: u64,
    short: u64,
    dropout: u64,
}

impl OutlierCuts {
    /// Replaces `echo` by an outlier with the configured probabilities; `None` keeps it. No
    /// draw when there are no outliers.
    #[inline(always)]
    pub fn draw(&self, echo: Echo, range_max: f64, rng: &mut SimRng) -> Option<Echo> {
        if !self.any {
            return None;
        }
        // The bits `rng.random::<f64>()` would turn into `k / 2^53`.
        let k = rng.next_u64() >> 11;
        if k >= self.dropout {
            None
        } else if k < self.uniform {
            Some(Echo::Range(rng.random::<f64>() * range_max))
        } else if k < self.short {
            let top = match echo {
                Echo::Range(r) => r,
                Echo::Lost => range_max,
            };
            Some(Echo::Range(rng.random::<f64>() * top))
        } else {
            Some(Echo::Lost)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_number_cuts_split_draws_as_the_uniform_draw_does() {
        let scale = (1u64 << 53) as f64;
        let probabilities = [0.0, 0.02, 0.2, 0.1 + 0.2, 1.0 / 3.0, 0.5, 1.0, 1.5, 1e-300];
        let mut rng = crate::rng::stream(9, "cuts");
        for p in probabilities {
            let cut = below(p);
            // Draws right at and around the cut, and random ones.
            let near = (-3i64..=3).map(|d| cut.saturating_add_signed(d).min((1 << 53) - 1));
            let random = (0..2000).map(|_| rng.next_u64() >> 11);
            for k in near.chain(random) {
                let u = k as f64 / scale;
                assert_eq!(k < cut, u < p, "draw {k} against {p}");
            }
        }
    }
}
