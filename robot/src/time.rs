//! Time on the robot's clock, as integer nanoseconds.
//!
//! Robot code never asks the operating system for the time: every reading carries the [`Stamp`] at
//! which it was measured, and controllers reason with those. The twin's clock starts at zero when
//! the world is created; a real backend's clock starts when the backend is opened.

use core::fmt;
use core::ops::{Add, AddAssign};
use core::time::Duration;
use serde::{Deserialize, Serialize};

/// A moment on the robot's clock: nanoseconds since the clock's origin.
///
/// ```
/// use robot::Stamp;
/// use std::time::Duration;
/// let t = Stamp::from_millis(1500) + Duration::from_millis(250);
/// assert_eq!(t.nanos(), 1_750_000_000);
/// assert_eq!(t.to_string(), "1.750000000");
/// ```
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
pub struct Stamp(pub u64);

impl Stamp {
    /// The clock's origin.
    pub const ZERO: Stamp = Stamp(0);

    /// A stamp from nanoseconds.
    pub const fn from_nanos(nanos: u64) -> Self {
        Stamp(nanos)
    }

    /// A stamp from milliseconds.
    pub const fn from_millis(millis: u64) -> Self {
        Stamp(millis * 1_000_000)
    }

    /// A stamp from seconds, rounded to the nearest nanosecond; negative or non-finite input
    /// gives [`Stamp::ZERO`].
    pub fn from_secs_f64(secs: f64) -> Self {
        if secs.is_finite() && secs > 0.0 {
            Stamp((secs * 1e9).round() as u64)
        } else {
            Stamp::ZERO
        }
    }

    /// Nanoseconds since the origin.
    pub const fn nanos(self) -> u64 {
        self.0
    }

    /// Seconds since the origin (for output and arithmetic in SI units).
    pub fn secs_f64(self) -> f64 {
        self.0 as f64 * 1e-9
    }

    /// The time from `earlier` to `self`, or zero if `earlier` is later.
    pub fn saturating_since(self, earlier: Stamp) -> Duration {
        Duration::from_nanos(self.0.saturating_sub(earlier.0))
    }
}

impl Add<Duration> for Stamp {
    type Output = Stamp;
    fn add(self, rhs: Duration) -> Stamp {
        Stamp(
            self.0
                .saturating_add(rhs.as_nanos().min(u64::MAX as u128) as u64),
        )
    }
}

impl AddAssign<Duration> for Stamp {
    fn add_assign(&mut self, rhs: Duration) {
        *self = *self + rhs;
    }
}

/// Seconds with all nine decimals: exact, so two equal stamps always print the same.
impl fmt::Display for Stamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}.{:09}",
            self.0 / 1_000_000_000,
            self.0 % 1_000_000_000
        )
    }
}

/// Where a backend that talks to real devices gets the time: the caller passes one in.
///
/// Robot code never asks the operating system for the time; a serial backend needs a clock to
/// stamp what arrives, so the program that opens it chooses one (a monotonic wall clock on the
/// robot, a scaled one when the twin runs faster than real time, a manual one in tests). It is
/// shared with the backend's reader threads, hence `Send + Sync`.
pub trait Clock: Send + Sync {
    /// The time now, on the robot's clock.
    fn now(&self) -> Stamp;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_is_exact_seconds() {
        assert_eq!(Stamp(1_024_000).to_string(), "0.001024000");
        assert_eq!(Stamp(12_000_000_001).to_string(), "12.000000001");
    }

    #[test]
    fn from_secs_rounds_and_clamps() {
        assert_eq!(Stamp::from_secs_f64(0.5), Stamp::from_millis(500));
        assert_eq!(Stamp::from_secs_f64(-3.0), Stamp::ZERO);
        assert_eq!(Stamp::from_secs_f64(f64::NAN), Stamp::ZERO);
    }

    #[test]
    fn since_saturates() {
        let a = Stamp::from_millis(10);
        let b = Stamp::from_millis(4);
        assert_eq!(a.saturating_since(b), Duration::from_millis(6));
        assert_eq!(b.saturating_since(a), Duration::ZERO);
    }
}
