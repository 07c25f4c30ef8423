//! Planar projected shadows (Blinn 1988, "Me and my (fake) shadow"): the casters flattened onto
//! a receiver plane as seen from a point light, by one 4×4 matrix. What the `planar` method
//! needs from the geometry layer: which objects are planar receivers, and the matrix.
//!
//! The matrix for the plane `P = (n, d)` (`n·x + d = 0`, oriented so the light is on its
//! positive side) and the light `L = (l, 1)` is `M = (P·L) I − L Pᵀ`:
//! `M (v, 1) = (h_L v − h_v l, h_L − h_v)` with `h_v = n·v + d`, the point where the line from
//! `l` through `v` meets the plane, kept homogeneous so that clipping drops what lies beyond the
//! light (`w < 0`). A point below the plane (`h_v < 0`) still lands on it: a caster poking
//! through the receiver casts a false shadow there, one of the method's limits.

use glam::{Mat4, Vec3, Vec4};

use crate::scene::Scene;

/// At most this many receiver planes (each costs a mark and a pass over every caster).
pub const MAX_PLANAR_RECEIVERS: usize = 8;

/// A flat object and its plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarReceiver {
    /// Index into `scene.objects`.
    pub object: usize,
    /// `(n, d)`: the plane `n·x + d = 0`, unit `n`, the light point on its positive side.
    pub plane: Vec4,
}

/// Blinn's projection onto `plane` from the point `light`.
pub fn projection(plane: Vec4, light: Vec3) -> Mat4 {
    let l = light.extend(1.0);
    let dot = plane.dot(l);
    // Column j of L Pᵀ is l · P[j].
    let outer = Mat4::from_cols(l * plane.x, l * plane.y, l * plane.z, l * plane.w);
    Mat4::from_diagonal(Vec4::splat(dot)) - outer
}

