//! Random outliers: readings that have nothing to do with the surface the beam met.
//!
//! Real scans carry them (the thesis's lab, §5.2: "a great number of outliers that follow no
//! particular distribution"); its simulated study added **uniformly distributed outliers at 2 %
//! and 20 %** of the readings (Table 5.1). Each beam independently becomes, with the given
//! probabilities, a reading drawn uniformly over the whole range, a short reading (uniform between
//! zero and the true range, as from dust or a passing leg), or a dropout (the maximum, as if
//! nothing came back).

use super::beam::Echo;
use crate::rng::SimRng;
use rand::RngExt;

/// Per-beam outlier probabilities.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Outliers {
    /// A reading uniform over `[0, range_max)`.
    pub uniform: f64,
    /// A reading uniform over `[0, true range)`.
    pub short: f64,
    /// No return.
    pub dropout: f64,
}

impl Outliers {
    /// No outliers.
    pub const NONE: Outliers = Outliers {
        uniform: 0.0,
        short: 0.0,
        dropout: 0.0,
    };

    /// The named presets: `none`, `thesis-2pct`, `thesis-20pct` (the thesis's uniform outliers)
    /// and `indoor` (a little of each, for a busy room).
    pub const PRESETS: [(&'static str, Outliers); 4] = [
        ("none", Outliers::NONE),
        (
            "thesis-2pct",
            Outliers {
                uniform: 0.02,
                short: 0.0,
                dropout: 0.0,
            },
        ),
        (
            "thesis-20pct",
            Outliers {
                uniform: 0.20,
                short: 0.0,
                dropout: 0.0,
            },
        ),
        (
            "indoor",
            Outliers {
                uniform: 0.005,
                short: 0.01,
                dropout: 0.01,
            },
        ),
    ];

    /// The preset called `name`.
    pub fn preset(name: &str) -> Option<Outliers> {
        Self::PRESETS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, o)| *o)
    }

    /// Whether any outlier can happen.
    pub fn any(&self) -> bool {
        self.uniform + self.short + self.dropout > 0.0
    }

    /// Replaces `echo` by an outlier with the configured probabilities; `None` keeps it.
    pub fn draw(&self, echo: Echo, range_max: f64, rng: &mut SimRng) -> Option<Echo> {
        if !self.any() {
            return None;
        }
        let u: f64 = rng.random();
        if u < self.uniform {
            Some(Echo::Range(rng.random::<f64>() * range_max))
        } else if u < self.uniform + self.short {
            let top = match echo {
                Echo::Range(r) => r,
                Echo::Lost => range_max,
            };
            Some(Echo::Range(rng.random::<f64>() * top))
        } else if u < self.uniform + self.short + self.dropout {
            Some(Echo::Lost)
        } else {
            None
        }
    }
}
