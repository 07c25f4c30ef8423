//! Bitmask soft shadows' arithmetic (Schwarz & Stamminger, Computer Graphics Forum 26(3), 2007),
//! the CPU twin of `shaders/methods/bitmask.wgsl`: each shadow-map texel in front of a receiver
//! is a micro-patch, a small quad at the distance the map stores; seen from the receiver `x` it
//! covers a quad of the light ([`back_project`]), and the light samples inside that quad are
//! found as the AND of its four edges' half-plane masks from look-up tables ([`quad_bits`]: the
//! tables of [`DiskMask`], the ones `dbuffer-fused` reads). The OR over every micro-patch is the
//! set of samples some occluder hides, so overlapping occluders combine as they do in the world
//! — occluder fusion in image space — and `V` is the share of samples left
//! ([`visibility`]).
//!
//! Gaps and overlaps between neighbouring micro-patches are the method's known error: two
//! texels at different distances back-project to quads that no longer meet. The gap filling of
//! the camera pass moves each patch corner to the distance the texels around it agree on
//! ([`corner_distance`]: the mean of those within [`CONTINUITY`] of the texel's own), so the
//! patches of one continuous surface share their corners and tile the light without gaps, as the
//! microquads of "Microquad soft shadow mapping revisited" (Schwarz & Stamminger, EG 2008) do.

use glam::{Vec2, Vec3};

use super::fused::{Bits, DiskMask};
use crate::scene::AreaLight;

/// Texels whose distances differ by less than this share of the texel's own are one surface:
/// their patches share the corner between them.
pub const CONTINUITY: f32 = 0.03;

/// The light's plane: where a receiver's rays are followed to, in the unit-disk coordinates the
/// masks use (the light's basis about its centre, over the radius of the disk that holds it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPlane {
    pub center: Vec3,
    pub u: Vec3,
    pub w: Vec3,
    pub normal: Vec3,
    pub bound: f32,
}

impl LightPlane {
    pub fn of(light: &AreaLight) -> LightPlane {
        let (u, w) = light.basis();
        LightPlane {
            center: light.center,
            u,
            w,
            normal: light.normal,
            bound: light.radius.max(f32::MIN_POSITIVE),
        }
    }

    /// Height of `p` in front of the plane.
    fn height(&self, p: Vec3) -> f32 {
        self.normal.dot(p - self.center)
    }
}

/// Where the ray from `x` through `p` meets the light's plane, in unit-disk coordinates; `None`
/// unless `p` lies strictly between the plane and `x`'s height above it (only then can it hide a
/// point of the light from `x`).
pub fn back_project(plane: &LightPlane, x: Vec3, p: Vec3) -> Option<Vec2> {
    let hx = plane.height(x);
    let hp = plane.height(p);
    if !(hp > 0.0 && hp < hx * (1.0 - 1e-5)) {
        return None;
    }
    let q = x + (p - x) * (hx / (hx - hp));
    let r = q - plane.center;
    Some(Vec2::new(r.dot(plane.u), r.dot(plane.w)) / plane.bound)
}

/// The samples inside the convex quad `q` (either winding) through the half-plane tables: the
/// AND of its four edges' inner half-planes. None when the quad is degenerate.
pub fn quad_bits(mask: &DiskMask, q: [Vec2; 4]) -> Bits {
    let twice_area: f32 = (0..4).map(|i| q[i].perp_dot(q[(i + 1) % 4])).sum();
    if twice_area.is_nan() || twice_area.abs() < 1e-12 {
        return Bits::default();
    }
    let orient = twice_area.signum();
    let mut bits = mask.all();
    for i in 0..4 {
        let (a, b) = (q[i], q[(i + 1) % 4]);
        let e = b - a;
        // The outward normal of a counter-clockwise edge; the inside is n·p ≤ n·a.
        let n = Vec2::new(e.y, -e.x) * orient;
        let h = mask.half_plane(n, n.dot(a));
        for (w, m) in bits.iter_mut().zip(h) {
            *w &= m;
        }
    }
    bits
}

