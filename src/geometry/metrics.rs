//! The quality metrics (docs/method/metrics.md): a method's visibility against the reference.
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
    // Exactly the counted pixels' errors: 8 bytes each, no more.
    let counted = reference
        .iter()
        .zip(method)
        .zip(mask)
        .filter(|(_, &on)| on)
        .count();
    let mut errors = Vec::with_capacity(counted);
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
    // The element a sort would put there, without the sort.
    let (_, &mut p99, _) = errors.select_nth_unstable_by(
        ((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1,
        f64::total_cmp,
    );
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

/// A hard shadow against the exact one (`reference-hard`): classes are binary, lit iff V ≥ ½
/// (so a filtered hard shadow such as PCF still has one), and every mismatched pixel is either an
/// *edge* pixel — the reference's class changes among its 8 neighbours that count: aliasing,
/// staircases, a boundary a pixel off — or an *interior* one: acne, light leaks, a missing or a
/// false shadow away from any true boundary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HardMetrics {
    /// Pixels compared.
    pub pixels: usize,
    pub mismatch_pct: f64,
    /// Mismatched pixels next to a change of the reference's class.
    pub edge_px: usize,
    /// The other mismatched pixels.
    pub interior_px: usize,
    /// Mismatched pixels the method darkens where the reference is lit.
    pub false_shadow_px: usize,
    /// Mismatched pixels the method lights where the reference is dark.
    pub missed_shadow_px: usize,
}

/// Compare a hard shadow `method` with the exact hard `reference` over the pixels where `mask`
/// is set, both `width`×`height` row-major. Non-finite values of the method count as the wrong
/// class.
pub fn compare_hard(
    reference: &[f32],
    method: &[f32],
    mask: &[bool],
    width: u32,
    height: u32,
) -> HardMetrics {
    let (w, h) = (width as usize, height as usize);
    let lit = |v: f32| v >= 0.5;
    let mut m = HardMetrics::default();
    if reference.len() < w * h || method.len() < w * h || mask.len() < w * h {
        return m;
    }
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if !mask[i] {
                continue;
            }
            m.pixels += 1;
            let r = lit(reference[i]);
            let v = method[i];
            let mine = if v.is_finite() { lit(v) } else { !r };
            if mine == r {
                continue;
            }
            if mine {
                m.missed_shadow_px += 1;
            } else {
                m.false_shadow_px += 1;
            }
            let mut edge = false;
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    edge |= mask[j] && lit(reference[j]) != r;
                }
            }
            if edge {
                m.edge_px += 1;
            } else {
                m.interior_px += 1;
            }
        }
    }
    let bad = m.edge_px + m.interior_px;
    m.mismatch_pct = if m.pixels > 0 {
        100.0 * bad as f64 / m.pixels as f64
    } else {
        0.0
    };
    m
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

    #[test]
    fn hard_metrics_by_hand() {
        // 4×3, reference lit on the left two columns, dark on the right two.
        let reference = [1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0];
        // The boundary a pixel off at (2, 0) and (1, 1); a light leak at (3, 2), whose
        // neighbours are all dark in the reference.
        let method = [1.0, 1.0, 1.0, 0.0, 1.0, 0.4, 0.0, 0.0, 1.0, 1.0, 0.0, 0.9];
        let mut mask = [true; 12];
        let m = compare_hard(&reference, &method, &mask, 4, 3);
        assert_eq!(m.pixels, 12);
        // (2, 0) lit where dark: next to (1, 0), lit: edge. (1, 1) 0.4 dark where lit: edge.
        // (3, 2) 0.9 lit where dark: its neighbours (2, 1), (3, 1), (2, 2) are all dark: interior.
        assert_eq!((m.edge_px, m.interior_px), (2, 1));
        assert_eq!((m.false_shadow_px, m.missed_shadow_px), (1, 2));
        assert!((m.mismatch_pct - 25.0).abs() < 1e-9);
        // Masked pixels do not count, and masked neighbours do not make an edge: without the
        // lit (1, 0) and (1, 1), the error at (2, 0) is interior.
        mask[1] = false;
        mask[5] = false;
        let m = compare_hard(&reference, &method, &mask, 4, 3);
        assert_eq!((m.pixels, m.edge_px, m.interior_px), (10, 0, 2));
        let nan = [f32::NAN; 12];
        assert_eq!(
            compare_hard(&reference, &nan, &[true; 12], 4, 3).mismatch_pct,
            100.0
        );
        assert_eq!(compare_hard(&[], &[], &[], 4, 3), HardMetrics::default());
    }
}
