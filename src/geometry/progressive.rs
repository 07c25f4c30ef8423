//! The ray-cast reference over an image, progressively: every pixel's point gets a few more of the
//! oracle's `K` disk samples per step, so a lab can show a converging ground truth and say how
//! many samples it holds. After all `K` the result is exactly [`Oracle::visibility`].
//!
//! The samples are taken in a fixed order that visits the oracle's stratified set with a
//! golden-ratio stride, so every prefix is spread over the whole disk (a prefix of the strata in
//! their own order would only cover a band of it).

use glam::Vec3;
use rayon::prelude::*;

use super::oracle::Oracle;

/// A reference image being accumulated.
#[derive(Debug)]
pub struct ProgressiveReference {
    oracle: Oracle,
    /// The oracle's samples, in the order they are taken.
    order: Vec<Vec3>,
    /// One point per pixel; `None` where no surface was hit (V = 0 there).
    points: Vec<Option<Vec3>>,
    /// Visible samples so far, per pixel.
    visible: Vec<u32>,
    /// `visible / done`, kept up to date by [`ProgressiveReference::step`].
    values: Vec<f32>,
    done: usize,
}

impl ProgressiveReference {
    /// A reference for `points` with every sample of `oracle` still to take.
    pub fn new(oracle: Oracle, points: Vec<Option<Vec3>>) -> ProgressiveReference {
        let order = progressive_order(oracle.sample_points());
        ProgressiveReference {
            visible: vec![0; points.len()],
            values: vec![0.0; points.len()],
            oracle,
            order,
            points,
            done: 0,
        }
    }

    /// Take up to `n` more samples per pixel (on every core); returns how many were taken.
    pub fn step(&mut self, n: usize) -> usize {
        let end = (self.done + n).min(self.order.len());
        let slice = &self.order[self.done..end];
        if slice.is_empty() {
            return 0;
        }
        let oracle = &self.oracle;
        self.visible
            .par_iter_mut()
            .zip(self.points.par_iter())
            .with_min_len(64)
            .for_each(|(v, p)| {
                if let Some(x) = p {
                    *v += oracle.count_visible(*x, slice);
                }
            });
        let taken = end - self.done;
        self.done = end;
        let n = self.done as f32;
        self.values = self.visible.iter().map(|&v| v as f32 / n).collect();
        taken
    }

    /// Take every remaining sample.
    pub fn finish(&mut self) {
        self.step(self.order.len());
    }

    /// Samples per pixel taken so far.
    pub fn samples_done(&self) -> usize {
        self.done
    }

    /// Samples per pixel when complete (the oracle's K).
    pub fn samples_total(&self) -> usize {
        self.order.len()
    }

    pub fn is_complete(&self) -> bool {
        self.done >= self.order.len()
    }

    /// V per pixel from the samples taken so far (0 before the first step and where no surface
    /// was hit).
    pub fn visibility(&self) -> &[f32] {
        &self.values
    }

    /// Shadow rays cast so far.
    pub fn rays_cast(&self) -> u64 {
        self.oracle.rays_cast()
    }

    pub fn oracle(&self) -> &Oracle {
        &self.oracle
    }

    /// The point under each pixel (`None` where no surface was hit).
    pub fn points(&self) -> &[Option<Vec3>] {
        &self.points
    }
}

/// `samples` in the order the progressive reference takes them (a golden-ratio stride over the
/// strata, see the module documentation): the GPU's reference takes them in the same order, so
/// its every prefix holds the same samples as the CPU's.
pub fn progressive_order(samples: &[Vec3]) -> Vec<Vec3> {
    let k = samples.len();
    (0..k).map(|i| samples[spread(i, k)]).collect()
}

/// The `i`-th index of a permutation of `0..k` by a stride near `k / φ` that is coprime to `k`.
fn spread(i: usize, k: usize) -> usize {
    if k <= 2 {
        return i;
    }
    let mut stride = ((k as f64) * 0.618_033_988_75).round() as usize;
    while gcd(stride, k) != 1 {
        stride += 1;
    }
    (i * stride) % k
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::AreaLight;

    fn oracle(k: usize) -> Oracle {
        // A unit square half covering the disk's view of the origin.
        let light = AreaLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: 1.0,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        };
        let a = Vec3::new(0.0, 2.0, -5.0);
        let b = Vec3::new(5.0, 2.0, -5.0);
        let c = Vec3::new(5.0, 2.0, 5.0);
        let d = Vec3::new(0.0, 2.0, 5.0);
        Oracle::new(vec![[a, b, c], [a, c, d]], light, k)
    }

    #[test]
    fn the_stride_is_a_permutation() {
        for k in [1, 2, 3, 16, 100, 1024, 1000] {
            let mut seen: Vec<usize> = (0..k).map(|i| spread(i, k)).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..k).collect::<Vec<_>>(), "k = {k}");
        }
    }

    #[test]
    fn complete_equals_the_oracle_and_prefixes_are_unbiased() {
        let o = oracle(1024);
        let points: Vec<Option<Vec3>> = (0..9)
            .map(|i| Some(Vec3::new(-1.0 + 0.25 * i as f32, 0.0, 0.3)))
            .chain([None])
            .collect();
        let exact: Vec<f32> = points
            .iter()
            .map(|p| p.map_or(0.0, |x| o.visibility(x)))
            .collect();
        let mut r = ProgressiveReference::new(o, points);
        assert_eq!(r.visibility(), &[0.0; 10][..]);
        assert_eq!(r.step(64), 64);
        // With 64 of 1024 samples spread over the disk, V is already close everywhere (a prefix
        // in strata order would see only a band of the disk and be off by up to 0.5 here).
        for (a, b) in r.visibility().iter().zip(&exact) {
            assert!((a - b).abs() < 0.1, "{a} vs {b}");
        }
        r.finish();
        assert!(r.is_complete());
        assert_eq!(r.samples_done(), 1024);
        assert_eq!(r.step(8), 0);
        assert_eq!(r.visibility(), &exact[..]);
        assert!(exact[0] > 0.99 && exact[8] < 0.01, "{exact:?}");
    }
}
