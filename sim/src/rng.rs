//! Seeded random streams: one per sensor or noise source, derived from the scenario's seed and
//! the stream's name, so adding a sensor never changes what another one draws.
//!
//! A sensor whose readings may be skipped (the laser's scans are measured only when the host
//! reads them) draws each reading from a numbered substream of its stream, so a reading's noise
//! depends on the seed and its number only, never on which other readings were taken.

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// The random generator used everywhere in the twin (portable and reproducible).
pub type SimRng = Xoshiro256PlusPlus;

/// The seed of the stream called `name` under the scenario seed `seed`.
pub fn stream_seed(seed: u64, name: &str) -> u64 {
    // FNV-1a of the name, mixed with the seed.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in name.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    mix(seed ^ h.rotate_left(17))
}

/// The stream called `name` of the scenario seeded with `seed`.
///
/// ```
/// use rand::RngExt;
/// let mut a = sim::rng::stream(7, "laser");
/// let mut b = sim::rng::stream(7, "laser");
/// let mut c = sim::rng::stream(7, "slip/left");
/// let (x, y, z): (u64, u64, u64) = (a.random(), b.random(), c.random());
/// assert_eq!(x, y);
/// assert_ne!(x, z);
/// ```
pub fn stream(seed: u64, name: &str) -> SimRng {
    SimRng::seed_from_u64(stream_seed(seed, name))
}

/// Reading number `index` of the stream seeded `stream_seed`.
pub fn substream(stream_seed: u64, index: u64) -> SimRng {
    SimRng::seed_from_u64(mix(
        stream_seed ^ mix(index.wrapping_add(0x9e37_79b9_7f4a_7c15))
    ))
}

/// SplitMix64's finaliser: a bijective scramble of 64 bits.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    #[test]
    fn substreams_differ_and_repeat() {
        let s = stream_seed(42, "laser");
        let a: u64 = substream(s, 0).random();
        let b: u64 = substream(s, 1).random();
        let a2: u64 = substream(s, 0).random();
        assert_ne!(a, b);
        assert_eq!(a, a2);
    }
}
