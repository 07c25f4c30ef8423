//! Moment shadow mapping's arithmetic (Peters & Klein, I3D 2015), the CPU twin of
//! `shaders/shared/msm.wgsl`: four power moments of a depth `z ∈ [0, 1]`, their optimized
//! quantization (the paper's 4×4 transform into `[0, 1]⁴`, so 16 bits a moment lose little), the
//! summed-area table's fixed point, and Hamburger 4MSM: from a filter region's mean moments `b`
//! and a receiver depth `z_f`, the three-point distribution with a point at `z_f` that has those
//! moments — the share of its weight strictly in front of `z_f` is the shadow intensity, and the
//! weighted mean of those points the region's mean blocker depth (moment soft shadow mapping,
//! Peters et al., I3D 2016).
//!
//! For a region that holds at most two depths the four moments determine the distribution and
//! both answers are exact but for the moment bias (within 0.02 in the tests); with more depths they are bounds, and light leaks.

use glam::{Mat4, Vec4};

/// The largest filter radius the summed-area table serves, in texels: a box of at most
/// `(2R + 1)²` texels.
pub const MAX_RADIUS: u32 = 128;

/// One moment's fixed-point scale in the summed-area table: the table's `u32` sums wrap, and a
/// box's sum is exact modulo 2³² as long as the true sum fits, so a texel may hold up to
/// `2³² / (2·MAX_RADIUS + 1)²` — about 16 bits (JCGT 2017's integer tables do the same).
pub const SAT_SCALE: f32 = (u32::MAX / ((2 * MAX_RADIUS + 1) * (2 * MAX_RADIUS + 1))) as f32;

/// The optimized quantization's offset on the first moment (Peters & Klein 2015).
pub const QUANTIZATION_OFFSET: f32 = 0.035_955_884;

/// The optimized quantization (Peters & Klein 2015, its supplementary listing), columns as the
/// listing's rows: `optimized = ENCODE · (z, z², z³, z⁴) + (offset, 0, 0, 0)`.
pub const ENCODE: [[f32; 4]; 4] = [
    [-2.072_246_5, 13.794_886, 0.105_877_704, 9.792_406],
    [32.237_038, -59.468_4, -1.907_746_6, -33.765_21],
    [-68.571_075, 82.035_97, 9.349_655, 47.945_61],
    [39.370_327, -35.364_903, -6.654_349, -23.972_805],
];

/// Its inverse, the same way round.
pub const DECODE: [[f32; 4]; 4] = [
    [0.222_774_41, 0.154_967_93, 0.145_198_9, 0.163_127_44],
    [0.077_197_29, 0.139_462_94, 0.212_020_22, 0.259_143_23],
    [0.792_698_7, 0.796_341_6, 0.725_869_5, 0.653_909_25],
    [0.031_941_756, -0.172_282_32, -0.275_801_48, -0.337_613_17],
];

/// The moment bias of 64-bit moment shadow maps (16 bits a moment; Peters & Klein 2015, 3·10⁻⁵):
/// the mean moments are pulled this far toward those of a spread distribution, so quantized
/// vectors stay valid.
pub const DEFAULT_MOMENT_BIAS: f32 = 3e-5;

fn matrix(columns: &[[f32; 4]; 4]) -> Mat4 {
    Mat4::from_cols_array_2d(columns)
}

/// `(z, z², z³, z⁴)`.
pub fn power_moments(z: f32) -> Vec4 {
    let s = z * z;
    Vec4::new(z, s, s * z, s * s)
}

/// A depth's four moments, quantization-optimized (each in `[0, 1]` for `z ∈ [0, 1]`).
pub fn encode(z: f32) -> Vec4 {
    matrix(&ENCODE) * power_moments(z) + Vec4::new(QUANTIZATION_OFFSET, 0.0, 0.0, 0.0)
}

/// Optimized moments back to power moments.
pub fn decode(optimized: Vec4) -> Vec4 {
    matrix(&DECODE) * (optimized - Vec4::new(QUANTIZATION_OFFSET, 0.0, 0.0, 0.0))
}

/// One texel's entry of the summed-area table.
pub fn fixed_point(optimized: Vec4) -> [u32; 4] {
    optimized
        .to_array()
        .map(|m| (m.clamp(0.0, 1.0) * SAT_SCALE).round() as u32)
}