/// The plane of a mesh given by its triangles if it is flat: the area-weighted normal through the
/// area-weighted centroid, every vertex within `1e-5` of the mesh's diagonal of it and every face
/// normal within `1 − 1e-4` of it (faces wound either way: surfaces are two-sided).
pub fn flat_plane(triangles: &[[Vec3; 3]]) -> Option<Vec4> {
    let mut sum = Vec3::ZERO;
    let mut centroid = Vec3::ZERO;
    let mut area = 0.0f32;
    let reference = triangles
        .iter()
        .map(|[a, b, c]| (*b - *a).cross(*c - *a))
        .max_by(|x, y| x.length_squared().total_cmp(&y.length_squared()))?;
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &[a, b, c] in triangles {
        let n = (b - a).cross(c - a);
        // Flipped faces count with their plane's orientation.
        let n = if n.dot(reference) < 0.0 { -n } else { n };
        let w = n.length();
        sum += n;
        centroid += (a + b + c) / 3.0 * w;
        area += w;
        for p in [a, b, c] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    if area.is_nan() || area <= 0.0 || !area.is_finite() {
        return None;
    }
    let n = sum.try_normalize()?;
    let centroid = centroid / area;
    let size = (hi - lo).length();
    for &[a, b, c] in triangles {
        let f = (b - a).cross(c - a);
        let len = f.length();
        if len > 0.0 && (f.dot(n) / len).abs() < 1.0 - 1e-4 {
            return None;
        }
        if [a, b, c]
            .iter()
            .any(|&p| (p - centroid).dot(n).abs() > 1e-5 * size)
        {
            return None;
        }
    }
    Some(n.extend(-n.dot(centroid)))
}

/// The planar receivers of `scene` for the light point `light`, at most
/// [`MAX_PLANAR_RECEIVERS`] (in object order), and a warning for each one left out or refused.
pub fn planar_receivers(scene: &Scene, light: Vec3) -> (Vec<PlanarReceiver>, Vec<String>) {
    let mut out = Vec::new();
    let mut warnings = Vec::new();
    for (i, object) in scene.objects.iter().enumerate() {
        let triangles: Vec<[Vec3; 3]> = object.mesh.triangle_corners().collect();
        let Some(mut plane) = flat_plane(&triangles) else {
            continue;
        };
        let h = plane.dot(light.extend(1.0));
        let size = object
            .mesh
            .bounds()
            .map_or(1.0, |(lo, hi)| (hi - lo).length());
        if h.abs() <= 1e-6 * size.max(1e-6) || !h.is_finite() {
            warnings.push(format!(
                "planar: '{}' is flat but its plane holds the light: no shadow projects onto it",
                object.name
            ));
            continue;
        }
        if h < 0.0 {
            plane = -plane;
        }
        if out.len() == MAX_PLANAR_RECEIVERS {
            warnings.push(format!(
                "planar: more than {MAX_PLANAR_RECEIVERS} flat objects; '{}' and later ones \
                 receive no shadow",
                object.name
            ));
            break;
        }
        out.push(PlanarReceiver { object: i, plane });
    }
    (out, warnings)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{shapes, AreaLight, Camera, Object};
    use glam::{Affine3A, Quat};

    fn hash(i: u32) -> f32 {
        let x = i.wrapping_mul(0x9e37_79b9) ^ (i >> 7).wrapping_mul(0x85eb_ca6b);
        (x % 10_000) as f32 / 10_000.0 - 0.5
    }

    #[test]
    fn projected_points_lie_on_the_plane_and_on_the_line_from_the_light() {
        for k in 0..200u32 {
            let n = Vec3::new(hash(k), hash(k + 1000) + 0.7, hash(k + 2000)).normalize();
            let plane = n.extend(hash(k + 3000));
            let l = Vec3::new(hash(k + 4000), 3.0, hash(k + 5000)) * 2.0;
            let v = Vec3::new(hash(k + 6000), hash(k + 7000) + 0.6, hash(k + 8000));
            let q = projection(plane, l) * v.extend(1.0);
            if q.w.abs() < 1e-3 {
                continue;
            }
            let p = q.truncate() / q.w;
            assert!(plane.dot(p.extend(1.0)).abs() < 1e-3, "{k}: off the plane");
            let along = (v - l).normalize().cross((p - l).normalize()).length();
            assert!(along < 1e-3, "{k}: not on the line from the light");
        }
    }

    fn object(name: &str, mesh: crate::scene::Mesh) -> Object {
        Object {
            name: name.into(),
            mesh,
            casts_shadow: true,
        }
    }

    #[test]
    fn receivers_are_the_flat_objects() {
        let tilt = Affine3A::from_rotation_translation(
            Quat::from_rotation_x(20f32.to_radians()),
            Vec3::new(0.0, 0.5, 0.0),
        );
        let mut flipped = shapes::plane();
        for t in &mut flipped.triangles {
            t.swap(1, 2);
        }
        flipped.triangles[1].swap(1, 2);
        let scene = Scene {
            name: "t".into(),
            camera: Camera {
                eye: Vec3::new(0.0, 2.0, 5.0),
                target: Vec3::ZERO,
                fov_y_deg: 45.0,
            },
            light: AreaLight {
                center: Vec3::new(0.0, 4.0, 0.0),
                normal: Vec3::NEG_Y,
                radius: 0.5,
                intensity: 1.0,
                outline: crate::scene::Outline::Disk,
            }
            .into(),
            objects: vec![
                object(
                    "ground",
                    shapes::plane().transformed(&Affine3A::from_scale(Vec3::splat(10.0))),
                ),
                object("sphere", shapes::sphere(16, 8)),
                object("tilted", shapes::plane().transformed(&tilt)),
                object("flipped", flipped),
            ],
        };
        let (r, warnings) = planar_receivers(&scene, scene.light.center());
        assert!(warnings.is_empty(), "{warnings:?}");
        let objects: Vec<usize> = r.iter().map(|r| r.object).collect();
        assert_eq!(objects, [0, 2, 3]);
        // Oriented toward the light.
        for p in &r {
            assert!(p.plane.dot(scene.light.center().extend(1.0)) > 0.0);
            assert!((p.plane.truncate().length() - 1.0).abs() < 1e-5);
        }
        let tilted = r[1].plane.truncate();
        assert!((tilted.dot(Vec3::Y) - 20f32.to_radians().cos()).abs() < 1e-4);
        // A light on the plane: refused with a warning.
        let (r, warnings) = planar_receivers(&scene, Vec3::new(3.0, 0.0, 0.0));
        assert!(r.iter().all(|p| p.object != 0));
        assert!(warnings[0].contains("'ground'"), "{warnings:?}");
    }
}
