//! Face classes against a disk light (Jakobsen et al. 2004, §2.1, with correction 1 of docs/method/dbuffer.md#face-classes).
//!
//! For a face with unit normal `n` through `v`, `f(p) = n·(p − v)`. Over the disk, `f` ranges
//! over `f(c) ± r|n⊥|` with `n⊥ = n − (n·n_c) n_c`, reached at `c ± r n⊥/|n⊥|`. The paper's
//! eq. (1a/1b) uses `(n×n_c)×n_c` unnormalised; its length is `|n⊥|`, not 1, which puts the
//! "extreme" points inside the disk and misclassifies tilted faces.

use glam::Vec3;
use rayon::prelude::*;

use super::adjacency::CasterMesh;
use crate::scene::AreaLight;

/// How a face sees the disk light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FaceClass {
    /// Every point of the disk is in front of the face (`min f > 0`).
    AllFront,
    /// No point of the disk is in front of the face (`max f ≤ 0`).
    NoneFront,
    /// A silhouette face whose plane has the light centre behind it (`f(c) < 0`): front-facing to
    /// less than half of the disk (Jakobsen et al. 2004, Fig. 6).
    SilhouetteA,
    /// A silhouette face with the light centre in front of it (`f(c) ≥ 0`).
    SilhouetteB,
}

impl FaceClass {
    /// The class of the same face seen from its back side. An open mesh is a two-sided sheet, so
    /// across a boundary edge a face borders its own mirror image.
    pub fn mirrored(self) -> FaceClass {
        match self {
            FaceClass::AllFront => FaceClass::NoneFront,
            FaceClass::NoneFront => FaceClass::AllFront,
            FaceClass::SilhouetteA => FaceClass::SilhouetteB,
            FaceClass::SilhouetteB => FaceClass::SilhouetteA,
        }
    }

    pub fn is_silhouette_face(self) -> bool {
        matches!(self, FaceClass::SilhouetteA | FaceClass::SilhouetteB)
    }

    /// Small integer code, the same one the GPU uses for the class overlay.
    pub fn code(self) -> u32 {
        match self {
            FaceClass::AllFront => 0,
            FaceClass::NoneFront => 1,
            FaceClass::SilhouetteA => 2,
            FaceClass::SilhouetteB => 3,
        }
    }
}

/// The range `[min f, max f]` of the face's plane function over the disk, and `f(c)`.
/// For a polygon, over its vertices (exact: a linear function's extremes over a convex polygon
/// are at its vertices).
pub fn plane_range_over_disk(normal: Vec3, offset: f32, light: &AreaLight) -> (f32, f32, f32) {
    super::outline::plane_range(normal, offset, light)
}

/// Class of a plane `normal · p = offset` against the light.
pub fn classify_plane(normal: Vec3, offset: f32, light: &AreaLight) -> FaceClass {
    let (min_f, max_f, fc) = plane_range_over_disk(normal, offset, light);
    if min_f > 0.0 {
        FaceClass::AllFront
    } else if max_f <= 0.0 {
        FaceClass::NoneFront
    } else if fc < 0.0 {
        FaceClass::SilhouetteA
    } else {
        FaceClass::SilhouetteB
    }
}

/// The class of face `f` of `mesh`.
pub fn classify_face(mesh: &CasterMesh, f: u32, light: &AreaLight) -> FaceClass {
    let (normal, offset) = mesh.plane(f);
    classify_plane(normal, offset, light)
}

