//! Numbers that check their own range while a data file is read, so that a bad value is
//! reported at its line and column by the TOML reader.

use serde::de::{Deserialize, Deserializer, Error};

macro_rules! checked_number {
    ($(#[$doc:meta])* $name:ident, $expected:literal, |$v:ident| $ok:expr) => {
        $(#[$doc])*
        #[derive(Copy, Clone, Debug, PartialEq, PartialOrd)]
        pub struct $name(pub f64);

        impl $name {
            /// The number.
            pub fn get(self) -> f64 {
                self.0
            }
        }

        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let $v = f64::deserialize(d)?;
                if $ok {
                    Ok($name($v))
                } else {
                    Err(D::Error::custom(format!(concat!("expected ", $expected, ", found {}"), show($v))))
                }
            }
        }
    };
}

/// A number as a person would write it in an error: `1e308`, not 309 digits.
pub fn show(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// The largest magnitude any physical number of a data file may have. Every quantity of a robot,
/// a world or a scenario (metres, kilograms, rpm, amperes, seconds…) is far below it; a number
/// above it is a typing slip, and would overflow single precision or a duration downstream.
pub const MAX_MAGNITUDE: f64 = 1e6;
/// The smallest non-zero magnitude (below it, subnormal and absurd numbers).
pub const MIN_MAGNITUDE: f64 = 1e-12;

/// Whether `v` is zero or a plausible magnitude.
fn plausible(v: f64) -> bool {
    v == 0.0 || (MIN_MAGNITUDE..=MAX_MAGNITUDE).contains(&v.abs())
}

checked_number!(
    /// A number greater than zero, from 1e-12 to 1e6.
    Positive, "a positive number from 1e-12 to 1e6", |v| v > 0.0 && plausible(v)
);
checked_number!(
    /// Zero, or a number from 1e-12 to 1e6.
    NonNegative, "0 or a number from 1e-12 to 1e6", |v| v >= 0.0 && plausible(v)
);
checked_number!(
    /// Zero, or a magnitude from 1e-12 to 1e6, either sign.
    Finite, "0 or a number of magnitude 1e-12 to 1e6", |v| plausible(v)
);
checked_number!(
    /// A duration in seconds, above zero and at most an hour.
    Seconds, "a duration in seconds from 1e-6 to 3600", |v| (1e-6..=3600.0).contains(&v)
);
checked_number!(
    /// A duration in seconds, zero or at most an hour.
    SecondsOrZero, "0 or a duration in seconds up to 3600", |v| v == 0.0 || (1e-6..=3600.0).contains(&v)
);
checked_number!(
    /// A standard deviation or noise scale, 0..=1 (metres, or √metres for slip).
    Sigma, "a standard deviation in 0..=1", |v| v == 0.0 || (MIN_MAGNITUDE..=1.0).contains(&v)
);
checked_number!(
    /// A number in 0..=1.
    UnitInterval, "a number in 0..=1", |v| (0.0..=1.0).contains(&v)
);
checked_number!(
    /// A relative error in −0.5..=0.5 (a systematic mismatch such as 0.01 for 1 %).
    RelativeError, "a relative error in -0.5..=0.5", |v| (-0.5..=0.5).contains(&v)
);
checked_number!(
    /// An incidence angle in degrees, 0..=90.
    Angle, "an angle in 0..=90 degrees", |v| (0.0..=90.0).contains(&v)
);
