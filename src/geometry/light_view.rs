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
    ///
    /// Every caster vertex's directions are covered. The work per call is kept off the mesh
    /// size where it can be without changing the result: the bounds, the far and the near
    /// plane skip each run of [`CHUNK`] vertices (triangles) whose bounding box cannot move
    /// them; only the axis — the mean direction, which the bounds then cover whatever it is —
    /// is taken over [`AXIS_SAMPLES`] caster vertices a fixed stride apart where there are more
    /// than [`AXIS_VERTICES`].
    pub fn fit(scene: &Scene) -> LightView {
        LightView::fit_with(scene, &FitBoxes::new(scene))
    }

    /// [`LightView::fit`] with the meshes' boxes made before (once per set of meshes: a light
    /// move then costs a few operations per box, not per vertex). Boxes of other meshes than
    /// `scene`'s (by their sizes) are made again here.
    pub fn fit_with(scene: &Scene, boxes: &FitBoxes) -> LightView {
        if !boxes.are_of(scene) {
            return LightView::fit(scene);
        }
        let light = scene.light;
        let c = light.center();
        let casters: Vec<Chunked<'_>> = scene
            .objects
            .iter()
            .zip(&boxes.objects)
            .filter(|(o, _)| o.casts_shadow)
            .map(|(o, b)| Chunked {
                points: &o.mesh.positions,
                boxes: &b.points,
            })
            .collect();
        // Without a caster, a point in front of the light stands in for one.
        let stand_in = [c + default_axis(&light)];
        let stand_in_box = [Some((stand_in[0], stand_in[0]))];
        let casters = if casters.iter().any(|k| k.boxes.iter().any(Option::is_some)) {
            casters
        } else {
            vec![Chunked {
                points: &stand_in,
                boxes: &stand_in_box,
            }]
        };
        let extrusion = crate::geometry::VolumeParams::for_scene(scene).far;
        // The near plane from the nearest point of any triangle (a large one passes much closer
        // to the light than its corners), less the light's half extent: the frustum is moved to
        // every point of the light (`sampled`, `linear-ssm`) and must not cut what they see.
        let nearest = nearest_surface(c, scene, boxes) - light.half_extent();
        let farthest = farthest_point(c, scene, boxes);
        fit_directions(&light, &casters, farthest, extrusion, nearest)
    }
}

/// An axis-aligned box, `(min, max)`.
type Box3 = (Vec3, Vec3);

/// The bounding boxes of a scene's meshes, [`CHUNK`] vertices (and triangles) at a time, for
/// [`LightView::fit_with`]: made once per set of meshes, in one pass over them.
#[derive(Clone, Debug, Default)]
pub struct FitBoxes {
    objects: Vec<MeshBoxes>,
}

#[derive(Clone, Debug)]
struct MeshBoxes {
    vertices: usize,
    triangles: usize,
    /// Per run of vertices, the box of its finite ones (`None`: none is).
    points: Vec<Option<Box3>>,
    /// Per run of triangles, the box of their finite corners.
    faces: Vec<Option<Box3>>,
}

impl FitBoxes {
    pub fn new(scene: &Scene) -> FitBoxes {
        let objects = scene
            .objects
            .iter()
            .map(|o| {
                let mesh = &o.mesh;
                MeshBoxes {
                    vertices: mesh.positions.len(),
                    triangles: mesh.triangles.len(),
                    points: mesh
                        .positions
                        .chunks(CHUNK)
                        .map(|chunk| finite_box(chunk.iter().copied()))
                        .collect(),
                    faces: mesh
                        .triangles
                        .chunks(CHUNK)
                        .map(|chunk| finite_box(chunk.iter().flat_map(|t| corners_of(mesh, t))))
                        .collect(),
                }
            })
            .collect();
        FitBoxes { objects }
    }