/// The patch corner's distance: the mean of the distances of the (up to four) texels that meet
/// at the corner and lie within [`CONTINUITY`] of `own`, the texel's (gap filling); `own` where
/// the texel is alone.
pub fn corner_distance(own: f32, around: &[f32]) -> f32 {
    let (sum, n) = around
        .iter()
        .filter(|o| (**o - own).abs() <= CONTINUITY * own)
        .fold((0.0, 0), |(s, n), o| (s + o, n + 1));
    if n == 0 {
        own
    } else {
        sum / n as f32
    }
}

/// `V` at `x` behind `patches` (world-space quads, corners in order round each): the share of
/// the mask's samples no patch covers.
pub fn visibility(plane: &LightPlane, mask: &DiskMask, x: Vec3, patches: &[[Vec3; 4]]) -> f32 {
    let mut hidden = Bits::default();
    for patch in patches {
        let mut q = [Vec2::ZERO; 4];
        let mut ok = true;
        for (k, p) in patch.iter().enumerate() {
            match back_project(plane, x, *p) {
                Some(a) => q[k] = a,
                None => ok = false,
            }
        }
        if !ok {
            continue;
        }
        for (h, b) in hidden.iter_mut().zip(quad_bits(mask, q)) {
            *h |= b;
        }
    }
    let all = mask.all();
    let covered: u32 = hidden
        .iter()
        .zip(all)
        .map(|(h, a)| (h & a).count_ones())
        .sum();
    1.0 - covered as f32 / mask.len().max(1) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::fused::MaskEval;
    use crate::geometry::oracle::Oracle;

    fn light() -> AreaLight {
        AreaLight::disk(Vec3::new(0.0, 4.0, 0.0), Vec3::NEG_Y, 0.5)
    }

    /// A plate at height `y` over `[x0, x1] × [z0, z1]` cut into `k × k` patches, each flat at
    /// its own corners' heights (`tilt` raises the plate along x: y + tilt·x).
    fn plate(k: usize, x0: f32, x1: f32, z0: f32, z1: f32, y: f32, tilt: f32) -> Vec<[Vec3; 4]> {
        let at = |i: usize, j: usize| {
            let x = x0 + (x1 - x0) * i as f32 / k as f32;
            let z = z0 + (z1 - z0) * j as f32 / k as f32;
            Vec3::new(x, y + tilt * x, z)
        };
        let mut out = Vec::new();
        for i in 0..k {
            for j in 0..k {
                out.push([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        out
    }

    fn triangles(patches: &[[Vec3; 4]]) -> Vec<[Vec3; 3]> {
        patches
            .iter()
            .flat_map(|p| [[p[0], p[1], p[2]], [p[0], p[2], p[3]]])
            .collect()
    }

    #[test]
    fn quad_bits_agree_with_testing_every_sample() {
        let mask = DiskMask::new(128, MaskEval::Lut);
        let exact = DiskMask::new(128, MaskEval::Exact);
        let mut worst = 0;
        for k in 0..200 {
            let f = k as f32;
            let c = Vec2::new((f * 0.37).sin() * 0.8, (f * 0.61).cos() * 0.8);
            let (s, r) = ((f * 1.3).sin() * 0.6 + 0.7, f * 0.29);
            let corner = |a: f32| c + s * Vec2::new((r + a).cos(), (r + a).sin());
            let mut q = [corner(0.0), corner(1.7), corner(3.3), corner(4.6)];
            if k % 2 == 1 {
                q.reverse();
            }
            let lut = quad_bits(&mask, q);
            let truth = quad_bits(&exact, q);
            let differ: u32 = lut
                .iter()
                .zip(truth)
                .map(|(a, b)| (a ^ b).count_ones())
                .sum();
            worst = worst.max(differ);
            assert!(
                lut.iter().zip(mask.all()).all(|(b, a)| b & !a == 0),
                "bits beyond the samples"
            );
        }
        // A quad's four edges, each within half a table bin: a few samples along them.
        assert!(worst <= 8, "{worst} of 128 samples differ");
    }

    #[test]
    fn a_plate_hides_what_the_ray_tracer_says() {
        let l = light();
        let plane = LightPlane::of(&l);
        let mask = DiskMask::for_light(&l, 256, MaskEval::Lut);
        let patches = plate(8, -0.5, 0.7, -0.4, 0.6, 2.5, 0.0);
        let oracle = Oracle::new(triangles(&patches), l, 4096);
        let mut worst = 0.0f32;
        for i in 0..40 {
            let x = Vec3::new(-2.0 + 0.1 * i as f32, 0.0, 0.1);
            let v = visibility(&plane, &mask, x, &patches);
            worst = worst.max((v - oracle.visibility(x)).abs());
        }
        assert!(worst < 0.03, "worst |ΔV| {worst}");
    }

    #[test]
    fn gap_filling_closes_the_gaps_between_texels_at_different_distances() {
        // A tilted plate as a shadow map stores it: each texel flat at its own distance (the
        // plain micro-patch) leaves gaps where neighbours step; moved to the corners they share
        // it hides what the continuous plate does.
        let l = light();
        let plane = LightPlane::of(&l);
        let mask = DiskMask::for_light(&l, 256, MaskEval::Lut);
        let shared = plate(6, -0.6, 0.6, -0.6, 0.6, 2.4, 0.5);
        let flat: Vec<[Vec3; 4]> = shared
            .iter()
            .map(|p| {
                let y = p.iter().map(|c| c.y).sum::<f32>() / 4.0;
                p.map(|c| Vec3::new(c.x, y, c.z))
            })
            .collect();
        let oracle = Oracle::new(triangles(&shared), l, 4096);
        let (mut err_flat, mut err_shared) = (0.0f32, 0.0f32);
        for i in 0..60 {
            let x = Vec3::new(-0.3 + 0.01 * i as f32, 0.0, 0.05);
            let truth = oracle.visibility(x);
            err_flat += (visibility(&plane, &mask, x, &flat) - truth).abs();
            err_shared += (visibility(&plane, &mask, x, &shared) - truth).abs();
        }
        assert!(
            err_shared < 0.5 * err_flat,
            "shared corners {err_shared}, flat patches {err_flat}"
        );
        assert!(err_shared / 60.0 < 0.02, "mean |ΔV| {}", err_shared / 60.0);
    }

    #[test]
    fn corners_take_only_the_texels_of_their_surface() {
        assert_eq!(corner_distance(2.0, &[2.0, 2.02, 2.04, 5.0]), 2.02);
        assert_eq!(corner_distance(2.0, &[5.0, 6.0]), 2.0);
    }

    #[test]
    fn shader_constants_match() {
        let shader = include_str!("../../shaders/methods/bitmask.wgsl");
        let tables = include_str!("../../shaders/shared/light_bits.wgsl");
        let patches = include_str!("../../shaders/passes/micro_patches.wgsl");
        let number = |source: &str, name: &str| -> f32 {
            let line = source
                .lines()
                .find(|l| l.starts_with(&format!("const {name}:")))
                .unwrap_or_else(|| panic!("{name} in the shader"));
            let value = line.split('=').nth(1).expect("a value");
            value
                .trim()
                .trim_end_matches(';')
                .trim_end_matches('u')
                .parse()
                .expect("a number")
        };
        use crate::geometry::fused::{LUT_ANGLES, LUT_OFFSETS};
        assert_eq!(number(tables, "LUT_ANGLES"), LUT_ANGLES as f32);
        assert_eq!(number(tables, "LUT_OFFSETS"), LUT_OFFSETS as f32);
        assert_eq!(number(shader, "CONTINUITY"), CONTINUITY);
        assert_eq!(number(patches, "CONTINUITY"), CONTINUITY);
    }
}
