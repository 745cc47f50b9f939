//! Hot loops compiled more than once: for the baseline x86-64 processor, for one with AVX2,
//! which does four `f64` operations at a time where the baseline does two, and for one with
//! AVX-512, eight at a time with twice the registers. The widest build is picked at run time
//! from what the processor reports ([`avx2`], [`avx512`]); each wider build is a
//! `#[target_feature(enable = ...)]` function that the loop's code is inlined into
//! (`#[inline(always)]`), beside the baseline one.
//!
//! All builds give the same bits: wider registers, not other arithmetic — each addition,
//! product, quotient and square root is still rounded as IEEE 754 says, and Rust never fuses a
//! product and a sum into one rounding (it asks LLVM for no contraction, even where the
//! processor has FMA, which AVX-512 implies). So a scan is the same whichever build cast it.

/// Whether the processor runs AVX2 instructions (the answer is cached by the standard library).
#[inline]
pub fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether the processor runs the AVX-512 instructions the wide builds use: the foundation
/// and its vector-length, double- and quad-word, and byte and word extensions.
#[inline]
pub fn avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512vl")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512bw")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