    /// Whether these are, by their sizes, the boxes of `scene`'s meshes.
    fn are_of(&self, scene: &Scene) -> bool {
        self.objects.len() == scene.objects.len()
            && self.objects.iter().zip(&scene.objects).all(|(b, o)| {
                b.vertices == o.mesh.positions.len() && b.triangles == o.mesh.triangles.len()
            })
    }
}

/// Every `stride`-th item (from the first) of lists of the lengths `lens` taken as one list, as
/// (list, index in it).
fn strided(
    lens: impl Iterator<Item = usize>,
    stride: usize,
) -> impl Iterator<Item = (usize, usize)> {
    let stride = stride.max(1);
    lens.enumerate()
        .scan(0usize, move |skip, (k, len)| {
            // `skip`: where the stride's next item lies in this list.
            let first = *skip;
            *skip = if first >= len {
                first - len
            } else {
                first + (len - first).div_ceil(stride) * stride - len
            };
            Some((k, first, len))
        })
        .flat_map(move |(k, first, len)| (first..len).step_by(stride).map(move |i| (k, i)))
}

/// A caster's vertices and their boxes, [`CHUNK`] to a box.
struct Chunked<'a> {
    points: &'a [Vec3],
    boxes: &'a [Option<Box3>],
}

/// The corners of triangle `t` of `mesh` (NaN for an index out of range).
fn corners_of(mesh: &crate::scene::Mesh, t: &[u32; 3]) -> [Vec3; 3] {
    let p = |i: u32| mesh.positions.get(i as usize).copied().unwrap_or(Vec3::NAN);
    [p(t[0]), p(t[1]), p(t[2])]
}

/// Caster vertices up to which the frustum's axis is averaged over every one of them.
pub const AXIS_VERTICES: usize = 1 << 16;

/// Caster vertices the axis is averaged over above [`AXIS_VERTICES`], a fixed stride apart: the
/// mean direction of a million vertices is the mean of a few thousand spread evenly among them
/// to well under a texel, and the bounds still cover all of them.
pub const AXIS_SAMPLES: usize = 1 << 12;

/// Vertices (or triangles) per bounding box when [`LightView::fit`] skips what cannot change
/// its result.
pub const CHUNK: usize = 256;

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

/// The bounding box of the finite points among `points` (`None` if none is).
fn finite_box(points: impl Iterator<Item = Vec3>) -> Option<(Vec3, Vec3)> {
    points.filter(|p| p.is_finite()).fold(None, |b, p| match b {
        None => Some((p, p)),
        Some((lo, hi)) => Some((lo.min(p), hi.max(p))),
    })
}

/// The eight corners of a box.
fn corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|k| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// A margin that float rounding of a point's own computation cannot cross, for values of the
/// size `scale`.
fn margin(scale: f32) -> f32 {
    1e-4 * (1.0 + scale.abs())
}

/// How far the farthest finite vertex of any object is from `c`.
fn farthest_point(c: Vec3, scene: &Scene, boxes: &FitBoxes) -> f32 {
    let mut farthest = 0.0f32;
    for (o, b) in scene.objects.iter().zip(&boxes.objects) {
        for (chunk, b) in o.mesh.positions.chunks(CHUNK).zip(&b.points) {
            let Some(b) = *b else {
                continue;
            };
            let reach = corners(b)
                .iter()
                .map(|&k| (k - c).length())
                .fold(0.0f32, f32::max);
            if reach.is_finite() && reach + margin(reach) <= farthest {
                continue; // no vertex in the box is farther than what was found
            }
            farthest = chunk
                .iter()
                .filter(|p| p.is_finite())
                .map(|&p| (p - c).length())
                .fold(farthest, f32::max);
        }
    }
    farthest
}

