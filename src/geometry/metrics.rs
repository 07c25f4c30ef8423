//! The quality metrics of design.md §4: a method's visibility against the reference.
//!
//! Over pixels that hit a surface facing the light, each V falls in a class — lit `V ≥ 1 − ε`,
//! umbra `V ≤ ε`, penumbra otherwise, `ε = 0.004` — and the report gives the class mismatch (the
//! paper's "boundary correct" claim as a number), the mean absolute error of V, the same over the
//! reference's penumbra pixels, and the 99th percentile of |ΔV|.

/// ε of the class thresholds.
pub const CLASS_EPS: f64 = 0.004;

/// Lit, penumbra or umbra, by the thresholds above.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ShadowClass {
    Lit,
    Penumbra,
    Umbra,
}

impl ShadowClass {
    pub const ALL: [ShadowClass; 3] = [ShadowClass::Lit, ShadowClass::Penumbra, ShadowClass::Umbra];

    pub fn index(self) -> usize {
        self as usize
    }

    pub fn name(self) -> &'static str {
        match self {
            ShadowClass::Lit => "lit",
            ShadowClass::Penumbra => "penumbra",
            ShadowClass::Umbra => "umbra",
        }
    }

    pub fn of(v: f64) -> ShadowClass {
        if v >= 1.0 - CLASS_EPS {
            ShadowClass::Lit
        } else if v <= CLASS_EPS {
            ShadowClass::Umbra
        } else {
            ShadowClass::Penumbra
        }
    }
}

/// A method measured against the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Pixels compared (hit a surface facing the light).
    pub pixels: usize,
    pub penumbra_pixels: usize,
    /// Percentage of pixels whose class differs from the reference's.
    pub class_mismatch_pct: f64,
    pub mae: f64,
    /// MAE over the pixels the reference puts in the penumbra.
    pub penumbra_mae: f64,
    /// 99th percentile of |ΔV|.
    pub p99: f64,
    /// Pixel counts by `[reference class][method class]`, indexed by [`ShadowClass::index`].
    pub confusion: [[usize; 3]; 3],
}

/// Compare `method` to `reference` over the pixels where `mask` is set. Non-finite values count
/// as the worst case (|ΔV| = 1), so a NaN cannot hide an error.
pub fn compare(reference: &[f32], method: &[f32], mask: &[bool]) -> Metrics {
    let mut errors = Vec::new();
    let (mut mismatch, mut pen, mut pen_sum) = (0usize, 0usize, 0.0f64);
    let mut confusion = [[0usize; 3]; 3];
    for ((&r, &m), &on) in reference.iter().zip(method).zip(mask) {
        if !on {
            continue;
        }
        let (r, m) = (f64::from(r), f64::from(m));
        let err = if r.is_finite() && m.is_finite() {
            (r - m).abs()
        } else {
            1.0
        };
        let rc = ShadowClass::of(r);
        // A non-finite method value can be in no class but the wrong one.
        let mc = if m.is_finite() {
            ShadowClass::of(m)
        } else if rc == ShadowClass::Lit {
            ShadowClass::Umbra
        } else {
            ShadowClass::Lit
        };
        confusion[rc.index()][mc.index()] += 1;
        mismatch += usize::from(rc != mc);
        if rc == ShadowClass::Penumbra {
            pen += 1;
            pen_sum += err;
        }
        errors.push(err);
    }
    let n = errors.len();
    if n == 0 {
        return Metrics::default();
    }
    let mae = errors.iter().sum::<f64>() / n as f64;
    errors.sort_unstable_by(f64::total_cmp);
    let p99 = errors[((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1];
    Metrics {
        pixels: n,
        penumbra_pixels: pen,
        class_mismatch_pct: 100.0 * mismatch as f64 / n as f64,
        mae,
        penumbra_mae: if pen > 0 { pen_sum / pen as f64 } else { 0.0 },
        p99,
        confusion,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_use_the_epsilon() {
        assert_eq!(ShadowClass::of(1.0), ShadowClass::Lit);
        assert_eq!(ShadowClass::of(0.997), ShadowClass::Lit);
        assert_eq!(ShadowClass::of(0.99), ShadowClass::Penumbra);
        assert_eq!(ShadowClass::of(0.004), ShadowClass::Umbra);
        assert_eq!(ShadowClass::of(0.01), ShadowClass::Penumbra);
    }

    #[test]
    fn metrics_by_hand() {
        let reference = [0.0, 0.5, 1.0, 0.25, 0.9];
        let method = [0.0, 0.7, 0.5, 0.25, f32::NAN];
        let mask = [true, true, true, true, false];
        let m = compare(&reference, &method, &mask);
        assert_eq!(m.pixels, 4);
        assert_eq!(m.penumbra_pixels, 2);
        assert!((m.class_mismatch_pct - 25.0).abs() < 1e-9);
        assert!((m.mae - 0.7 / 4.0).abs() < 1e-6);
        assert!((m.penumbra_mae - 0.1).abs() < 1e-6);
        assert!((m.p99 - 0.5).abs() < 1e-6);
        // Reference umbra/penumbra/lit/penumbra; method umbra/penumbra/penumbra/penumbra.
        assert_eq!(m.confusion, [[0, 1, 0], [0, 2, 0], [0, 0, 1]]);
        // A NaN that is compared counts as a full error and a mismatch.
        let m = compare(&reference, &method, &[false, false, false, false, true]);
        assert_eq!((m.mae, m.class_mismatch_pct), (1.0, 100.0));
        assert_eq!(compare(&[], &[], &[]), Metrics::default());
    }
}
