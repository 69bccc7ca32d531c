//! The deterministic generator of the kernel's tests and benches (xorshift64, Marsaglia 2003):
//! the same seed gives the same stream on every target, so benches and tests are repeatable.

/// xorshift64 state; seed it with a nonzero value (zero stays zero).
#[derive(Clone, Debug)]
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform in `0..n` (`0` for `n = 0`), by remainder.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }

    /// Uniform in `[0, 1)` on a 2^-24 grid (exact in f32).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}
