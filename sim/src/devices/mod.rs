//! What the twin simulates of the robot, one model per device: the drive motors and encoders
//! ([`motor`]), the batteries ([`battery`]), the two microcontrollers' ported firmware and their
//! serial timing ([`firmware`]), the SICK laser and its optics ([`laser`]), the sonar ring
//! ([`sonar`]) and the pan-tilt head that carries the laser ([`pan_tilt`]).

pub mod battery;
pub mod firmware;
pub mod laser;
pub mod motor;
pub mod pan_tilt;
pub mod sonar;

/// `x.floor()` without a call: the baseline x86-64 target has no rounding instruction, so
/// `f64::floor` is a library call, and a motor's encoder takes two every firmware tick. The same
/// value for every `x` (up to the sign of a zero), through `i64` where `x` fits in one.
#[inline]
pub(crate) fn floor(x: f64) -> f64 {
    if x.abs() < 9.0e15 {
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t }
    } else {
        x.floor()
    }
}

/// `x.round()` (half away from zero) without a call, as [`floor`]: the battery's ADC rounds four
/// readings every firmware tick. The same value for every `x` (up to the sign of a zero).
#[inline]
pub(crate) fn round(x: f64) -> f64 {
    if x.abs() < 9.0e15 {
        let t = x as i64 as f64;
        let rest = x - t;
        if rest >= 0.5 {
            t + 1.0
        } else if rest <= -0.5 {
            t - 1.0
        } else {
            t
        }
    } else {
        x.round()
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};

    #[test]
    fn floor_and_round_without_a_call_are_the_library_s() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(4);
        let mut values = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            4503599627370497.0,
            8.9e15,
            -8.9e15,
            9.1e15,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
        ];
        for _ in 0..200_000 {
            let scale = 10f64.powi(rng.random_range(-6..17));
            values.push(rng.random_range(-1.0..1.0) * scale);
            let k = rng.random_range(-1_000_000i64..1_000_000) as f64;
            values.extend([
                k,
                k + 0.5,
                k - 0.5,
                k + 0.5f64.next_down(),
                k + 0.5f64.next_up(),
            ]);
        }
        for x in values {
            assert_eq!(super::floor(x), x.floor(), "floor({x:e})");
            assert_eq!(super::round(x), x.round(), "round({x:e})");
        }
        assert!(super::floor(f64::NAN).is_nan() && super::round(f64::NAN).is_nan());
    }
}