/// The mean power moments of `count` texels whose fixed-point entries sum (wrapping) to `sum`.
pub fn mean_of_sum(sum: [u32; 4], count: u32) -> Vec4 {
    let optimized = Vec4::from_array(sum.map(|s| s as f32)) / (count.max(1) as f32 * SAT_SCALE);
    decode(optimized)
}

/// What a filter region's moments say at a receiver depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hamburger {
    /// The share of the region strictly in front of the receiver: the shadow intensity.
    pub in_front: f32,
    /// The mean depth of that share (the receiver's depth where none is in front).
    pub blocker: f32,
}

/// Hamburger 4MSM (Peters & Klein 2015, Algorithm 3) of mean power moments `b` at depth `z_f`,
/// with the moment bias `bias`.
pub fn hamburger(b: Vec4, z_f: f32, bias: f32) -> Hamburger {
    let b = b.lerp(Vec4::new(0.5, 0.5, 0.5, 0.5), bias);
    // A Cholesky factorization of the Hankel matrix of (1, b1, b2, b3, b4).
    let l32_d22 = -b.x * b.y + b.z;
    let d22 = (-b.x * b.x + b.y).max(1e-12);
    let squared_variance = -b.y * b.y + b.w;
    let d33_d22 = (squared_variance * d22 - l32_d22 * l32_d22).max(1e-18);
    let l32 = l32_d22 / d22;
    // Solve for the quadratic whose roots are the other two support points.
    let mut c = [1.0, z_f, z_f * z_f];
    c[1] -= b.x;
    c[2] -= b.y + l32 * c[1];
    c[1] /= d22;
    c[2] *= d22 / d33_d22;
    c[1] -= l32 * c[2];
    c[0] -= c[1] * b.x + c[2] * b.y;
    let p = c[1] / c[2];
    let q = c[0] / c[2];
    let r = (p * p * 0.25 - q).max(0.0).sqrt();
    let z1 = -p * 0.5 - r;
    let z2 = -p * 0.5 + r;
    // The weights of the three points (z_f, z1, z2) that have moments 0, 1 and 2 of b.
    let weight = |zi: f32, zj: f32, zk: f32| {
        let den = (zi - zj) * (zi - zk);
        if den.abs() < 1e-12 {
            0.0
        } else {
            (b.y - (zj + zk) * b.x + zj * zk) / den
        }
    };
    let w1 = weight(z1, z_f, z2);
    let w2 = weight(z2, z_f, z1);
    let (mut in_front, mut sum) = (0.0f32, 0.0f32);
    for (w, z) in [(w1, z1), (w2, z2)] {
        if z < z_f && z.is_finite() && w.is_finite() {
            in_front += w;
            sum += w * z;
        }
    }
    let in_front = in_front.clamp(0.0, 1.0);
    let blocker = if in_front > 1e-6 {
        (sum / in_front.max(1e-6)).clamp(0.0, z_f)
    } else {
        z_f
    };
    Hamburger { in_front, blocker }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mix(points: &[(f32, f32)]) -> Vec4 {
        points
            .iter()
            .map(|&(w, z)| power_moments(z) * w)
            .fold(Vec4::ZERO, |a, b| a + b)
    }

    /// The numbers of a `const NAME = mat4x4<f32>(...)` or `const NAME = x;` in WGSL text.
    fn wgsl_numbers(source: &str, name: &str) -> Vec<f32> {
        let start = source
            .find(&format!("const {name} ="))
            .unwrap_or_else(|| panic!("const {name} in the shader"));
        let body = &source[start..];
        let body = &body[body.find('=').unwrap_or(0) + 1..body.find(';').unwrap_or(body.len())];
        let body = body.split_once('(').map_or(body, |(_, b)| b);
        body.split(|c: char| c == ',' || c == ')' || c.is_whitespace())
            .filter(|t| !t.is_empty())
            .map(|t| {
                t.parse()
                    .unwrap_or_else(|_| panic!("{name}: {t} is a number"))
            })
            .collect()
    }

    /// The WGSL twins spell these constants out; they must be this file's.
    #[test]
    fn shader_constants_match() {
        let read = include_str!("../../shaders/shared/msm.wgsl");
        let write = include_str!("../../shaders/passes/moment_sat.wgsl");
        assert_eq!(wgsl_numbers(read, "MSM_MAX_RADIUS"), [MAX_RADIUS as f32]);
        assert_eq!(wgsl_numbers(read, "MSM_SCALE"), [SAT_SCALE]);
        let flat = |m: &[[f32; 4]; 4]| m.iter().flatten().copied().collect::<Vec<f32>>();
        for (source, name, matrix) in [(read, "DECODE", &DECODE), (write, "ENCODE", &ENCODE)] {
            let shader = wgsl_numbers(source, name);
            assert_eq!(shader.len(), 16, "{name}");
            for (a, b) in shader.iter().zip(flat(matrix)) {
                assert!(
                    (a - b).abs() <= 1e-6 * b.abs().max(1.0),
                    "{name}: {a} vs {b}"
                );
            }
        }
        for source in [read, write] {
            // The offset is written inline: `vec4<f32>(0.0359..., 0.0, 0.0, 0.0)`.
            let offset: f32 = source
                .split(|c: char| !(c.is_ascii_digit() || c == '.'))
                .find(|t| t.starts_with("0.0359"))
                .and_then(|t| t.parse().ok())
                .expect("the quantization offset in the shader");
            assert!(
                (offset - QUANTIZATION_OFFSET).abs() < 1e-8,
                "the offset: {offset}"
            );
        }
    }

    #[test]
    fn the_quantization_round_trips_and_stays_in_the_unit_cube() {
        for i in 0..=100 {
            let z = i as f32 / 100.0;
            let e = encode(z);
            assert!(
                e.min_element() >= -1e-3 && e.max_element() <= 1.0 + 1e-3,
                "{z}: {e}"
            );
            let back = decode(e);
            assert!((back - power_moments(z)).abs().max_element() < 1e-4, "{z}");
        }
    }

    #[test]
    fn two_depths_are_read_exactly_through_the_fixed_point_table() {
        // A region of 100 texels: a share w at the blocker depth, the rest at the receiver's.
        // (Closer than about 0.1 the moment bias blurs the two: 0.75 at 0.45 over 0.5 reads 0.62.)
        for (w, blocker, receiver) in [(0.3, 0.2, 0.7), (0.75, 0.35, 0.5), (0.05, 0.1, 0.9)] {
            let n = 100u32;
            let k = (w * n as f32).round() as u32;
            let mut sum = [0u32; 4];
            for i in 0..n {
                let z = if i < k { blocker } else { receiver };
                for (s, t) in sum.iter_mut().zip(fixed_point(encode(z))) {
                    *s = s.wrapping_add(t);
                }
            }
            let h = hamburger(mean_of_sum(sum, n), receiver - 0.01, DEFAULT_MOMENT_BIAS);
            assert!((h.in_front - w).abs() < 0.02, "{w}: {h:?}");
            assert!((h.blocker - blocker).abs() < 0.01, "{blocker}: {h:?}");
        }
    }

    #[test]
    fn a_box_sum_survives_the_table_wrapping() {
        // The largest box of the deepest texels: the true sum is below 2³², the table's wraps.
        let side = 2 * MAX_RADIUS + 1;
        let t = fixed_point(encode(1.0));
        let total = t.map(|v| v as u64 * (side * side) as u64);
        assert!(total.iter().all(|&s| s < 1u64 << 32));
        // Differences of wrapped prefix sums recover it.
        let before = [u32::MAX - 5; 4];
        let after: Vec<u32> = (0..4)
            .map(|i| before[i].wrapping_add(total[i] as u32))
            .collect();
        for i in 0..4 {
            assert_eq!(after[i].wrapping_sub(before[i]) as u64, total[i]);
        }
    }

    #[test]
    fn nothing_in_front_is_lit_and_everything_in_front_is_shadow() {
        let behind = hamburger(mix(&[(1.0, 0.8)]), 0.5, DEFAULT_MOMENT_BIAS);
        assert!(behind.in_front < 0.01, "{behind:?}");
        let before = hamburger(mix(&[(0.5, 0.2), (0.5, 0.3)]), 0.6, DEFAULT_MOMENT_BIAS);
        assert!(before.in_front > 0.99, "{before:?}");
        assert!((before.blocker - 0.25).abs() < 0.02, "{before:?}");
    }

    #[test]
    fn three_depths_leak_but_stay_bounded() {
        // Two occluders and the receiver: the four moments no longer determine the
        // distribution; the share in front is a lower bound, so the error is light.
        let b = mix(&[(0.4, 0.2), (0.4, 0.5), (0.2, 0.9)]);
        let h = hamburger(b, 0.85, DEFAULT_MOMENT_BIAS);
        assert!(h.in_front <= 0.8 + 0.01, "{h:?}");
        assert!(h.in_front > 0.5, "{h:?}");
    }
}