/// How close any (finite) triangle of any object comes to `c`; `f32::MAX` with none.
fn nearest_surface(c: Vec3, scene: &Scene, boxes: &FitBoxes) -> f32 {
    let mut nearest = f32::MAX;
    for (o, b) in scene.objects.iter().zip(&boxes.objects) {
        let mesh = &o.mesh;
        for (chunk, b) in mesh.triangles.chunks(CHUNK).zip(&b.faces) {
            let Some((lo, hi)) = *b else {
                continue;
            };
            // The box holds every finite corner, so every finite triangle: none is nearer.
            let below = (c.clamp(lo, hi) - c).length();
            let scale = c.abs().max(lo.abs()).max(hi.abs()).max_element();
            if below.is_finite() && below - margin(scale) >= nearest {
                continue;
            }
            nearest = chunk
                .iter()
                .map(|t| (closest_on_triangle(c, corners_of(mesh, t)) - c).length())
                .filter(|d| d.is_finite())
                .fold(nearest, f32::min);
        }
    }
    nearest
}

/// The frustum's slopes `[l, r] × [b, t]` as directions are added, and whether any was clipped.
struct Bounds {
    l: f32,
    r: f32,
    b: f32,
    t: f32,
    clipped: bool,
    max_tan: f32,
}

impl Bounds {
    fn new() -> Bounds {
        Bounds {
            l: f32::MAX,
            r: f32::MIN,
            b: f32::MAX,
            t: f32::MIN,
            clipped: false,
            max_tan: MAX_HALF_ANGLE_DEG.to_radians().tan(),
        }
    }

    /// Add the direction `d` (unit length), seen through `view`.
    fn add(&mut self, view: &Mat4, d: Vec3) {
        let p = view.transform_vector3(d);
        // Looking down −Z: slopes x/(−z), y/(−z).
        let depth = -p.z;
        let (sx, sy) = if depth > 1e-6 {
            (p.x / depth, p.y / depth)
        } else {
            (p.x.signum() * f32::MAX, p.y.signum() * f32::MAX)
        };
        let max_tan = self.max_tan;
        let (cx, cy) = (sx.clamp(-max_tan, max_tan), sy.clamp(-max_tan, max_tan));
        self.clipped |= cx != sx || cy != sy;
        self.l = self.l.min(cx);
        self.r = self.r.max(cx);
        self.b = self.b.min(cy);
        self.t = self.t.max(cy);
    }

    /// Whether the slopes `range` (`[min x, max x, min y, max y]`) lie inside the bounds by a
    /// margin rounding cannot cross: adding their directions changes nothing.
    fn hold(&self, range: [f32; 4]) -> bool {
        if self.l > self.r || self.b > self.t {
            return false;
        }
        let m = margin(
            self.l
                .abs()
                .max(self.r.abs())
                .max(self.b.abs())
                .max(self.t.abs()),
        );
        range[0] >= self.l + m
            && range[1] <= self.r - m
            && range[2] >= self.b + m
            && range[3] <= self.t - m
    }
}

/// The slopes (`[min x, max x, min y, max y]`) of every direction from any of `sources` to any
/// point of the box `b` seen through `view`, where all lie well in front of it: the directions
/// to a box lie in front where its corners' do (a cone), and a slope over them is largest at a
/// corner. `None` where some corner's direction does not.
fn box_slopes(view: &Mat4, sources: &[Vec3], b: (Vec3, Vec3)) -> Option<[f32; 4]> {
    let mut range = [f32::MAX, f32::MIN, f32::MAX, f32::MIN];
    for k in corners(b) {
        for &q in sources {
            let d = k - q;
            let p = view.transform_vector3(d);
            let depth = -p.z;
            // (A NaN depth fails too.)
            if depth.partial_cmp(&(1e-3 * d.length())) != Some(std::cmp::Ordering::Greater) {
                return None;
            }
            let (sx, sy) = (p.x / depth, p.y / depth);
            range = [
                range[0].min(sx),
                range[1].max(sx),
                range[2].min(sy),
                range[3].max(sy),
            ];
        }
    }
    Some(range)
}

