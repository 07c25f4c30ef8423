//! The light view's tests: the fit against an exhaustive one, on the built-ins and on generated
//! families of scenes.

use super::*;
use crate::geometry::{PreparedCasters, VolumeParams};
use crate::scene::{shapes, AreaLight, Camera, LineLight, Mesh, Object};
use glam::{Affine3A, Quat};

/// The fit as it walks every vertex and triangle, with the axis over all of them: what
/// [`LightView::fit`] must equal where the axis takes every vertex.
fn fit_exhaustive(scene: &Scene) -> LightView {
    let light = scene.light;
    let vertices = || {
        scene
            .casters()
            .flat_map(|o| o.mesh.positions.iter().copied())
            .filter(|p| p.is_finite())
    };
    // Without a caster, a point in front of the light stands in for one.
    let stand_in = vertices()
        .next()
        .is_none()
        .then(|| light.center() + default_axis(&light));
    let casters = || vertices().chain(stand_in);
    let everything = || {
        scene
            .objects
            .iter()
            .flat_map(|o| o.mesh.positions.iter().copied())
            .filter(|p| p.is_finite())
    };
    let extrusion = crate::geometry::VolumeParams::for_scene(scene).far;
    // The near plane from the nearest point of any triangle (a large one passes much closer
    // to the light than its corners), less the light's half extent: the frustum is moved to
    // every point of the light (`sampled`, `linear-ssm`) and must not cut what they see.
    let c = light.center();
    let nearest = scene
        .objects
        .iter()
        .flat_map(|o| o.mesh.triangle_corners())
        .map(|t| (closest_on_triangle(c, t) - c).length())
        .filter(|d| d.is_finite())
        .fold(f32::MAX, f32::min)
        - light.half_extent();
    fit_directions_exhaustive(&light, casters, everything, extrusion, nearest)
}

/// `extrusion`: how far volumes reach beyond the casters. The far plane must hold them: an umbra
/// exit clipped away would count as "no exit" and lose the farthest-over-casters contest.
/// `nearest`: how close a surface comes to any point of the light (the near plane is half of it).
/// `casters` and `everything` are walked (twice and once) rather than collected: a mesh of
/// millions of vertices has 17 directions each (1.7 GB at 8M vertices if they were kept).
fn fit_directions_exhaustive<C, E>(
    light: &Light,
    casters: impl Fn() -> C,
    everything: impl Fn() -> E,
    extrusion: f32,
    nearest: f32,
) -> LightView
where
    C: Iterator<Item = Vec3>,
    E: Iterator<Item = Vec3>,
{
    let c = light.center();
    // The points of the light whose directions to a caster vertex bound its shadows: the disk's
    // rim (grown so the polygon covers the circle), a segment's two ends.
    let (extreme, normal): (Vec<Vec3>, Option<Vec3>) = match light {
        Light::Area(d) => {
            let (u, w) = d.basis();
            let grow = 1.0 / (std::f32::consts::PI / RIM_SAMPLES as f32).cos();
            let rim = (0..RIM_SAMPLES)
                .map(|k| {
                    let a = k as f32 / RIM_SAMPLES as f32 * std::f32::consts::TAU;
                    c + d.radius * grow * (a.cos() * u + a.sin() * w)
                })
                .collect();
            (rim, Some(d.normal))
        }
        Light::Line(l) => (vec![l.a, l.b], None),
    };
    // Every direction from the centre and the extreme points to a caster vertex in front of the
    // light; directions pointing behind the light plane cannot hold a lit receiver.
    let directions = || {
        casters()
            .filter(|&v| normal.is_none_or(|n| n.dot(v - c) > 0.0)) // behind the one-sided light: casts nothing
            .flat_map(|v| {
                std::iter::once(c)
                    .chain(extreme.iter().copied())
                    .filter_map(move |q| (v - q).try_normalize())
            })
            .filter(|d| normal.is_none_or(|n| d.dot(n) > 1e-4))
    };
    let fallback_axis = default_axis(light);
    let (sum, any) = directions().fold((Vec3::ZERO, false), |(s, _), d| (s + d, true));
    let axis = if any {
        sum.try_normalize().unwrap_or(fallback_axis)
    } else {
        fallback_axis
    };
    let up_hint = if axis.cross(Vec3::Y).length_squared() > 1e-6 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let view = Mat4::look_to_rh(c, axis, up_hint);
    let max_tan = MAX_HALF_ANGLE_DEG.to_radians().tan();
    let (mut l, mut r, mut b, mut t) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    let mut clipped = false;
    let fallback = (!any).then_some(fallback_axis);
    for d in directions().chain(fallback) {
        let p = view.transform_vector3(d);
        // Looking down −Z: slopes x/(−z), y/(−z).
        let depth = -p.z;
        let (sx, sy) = if depth > 1e-6 {
            (p.x / depth, p.y / depth)
        } else {
            (p.x.signum() * f32::MAX, p.y.signum() * f32::MAX)
        };
        let (cx, cy) = (sx.clamp(-max_tan, max_tan), sy.clamp(-max_tan, max_tan));
        clipped |= cx != sx || cy != sy;
        l = l.min(cx);
        r = r.max(cx);
        b = b.min(cy);
        t = t.max(cy);
    }
    // At least a tiny frustum, and a one-texel-ish margin.
    let pad = 0.01 * (r - l).max(t - b).max(1e-3);
    let (l, r, b, t) = (l - pad, r + pad, b - pad, t + pad);

    let farthest = everything()
        .map(|p| (p - c).length())
        .fold(0.0f32, f32::max);
    let far = (farthest * 2.0 + extrusion).max(1.0);
    let near = (nearest * 0.5).clamp(far * 1e-6, far * 1e-2).max(1e-4);
    LightView {
        view,
        projection: off_center_perspective(l, r, b, t, near, far),
        near,
        far,
        clipped,
    }
}