/// Classes of every face of the caster, in face order (in parallel for large meshes).
pub fn classify(mesh: &CasterMesh, light: &AreaLight) -> Vec<FaceClass> {
    const PARALLEL_ABOVE: usize = 16 * 1024;
    if mesh.faces.len() > PARALLEL_ABOVE {
        (0..mesh.faces.len() as u32)
            .into_par_iter()
            .with_min_len(4096)
            .map(|f| classify_face(mesh, f, light))
            .collect()
    } else {
        (0..mesh.faces.len() as u32)
            .map(|f| classify_face(mesh, f, light))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(r: f32) -> AreaLight {
        AreaLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: r,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        }
    }

    /// Brute force: `f` at many rim points (the extremes of a linear function over a disk lie on
    /// its rim), classified with the same rule.
    fn brute(normal: Vec3, offset: f32, l: &AreaLight) -> FaceClass {
        let (u, w) = l.basis();
        let fc = normal.dot(l.center) - offset;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for i in 0..20_000 {
            let a = i as f32 / 20_000.0 * std::f32::consts::TAU;
            let p = l.center + l.radius * (a.cos() * u + a.sin() * w);
            let f = normal.dot(p) - offset;
            lo = lo.min(f);
            hi = hi.max(f);
        }
        if lo > 0.0 {
            FaceClass::AllFront
        } else if hi <= 0.0 {
            FaceClass::NoneFront
        } else if fc < 0.0 {
            FaceClass::SilhouetteA
        } else {
            FaceClass::SilhouetteB
        }
    }

    fn plane_through(normal: Vec3, point: Vec3) -> (Vec3, f32) {
        let n = normal.normalize();
        (n, n.dot(point))
    }

    #[test]
    fn face_parallel_to_the_disk() {
        let l = light(0.5);
        // Below the light, facing up toward it: the whole disk is in front.
        let (n, d) = plane_through(Vec3::Y, Vec3::new(3.0, 1.0, -2.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::AllFront);
        // Facing down, away from it: none of the disk is in front.
        let (n, d) = plane_through(Vec3::NEG_Y, Vec3::new(3.0, 1.0, -2.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::NoneFront);
        // In the light plane itself: f = 0 everywhere on the disk, so no point is in front.
        let (n, d) = plane_through(Vec3::Y, Vec3::new(0.0, 4.0, 0.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::NoneFront);
    }

    #[test]
    fn face_edge_on_to_the_disk() {
        let l = light(0.5);
        // A vertical face through the light centre: half the disk on each side, f(c) = 0 -> B.
        let (n, d) = plane_through(Vec3::X, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::SilhouetteB);
        // Offset by 0.3 < r with the centre behind it: front-facing to less than half -> A.
        let (n, d) = plane_through(Vec3::X, Vec3::new(0.3, 1.0, 0.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::SilhouetteA);
        let (n, d) = plane_through(Vec3::NEG_X, Vec3::new(0.3, 1.0, 0.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::SilhouetteB);
        // Offset by 0.7 > r: the whole disk on one side.
        let (n, d) = plane_through(Vec3::X, Vec3::new(0.7, 1.0, 0.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::NoneFront);
        let (n, d) = plane_through(Vec3::NEG_X, Vec3::new(0.7, 1.0, 0.0));
        assert_eq!(classify_plane(n, d, &l), FaceClass::AllFront);
    }

    #[test]
    fn correction_1_normalised_extreme_points() {
        // A face tilted 30° from the light normal: |n⊥| = ½. With f(c) = 0.3 r the disk reaches
        // f(c) − r|n⊥| = −0.2 r, so part of it is behind the face: a silhouette face. The printed
        // unnormalised eq. (1) reaches only f(c) − r|n⊥|² = +0.05 r and calls it all-frontfacing.
        let l = light(1.0);
        let n = Vec3::new(0.5, 0.75f32.sqrt(), 0.0);
        let d = n.dot(l.center) - 0.3;
        assert_eq!(classify_plane(n, d, &l), FaceClass::SilhouetteB);
        assert_eq!(brute(n, d, &l), FaceClass::SilhouetteB);
        let printed_min = 0.3 - l.radius * 0.25;
        assert!(
            printed_min > 0.0,
            "the printed equation would say all-front"
        );
    }

    #[test]
    fn classes_agree_with_brute_force_rim_sampling() {
        let mut state = 0x2545_f491_u32;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32 * 2.0 - 1.0
        };
        let l = AreaLight {
            center: Vec3::new(0.1, 3.0, -0.2),
            normal: Vec3::new(0.2, -1.0, 0.1).normalize(),
            radius: 0.8,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        };
        let mut seen = std::collections::HashSet::new();
        for _ in 0..4000 {
            let n = Vec3::new(rnd(), rnd(), rnd()).normalize_or(Vec3::Y);
            let p = l.center + Vec3::new(rnd(), rnd() - 1.5, rnd());
            let (n, d) = plane_through(n, p);
            let (lo, hi, _) = plane_range_over_disk(n, d, &l);
            if lo.abs() < 1e-3 || hi.abs() < 1e-3 {
                continue; // too close to a class boundary for the sampled rim to decide
            }
            let c = classify_plane(n, d, &l);
            assert_eq!(c, brute(n, d, &l), "normal {n}, point {p}");
            seen.insert(c);
        }
        assert_eq!(seen.len(), 4, "every class was exercised");
    }

    #[test]
    fn mirrored_swaps_sides() {
        for c in [
            FaceClass::AllFront,
            FaceClass::NoneFront,
            FaceClass::SilhouetteA,
            FaceClass::SilhouetteB,
        ] {
            assert_eq!(c.mirrored().mirrored(), c);
            assert_ne!(c.mirrored(), c);
        }
    }
}
