//! Closed forms for a linear light (Heidrich et al. 2000, §3.1): the exact visible fraction of a segment light
//! seen past one straight edge, the truth the line reference, `sampled` and `linear-ssm` are
//! tested against.
//!
//! **A half-plane occluder** `H = {o + α d + β m : β ≥ 0}` (edge through `o` along unit `d`,
//! unit `m ⟂ d` pointing into the occluder, plane normal `n_H = d × m`) and a receiver point
//! `x`. A light point `q` is hidden iff the segment `x → q` meets `H`, iff (1) `q` lies across
//! `H`'s plane from `x`, and (2) `q` lies on `H`'s side of the plane through `x` and the edge line
//! (the segment's crossing with `H`'s plane lies on the ray from `x` through `q`, and `Π` contains
//! `x`, so both sides agree). Along `q(s) = a + s (b − a)` both conditions are linear in `s`:
//!
//! ```text
//! g1(s) = n_H·(q(s) − o),   σ1 = −sign(n_H·(x − o))        hidden needs σ1·g1(s) > 0
//! k     = d × (x − o)
//! g2(s) = k·(q(s) − o),     σ2 =  sign(k·m)                 hidden needs σ2·g2(s) > 0
//! hidden = [0, 1] ∩ {σ1 g1 > 0} ∩ {σ2 g2 > 0} = [lo, hi],   V(x) = 1 − max(0, hi − lo)
//! ```
//!
//! For a light from `(−L/2, H, 0)` to `(L/2, H, 0)`, the occluder `x < 0` in the plane `y = h`
//! and receivers on `y = 0`, this is `V = clamp(½ + x (H − h)/(h L), 0, 1)`: linear across the
//! penumbra, as Heidrich et al. 2000 say for a receiver parallel to the light; an edge parallel to the light
//! casts a hard boundary.

use glam::{DVec3, Vec3};

use crate::scene::LineLight;

/// A half-plane occluder: bounded by the line through `origin` along `along`, extending toward
/// `into` (perpendicular to `along`, in its plane). Both directions need not be unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfPlane {
    pub origin: Vec3,
    pub along: Vec3,
    pub into: Vec3,
}

impl HalfPlane {
    /// The occluder as two triangles reaching `reach` from its edge and `half` along it both
    /// ways (for ray casting; "infinite" for points whose shadow rays cross its plane inside it).
    pub fn quad(&self, half: f32, reach: f32) -> [[Vec3; 3]; 2] {
        let d = self.along.normalize();
        let m = (self.into - d * d.dot(self.into)).normalize();
        let a = self.origin - d * half;
        let b = self.origin + d * half;
        let c = b + m * reach;
        let e = a + m * reach;
        [[a, b, c], [a, c, e]]
    }
}