#[test]
fn closest_points_on_a_triangle() {
    let t = [Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0];
    let near = |p: Vec3, q: Vec3| (closest_on_triangle(p, t) - q).length() < 1e-6;
    assert!(
        near(Vec3::new(0.5, 3.0, 0.5), Vec3::new(0.5, 0.0, 0.5)),
        "inside"
    );
    assert!(near(Vec3::new(-1.0, 1.0, -1.0), Vec3::ZERO), "a corner");
    assert!(
        near(Vec3::new(1.0, -2.0, -3.0), Vec3::new(1.0, 0.0, 0.0)),
        "an edge"
    );
    assert!(
        near(Vec3::new(2.0, 0.0, 2.0), Vec3::new(1.0, 0.0, 1.0)),
        "the far edge"
    );
}

#[test]
fn off_center_perspective_maps_its_bounds() {
    let m = off_center_perspective(-0.5, 1.5, -1.0, 0.25, 0.1, 50.0);
    let corner = |sx: f32, sy: f32, d: f32| m.project_point3(Vec3::new(sx * d, sy * d, -d));
    let p = corner(-0.5, -1.0, 0.1);
    assert!((p - Vec3::new(-1.0, -1.0, 0.0)).length() < 1e-5, "{p}");
    let p = corner(1.5, 0.25, 50.0);
    assert!((p - Vec3::new(1.0, 1.0, 1.0)).length() < 1e-4, "{p}");
    let p = corner(0.5, -0.375, 3.0);
    assert!(
        p.x.abs() < 1e-5 && p.y.abs() < 1e-5 && p.z > 0.0 && p.z < 1.0,
        "{p}"
    );
}

/// Every penumbra point the twin finds on the ground must land inside the frustum.
#[test]
fn fitted_view_covers_every_penumbra_on_the_ground() {
    for name in crate::scene::builtin::names() {
        let Ok(scene) = crate::scene::load(name) else {
            panic!("{name} loads");
        };
        let view = LightView::fit(&scene);
        let vp = view.view_projection();
        let Some(disk) = scene.light.as_area() else {
            continue; // the D-buffer twin needs a disk
        };
        let geometry = PreparedCasters::new(&scene).build(disk, &VolumeParams::for_scene(&scene));
        let twin = crate::geometry::DBufferTwin::new(&scene, &geometry.casters);
        let mut shadowed = 0;
        for i in 0..60 {
            for j in 0..60 {
                let x = Vec3::new(-5.0 + i as f32 / 6.0, 0.0, -5.0 + j as f32 / 6.0);
                if twin.sample(x).branch == crate::geometry::Branch::Lit {
                    continue;
                }
                shadowed += 1;
                let ndc = vp.project_point3(x);
                assert!(
                    ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && (0.0..=1.0).contains(&ndc.z),
                    "{name}: shadowed ground point {x} falls outside the D-buffer ({ndc})"
                );
            }
        }
        assert!(shadowed > 0, "{name}: no shadow on the ground grid");
    }
}

