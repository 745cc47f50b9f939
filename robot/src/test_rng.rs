//! A small generator for the unit tests' own data: the robot crate draws no random numbers, so
//! its tests do not pull in a generator crate for the few scenes they scatter.

/// Marsaglia's xorshift (13, 7, 17) over 64 bits: the same sequence from the same seed on
/// every machine.
pub(crate) struct XorShift(pub(crate) u64);

impl XorShift {
    /// The next 64 bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}
