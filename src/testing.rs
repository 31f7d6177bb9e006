//! Helpers shared by the library's unit tests.

/// A reproducible value in [−1, 1) from `seed`, which it advances (a 64-bit linear
/// congruential generator: the same sequence on every machine, with no crate to pin).
pub(crate) fn uniform(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}