/// SplitMix64 to `[0, 1)`.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next()
    }

    fn vec(&mut self, a: f32, b: f32) -> Vec3 {
        Vec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
    }
}

fn object(name: &str, mesh: Mesh, casts_shadow: bool) -> Object {
    Object {
        name: name.into(),
        mesh,
        casts_shadow,
    }
}

/// A generated scene: a ground, 1–4 casters (tessellated spheres, tori, boxes, vertex
/// soups), some reaching up to or past the light's plane, under a disk, rectangle, polygon
/// or segment of random size and tilt.
fn generated(seed: u64) -> Scene {
    let mut rng = Rng(seed);
    let mut objects = vec![object("ground", shapes::plane(), false)];
    let ground = Affine3A::from_scale(Vec3::splat(10.0));
    objects[0].mesh = objects[0].mesh.transformed(&ground);
    let casters = 1 + (rng.next() * 4.0) as usize;
    for k in 0..casters {
        let mesh = match (rng.next() * 4.0) as u32 {
            0 => shapes::sphere(
                8 + (rng.next() * 120.0) as u32,
                4 + (rng.next() * 60.0) as u32,
            ),
            1 => shapes::torus(
                8 + (rng.next() * 60.0) as u32,
                6 + (rng.next() * 20.0) as u32,
            ),
            2 => shapes::rounded_box(
                8 + (rng.next() * 40.0) as u32,
                4 + (rng.next() * 12.0) as u32,
            ),
            _ => {
                let n = 3 * (1 + (rng.next() * 3000.0) as usize);
                let positions: Vec<Vec3> = (0..n).map(|_| rng.vec(-1.0, 1.0)).collect();
                let triangles = (0..n as u32 / 3)
                    .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                    .collect();
                Mesh::new(positions, triangles)
            }
        };
        let place = Affine3A::from_scale_rotation_translation(
            Vec3::splat(rng.range(0.2, 1.5)),
            Quat::from_euler(
                glam::EulerRot::XYZ,
                rng.range(0.0, 6.3),
                rng.range(0.0, 6.3),
                0.0,
            ),
            Vec3::new(
                rng.range(-3.0, 3.0),
                rng.range(0.3, 4.5),
                rng.range(-3.0, 3.0),
            ),
        );
        objects.push(object(
            &format!("caster{k}"),
            mesh.transformed(&place),
            true,
        ));
    }
    let center = Vec3::new(
        rng.range(-2.0, 2.0),
        rng.range(4.0, 7.0),
        rng.range(-2.0, 2.0),
    );
    let normal = (Vec3::NEG_Y + rng.vec(-0.6, 0.6)).normalize();
    let size = rng.range(0.05, 3.0);
    let light: Light = match seed % 4 {
        0 => AreaLight::disk(center, normal, size).into(),
        1 => AreaLight::rect(center, normal, [size, 0.3 * size], None).into(),
        2 => {
            let (u, w) = AreaLight::disk(center, normal, size).basis();
            AreaLight::polygon(&[
                center + size * u,
                center + size * w,
                center - size * (u + w),
            ])
            .into()
        }
        _ => LineLight {
            a: center - size * Vec3::X,
            b: center + size * Vec3::new(1.0, 0.2, 0.3),
            intensity: 1.0,
        }
        .into(),
    };
    Scene {
        name: format!("generated-{seed}"),
        camera: Camera {
            eye: Vec3::new(0.0, 6.0, 9.0),
            target: Vec3::ZERO,
            fov_y_deg: 45.0,
        },
        light,
        objects,
    }
}

fn caster_vertices(scene: &Scene) -> usize {
    scene.casters().map(|o| o.mesh.positions.len()).sum()
}

