//! The one random generator of quadray's CPU code: SplitMix64, small and deterministic, so every
//! run samples the same patterns (the ray tracer's pilot points and micro-benchmarks, the RSM
//! sampling baseline's Poisson disk, the tests' random cases).

/// SplitMix64 (Steele, Lea & Flood 2014), seeded by its state: `SplitMix(seed)`.
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1): the top 24 bits, so every value is an exact `f32`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix;

    /// The sequence is pinned: pictures, benchmark patterns and the RSM-sampling pattern are made
    /// from it. The first outputs for seed 0 are the reference implementation's.
    #[test]
    fn the_sequence_is_splitmix64() {
        let mut rng = SplitMix(0);
        assert_eq!(rng.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(rng.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        assert_eq!(rng.next_u64(), 0x06C4_5D18_8009_454F);
        let mut rng = SplitMix(0);
        assert_eq!(
            rng.next_f32(),
            (0xE220_A839_7B1D_CDAFu64 >> 40) as f32 / 16_777_216.0
        );
    }
}
