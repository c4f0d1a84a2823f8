//! The random number generator of the calls that need an unbounded count of random numbers.


/// O'Neill's PCG32 generator (PCG-XSH-RR: 64-bit LCG state, 32-bit output, selectable stream).
///
/// Deterministic and reproducible across platforms. The library never seeds one itself: the
/// calls that need an unbounded count of random numbers (tracking, GPIS realizations) take a
/// 64-bit seed from their caller, so the same seed gives the same result. Seeding follows
/// the reference `pcg32_srandom_r(rng, seed, stream)`, so `Pcg32::new(42, 54)` reproduces the
/// reference demo sequence `0xa15c02b7, 0x7b47f409, 0xba1d3330, …`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MULTIPLIER: u64 = 6_364_136_223_846_793_005;

    /// A generator seeded like the reference `pcg32_srandom_r(rng, seed, stream)`. Different
    /// `stream` values give statistically independent sequences (only the low 63 bits of
    /// `stream` matter).
    #[must_use]
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg32 { state: 0, inc: (stream << 1) | 1 };
        rng.step();
        rng.state = rng.state.wrapping_add(seed);
        rng.step();
        rng
    }

    #[inline]
    fn step(&mut self) {
        self.state = self.state.wrapping_mul(Self::MULTIPLIER).wrapping_add(self.inc);
    }

    /// The next 32 uniformly distributed bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.step();
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform `f64` in `[0, 1)` with 53 random bits (consumes two 32-bit outputs: the
    /// first gives the high bits).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = u64::from(self.next_u32());
        let lo = u64::from(self.next_u32());
        (((hi << 32) | lo) >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0) // 2^-53
    }

    /// A uniform `f64` in the open interval `(0, 1)`: the midpoints `(k + ½)·2⁻⁵²`,
    /// `k ∈ [0, 2⁵²)` (consumes two 32-bit outputs). Never returns 0 or 1, so `ln u` and
    /// `ln(1 − u)` are always finite.
    #[inline]
    pub fn next_f64_open(&mut self) -> f64 {
        let hi = u64::from(self.next_u32());
        let lo = u64::from(self.next_u32());
        let k = ((hi << 32) | lo) >> 12;
        (k as f64 + 0.5) * (1.0 / 4_503_599_627_370_496.0) // 2^-52
    }
}