/// Skipping boxes changes nothing: on 200 generated scenes with the axis over every vertex,
/// and on every built-in, the fit is the exhaustive fit bit for bit.
#[test]
fn the_fit_is_the_exhaustive_fit() {
    let mut skipped_any = false;
    for seed in 0..200 {
        let mut scene = generated(seed);
        if seed % 7 == 3 {
            // A vertex that is not a number, and one at infinity.
            if let Some(o) = scene.objects.get_mut(1) {
                o.mesh.positions[0] = Vec3::NAN;
                let last = o.mesh.positions.len() - 1;
                o.mesh.positions[last] = Vec3::splat(f32::INFINITY);
            }
        }
        assert!(caster_vertices(&scene) <= AXIS_VERTICES, "seed {seed}");
        assert_eq!(
            LightView::fit(&scene),
            fit_exhaustive(&scene),
            "seed {seed}"
        );
        skipped_any |= caster_vertices(&scene) > 4 * CHUNK;
    }
    assert!(skipped_any, "some scenes have boxes to skip");
    for name in crate::scene::builtin::names() {
        let scene = crate::scene::load(name).expect("a built-in loads");
        assert_eq!(LightView::fit(&scene), fit_exhaustive(&scene), "{name}");
    }
}

/// Over [`AXIS_VERTICES`] caster vertices the axis is strided, and the frustum still
/// covers every direction from the light to every caster vertex, and is close to the
/// exhaustive one (within 2 % in each slope's extent).
#[test]
fn a_large_caster_is_covered_with_a_strided_axis() {
    for seed in 0..4u64 {
        let mut scene = generated(1000 + seed);
        let big = shapes::sphere(400, 200).transformed(&Affine3A::from_scale_rotation_translation(
            Vec3::new(1.0, 0.6, 1.3),
            Quat::from_rotation_z(0.3 * seed as f32),
            Vec3::new(0.5, 2.0, -0.5),
        ));
        scene.objects.push(object("big", big, true));
        assert!(caster_vertices(&scene) > AXIS_VERTICES);
        let view = LightView::fit(&scene);
        let exhaustive = fit_exhaustive(&scene);
        let vp = view.view_projection();
        let c = scene.light.center();
        let sources: Vec<Vec3> = match &scene.light {
            Light::Area(_) => vec![c],
            Light::Line(l) => vec![l.a, l.b],
        };
        let mut seen = 0;
        for o in scene.casters() {
            for &v in &o.mesh.positions {
                for &q in &sources {
                    if scene
                        .light
                        .as_area()
                        .is_some_and(|a| a.normal.dot(v - q) <= 0.0)
                    {
                        continue;
                    }
                    // The direction from the light's centre towards the vertex, at depth.
                    let Some(d) = (v - q).try_normalize() else {
                        continue;
                    };
                    let p = vp.project_point3(c + d * (view.near * 2.0));
                    if exhaustive.clipped {
                        continue;
                    }
                    seen += 1;
                    assert!(
                        p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                        "seed {seed}: {v} outside the frustum ({p})"
                    );
                }
            }
        }
        assert!(seen > 0 || exhaustive.clipped);
        let extent = |m: Mat4| (2.0 / m.x_axis.x, 2.0 / m.y_axis.y);
        let (a, b) = (extent(view.projection), extent(exhaustive.projection));
        assert!(
            (a.0 / b.0 - 1.0).abs() < 0.02 && (a.1 / b.1 - 1.0).abs() < 0.02,
            "seed {seed}: extents {a:?} against {b:?}"
        );
        assert_eq!((view.near, view.far), (exhaustive.near, exhaustive.far));
    }
}

#[test]
fn strided_takes_every_stride_th_item_across_the_lists() {
    let mut rng = Rng(7);
    for _ in 0..200 {
        let lens: Vec<usize> = (0..1 + (rng.next() * 5.0) as usize)
            .map(|_| (rng.next() * 40.0) as usize)
            .collect();
        let stride = 1 + (rng.next() * 9.0) as usize;
        let flat: Vec<(usize, usize)> = lens
            .iter()
            .enumerate()
            .flat_map(|(k, &n)| (0..n).map(move |i| (k, i)))
            .collect();
        let expected: Vec<(usize, usize)> = flat.iter().copied().step_by(stride).collect();
        assert_eq!(
            strided(lens.iter().copied(), stride).collect::<Vec<_>>(),
            expected,
            "{lens:?} / {stride}"
        );
    }
}

/// Boxes made for other meshes (another count of vertices) are not trusted: the fit makes its
/// own.
#[test]
fn boxes_of_other_meshes_are_made_again() {
    let (a, b) = (generated(11), generated(12));
    assert_ne!(caster_vertices(&a), caster_vertices(&b));
    assert_eq!(
        LightView::fit_with(&b, &FitBoxes::new(&a)),
        LightView::fit(&b)
    );
    assert_eq!(
        LightView::fit_with(&b, &FitBoxes::default()),
        LightView::fit(&b)
    );
}
