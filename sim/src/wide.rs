//! Hot loops compiled twice: for the baseline x86-64 processor and for one with AVX2, which
//! does four `f64` operations at a time where the baseline does two. The faster build is
//! picked at run time from what the processor reports ([`avx2`]); the AVX2 build is a
//! `#[target_feature(enable = "avx2")]` function that the loop's code is inlined into
//! (`#[inline(always)]`), beside the baseline one.
//!
//! Both builds give the same bits: AVX2 adds wider registers, not other arithmetic — each
//! addition, product, quotient and square root is still rounded as IEEE 754 says, and Rust
//! never fuses a product and a sum into one rounding (FMA is a separate feature, not enabled
//! here). So a scan is the same whichever build cast it.

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
