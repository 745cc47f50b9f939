//! Random outliers as a scenario or study asks for them: per-beam probabilities of a reading that
//! has nothing to do with the surface the beam met (thesis §5.2, Table 5.1). The laser model
//! draws them ([`crate::devices::laser::outliers`]).

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
}
