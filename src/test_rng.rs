//! A seeded xorshift64 for tests that sweep many inputs: the same numbers on every run and
//! machine, without a crate for five lines.

/// Uniform numbers in [0, 1) from `seed` (xorshift64; 53 bits of each draw).
pub fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}
