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
                    Err(D::Error::custom(format!(concat!("expected ", $expected, ", found {}"), $v)))
                }
            }
        }
    };
}

checked_number!(
    /// A finite number greater than zero.
    Positive, "a positive number", |v| v.is_finite() && v > 0.0
);
checked_number!(
    /// A finite number, zero or more.
    NonNegative, "a number >= 0", |v| v.is_finite() && v >= 0.0
);
checked_number!(
    /// Any finite number.
    Finite, "a finite number", |v| v.is_finite()
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
