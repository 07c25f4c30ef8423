//! A small deterministic generator (SplitMix64) for the tests' generated scenes: the same seed
//! gives the same scene on every machine.

pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [0, 1).
    pub fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f32) as usize).min(n.saturating_sub(1))
    }
}

impl Rng {
    /// A size `s` stretched at random: 60–140 % across, 50–120 % in height.
    pub fn stretched(&mut self, s: f32) -> glam::Vec3 {
        glam::Vec3::new(
            s * self.range(0.6, 1.4),
            s * self.range(0.5, 1.2),
            s * self.range(0.6, 1.4),
        )
    }

    /// A turn by XYZ Euler angles each in `[0, max)` radians.
    pub fn rotation(&mut self, max: [f32; 3]) -> glam::Quat {
        let [x, y, z] = max.map(|m| self.range(0.0, m));
        glam::Quat::from_euler(glam::EulerRot::XYZ, x, y, z)
    }
}
