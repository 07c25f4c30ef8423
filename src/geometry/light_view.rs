//! The D-buffer's view from the light centre: a perspective frustum fitted to where the casters'
//! penumbrae can be, so texels are spent where shadows fall (docs/method/dbuffer.md#the-d-buffer, "fit it to their
//! bounds").
//!
//! A line light's view looks from its midpoint, fitted the same way with the segment's two end
//! points in place of the rim (a point in any segment point's shadow of a caster vertex `v` lies
//! in the cone of `v − a` and `v − b`); its axis is the mean of those directions, since a line
//! has no normal and emits all around.
//!
//! A point in a caster's penumbra sees some disk point `q` through the caster, so it lies on a ray
//! `v + s(v − q)` from a caster point `v` away from a rim point. Seen from `c`, such points lie in
//! the cone spanned by the directions `v − c` and, for far points, `v − q`. The frustum is fitted
//! to those directions over every caster vertex and rim samples (grown slightly so the polygon of
//! samples covers the circle).

use glam::{Mat4, Vec3};

use crate::scene::{Light, Scene};

/// The largest angle between the frustum axis and a direction it must cover. Wider penumbrae are
/// clipped to it (and reported), since a perspective projection cannot reach 90°.
pub const MAX_HALF_ANGLE_DEG: f32 = 80.0;

/// The light-view camera of the D-buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    pub view: Mat4,
    pub projection: Mat4,
    pub near: f32,
    pub far: f32,
    /// Some directions of the casters' penumbrae fall outside [`MAX_HALF_ANGLE_DEG`].
    pub clipped: bool,
}

impl LightView {
    pub fn view_projection(&self) -> Mat4 {
        self.projection * self.view
    }

    /// The slope (tangent) one texel of a `size`² map spans, the larger of its two axes.
    pub fn texel_slope(&self, size: u32) -> f32 {
        let w = 2.0 / self.projection.x_axis.x;
        let h = 2.0 / self.projection.y_axis.y;
        w.abs().max(h.abs()) / size.max(1) as f32
    }

    /// Fit to the scene's casters; with no caster, a 90° cone around the light normal.
    pub fn fit(scene: &Scene) -> LightView {
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
        fit_directions(&light, casters, everything, extrusion, nearest)
    }
}

/// Number of rim samples; the sample polygon is grown by `1/cos(π/n)` to cover the circle.
const RIM_SAMPLES: usize = 16;

/// The axis of a view with nothing to fit: the disk's normal; straight down for a line (or,
/// for a vertical line, along +X).
fn default_axis(light: &Light) -> Vec3 {
    match light {
        Light::Area(d) => d.normal,
        Light::Line(l) => {
            let along = (l.b - l.a).normalize_or_zero();
            (Vec3::NEG_Y - along * along.dot(Vec3::NEG_Y))
                .try_normalize()
                .unwrap_or(Vec3::X)
        }
    }
}

/// `extrusion`: how far volumes reach beyond the casters. The far plane must hold them: an umbra
/// exit clipped away would count as "no exit" and lose the farthest-over-casters contest.
/// `nearest`: how close a surface comes to any point of the light (the near plane is half of it).
/// `casters` and `everything` are walked (twice and once) rather than collected: a mesh of
/// millions of vertices has 17 directions each (1.7 GB at 8M vertices if they were kept).
fn fit_directions<C, E>(
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

/// The point of triangle `t` nearest `p` (Ericson, Real-Time Collision Detection §5.1.5).
fn closest_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom.abs() < f32::MIN_POSITIVE {
        return a; // a degenerate triangle: its corner will do
    }
    a + ab * (vb / denom) + ac * (vc / denom)
}

/// A right-handed perspective looking down −Z with the image spanning slopes `[l, r] × [b, t]`,
/// depth 0 at `near` and 1 at `far` (wgpu's clip space).
pub fn off_center_perspective(l: f32, r: f32, b: f32, t: f32, near: f32, far: f32) -> Mat4 {
    let (w, h) = (r - l, t - b);
    let z = far / (near - far);
    Mat4::from_cols(
        glam::Vec4::new(2.0 / w, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, 2.0 / h, 0.0, 0.0),
        glam::Vec4::new((r + l) / w, (t + b) / h, z, -1.0),
        glam::Vec4::new(0.0, 0.0, near * z, 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{PreparedCasters, VolumeParams};

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
            let geometry =
                PreparedCasters::new(&scene).build(disk, &VolumeParams::for_scene(&scene));
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
}
