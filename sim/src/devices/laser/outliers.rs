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
use rand::RngExt;

impl Outliers {
    /// The probabilities summed once, for many readings.
    pub fn cuts(&self) -> OutlierCuts {
        OutlierCuts {
            any: self.any(),
            uniform: self.uniform,
            short: self.uniform + self.short,
            dropout: self.uniform + self.short + self.dropout,
        }
    }
}

/// [`Outliers`] as the cumulative probabilities one uniform draw is compared with: below
/// `uniform` a uniform reading, then a short one, then a dropout.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct OutlierCuts {
    any: bool,
    uniform: f64,
    short: f64,
    dropout: f64,
}

impl OutlierCuts {
    /// Replaces `echo` by an outlier with the configured probabilities; `None` keeps it. No
    /// draw when there are no outliers.
    #[inline(always)]
    pub fn draw(&self, echo: Echo, range_max: f64, rng: &mut SimRng) -> Option<Echo> {
        if !self.any {
            return None;
        }
        let u: f64 = rng.random();
        if u < self.uniform {
            Some(Echo::Range(rng.random::<f64>() * range_max))
        } else if u < self.short {
            let top = match echo {
                Echo::Range(r) => r,
                Echo::Lost => range_max,
            };
            Some(Echo::Range(rng.random::<f64>() * top))
        } else if u < self.dropout {
            Some(Echo::Lost)
        } else {
            None
        }
    }
}