/// `extrusion`: how far volumes reach beyond the casters. The far plane must hold them: an umbra
/// exit clipped away would count as "no exit" and lose the farthest-over-casters contest.
/// `nearest`: how close a surface comes to any point of the light (the near plane is half of it);
/// `farthest`: how far the farthest point of the scene is from its centre.
fn fit_directions(
    light: &Light,
    casters: &[Chunked<'_>],
    farthest: f32,
    extrusion: f32,
    nearest: f32,
) -> LightView {
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
    let sources: Vec<Vec3> = std::iter::once(c).chain(extreme.iter().copied()).collect();
    // Every direction from the centre and the extreme points to a caster vertex in front of the
    // light; directions pointing behind the light plane cannot hold a lit receiver.
    let from = sources.as_slice();
    let directions = move |v: Vec3| {
        normal
            .is_none_or(|n| n.dot(v - c) > 0.0) // behind the one-sided light: casts nothing
            .then_some(())
            .into_iter()
            .flat_map(move |_| from.iter().filter_map(move |&q| (v - q).try_normalize()))
            .filter(move |d| normal.is_none_or(|n| d.dot(n) > 1e-4))
    };
    // The axis over every caster vertex up to `AXIS_VERTICES`, else over `AXIS_SAMPLES` of
    // them a stride apart, counted through the casters as one list.
    let count: usize = casters.iter().map(|k| k.points.len()).sum();
    let stride = if count <= AXIS_VERTICES {
        1
    } else {
        count.div_ceil(AXIS_SAMPLES)
    };
    let mut sum = Vec3::ZERO;
    let mut any = false;
    for (k, i) in strided(casters.iter().map(|k| k.points.len()), stride) {
        let v = casters[k].points[i];
        if v.is_finite() {
            for d in directions(v) {
                sum += d;
                any = true;
            }
        }
    }
    let fallback_axis = default_axis(light);
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
    // The bounds, chunk by chunk: each chunk's box gives its slopes' range; the four chunks
    // reaching farthest are walked first, so the bounds are about whole before the rest are
    // tested, and a chunk whose range they hold is skipped. (Walked in any order, the bounds
    // come out the same.)
    let chunks: Vec<(&[Vec3], Option<[f32; 4]>)> = casters
        .iter()
        .flat_map(|k| k.points.chunks(CHUNK).zip(k.boxes))
        .filter_map(|(chunk, b)| Some((chunk, box_slopes(&view, &sources, (*b)?))))
        .collect();
    let reach = |side: usize| {
        let sign = if side.is_multiple_of(2) { -1.0 } else { 1.0 };
        (0..chunks.len()).max_by(|&i, &j| {
            let v = |k: usize| chunks[k].1.map_or(f32::MAX, |r| sign * r[side]);
            v(i).total_cmp(&v(j))
        })
    };
    let first: Vec<usize> = (0..4).filter_map(reach).collect();
    let mut bounds = Bounds::new();
    let walk = |bounds: &mut Bounds, chunk: &[Vec3]| {
        for &v in chunk.iter().filter(|p| p.is_finite()) {
            for d in directions(v) {
                bounds.add(&view, d);
            }
        }
    };
    for &i in &first {
        walk(&mut bounds, chunks[i].0);
    }
    for (i, (chunk, range)) in chunks.iter().enumerate() {
        if first.contains(&i) || range.is_some_and(|r| bounds.hold(r)) {
            continue;
        }
        walk(&mut bounds, chunk);
    }
    if bounds.l > bounds.r {
        // No direction at all: the light's own axis.
        bounds.add(&view, fallback_axis);
    }
    let Bounds {
        l,
        r,
        b,
        t,
        clipped,
        ..
    } = bounds;
    // At least a tiny frustum, and a one-texel-ish margin.
    let pad = 0.01 * (r - l).max(t - b).max(1e-3);
    let (l, r, b, t) = (l - pad, r + pad, b - pad, t + pad);

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
mod tests;