/// The fraction of `light`'s length visible from `x` past the half-plane `h`, exact (in f64).
/// A point in the occluder's plane sees the whole light (the occluder has no thickness).
pub fn half_plane_visibility(light: &LineLight, h: &HalfPlane, x: Vec3) -> f64 {
    let d = h.along.as_dvec3().normalize();
    let into = h.into.as_dvec3();
    let m = (into - d * d.dot(into)).normalize();
    let n = d.cross(m);
    let o = h.origin.as_dvec3();
    let x = x.as_dvec3();
    let (a, b) = (light.a.as_dvec3(), light.b.as_dvec3());
    let side = n.dot(x - o);
    if side == 0.0 {
        return 1.0;
    }
    let k = d.cross(x - o);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    // σ·(g0 + s·g1) > 0 for s in [lo, hi].
    let mut clip = |normal: DVec3, sigma: f64| {
        let g0 = sigma * normal.dot(a - o);
        let g1 = sigma * normal.dot(b - a);
        if g1 > 0.0 {
            lo = lo.max(-g0 / g1);
        } else if g1 < 0.0 {
            hi = hi.min(-g0 / g1);
        } else if g0 <= 0.0 {
            hi = lo; // never
        }
    };
    clip(n, -side.signum());
    clip(k, k.dot(m).signum());
    1.0 - (hi - lo).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light() -> LineLight {
        LineLight {
            a: Vec3::new(-1.0, 4.0, 0.0),
            b: Vec3::new(1.0, 4.0, 0.0),
            intensity: 1.0,
        }
    }

    /// The fraction of `n` evenly spaced light points whose segment to `x` meets the half-plane.
    fn brute(light: &LineLight, h: &HalfPlane, x: Vec3, n: usize) -> f64 {
        let d = h.along.as_dvec3().normalize();
        let m = {
            let i = h.into.as_dvec3();
            (i - d * d.dot(i)).normalize()
        };
        let nrm = d.cross(m);
        let o = h.origin.as_dvec3();
        let xd = x.as_dvec3();
        let visible = (0..n)
            .filter(|&i| {
                let q = light.at((i as f32 + 0.5) / n as f32).as_dvec3();
                let (sx, sq) = (nrm.dot(xd - o), nrm.dot(q - o));
                if sx * sq >= 0.0 {
                    return true; // same side: the segment does not cross the plane
                }
                let y = xd + (q - xd) * (sx / (sx - sq));
                m.dot(y - o) < 0.0
            })
            .count();
        visible as f64 / n as f64
    }

    #[test]
    fn parallel_receiver_is_linear_across_the_penumbra() {
        // Light at height 4, length 2; occluder x < 0 at y = 2: V = ½ + x·(4 − 2)/(2·2).
        let l = light();
        let h = HalfPlane {
            origin: Vec3::new(0.0, 2.0, 0.0),
            along: Vec3::Z,
            into: Vec3::NEG_X,
        };
        for i in 0..=40 {
            let x = -1.5 + 3.0 * i as f32 / 40.0;
            let v = half_plane_visibility(&l, &h, Vec3::new(x, 0.0, 0.7));
            let expect = (0.5 + f64::from(x) * 0.5).clamp(0.0, 1.0);
            assert!((v - expect).abs() < 1e-6, "x = {x}: {v} vs {expect}");
        }
        // Receivers above the occluder see everything; an edge parallel to the light is hard.
        assert_eq!(
            half_plane_visibility(&l, &h, Vec3::new(-0.3, 3.0, 0.0)),
            1.0
        );
        let parallel = HalfPlane {
            origin: Vec3::new(0.0, 2.0, 0.0),
            along: Vec3::X,
            into: Vec3::NEG_Z,
        };
        for z in [-0.3f32, -0.01, 0.01, 0.3] {
            let v = half_plane_visibility(&l, &parallel, Vec3::new(0.2, 0.0, z));
            assert_eq!(v, if z < 0.0 { 0.0 } else { 1.0 }, "z = {z}");
        }
    }

    #[test]
    fn agrees_with_brute_force_for_random_configurations() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f32 / (1u64 << 53) as f32
        };
        let mut unit = || loop {
            let v = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 2.0;
            if let Some(u) = v.try_normalize() {
                return u;
            }
        };
        let mut worst = 0.0f64;
        for _ in 0..200 {
            let l = LineLight {
                a: Vec3::new(-1.0, 4.0, 0.0) + unit() * 0.5,
                b: Vec3::new(1.0, 4.0, 0.0) + unit() * 0.5,
                intensity: 1.0,
            };
            let along = unit();
            let h = HalfPlane {
                origin: Vec3::new(0.0, 2.0, 0.0) + unit() * 0.3,
                along,
                into: along.cross(unit()),
            };
            let x = Vec3::new(0.0, 0.0, 0.0) + unit() * 1.5;
            let exact = half_plane_visibility(&l, &h, x);
            let b = brute(&l, &h, x, 20_000);
            worst = worst.max((exact - b).abs());
        }
        // Midpoint sampling of one interval: at most one sample's worth at each end.
        assert!(worst <= 1.0 / 10_000.0 + 1e-9, "worst |ΔV| {worst}");
    }
}
