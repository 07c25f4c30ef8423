//! The casters' shadow volumes as the D-buffer's light pass draws them: each volume triangle's
//! vertices with what `|cx_s|` needs ([`volume_vertices`]), the volumes ended where no receiver
//! lies beyond ([`end_at`]), ordered nearest the light first ([`sort_near_first`]), and the part of
//! the light view they can cover ([`light_view_rect`]), all of it per frame in [`drawn_volumes`];
//! and the fill they cost the rasteriser ([`footprint_texels`]). Plain CPU geometry: the render
//! method (`render::methods::dbuffer`) uploads what these return, `dbuffer inspect` reports their
//! fill, and the tests reach them here.

use glam::{Vec3, Vec4};

use super::light_view::LightView;
use super::volumes::CasterGeometry;
use super::SceneGeometry;
use crate::scene::AreaLight;

/// The vertex of a shadow-volume triangle the light pass draws: position, kind, and what
/// `|cx_s|` needs — the height below the light's plane of the edge point the fragment was
/// extruded from, as `base + num / den` with `num` and `den` affine over the triangle (so
/// interpolating them is exact; see [`volume_vertices`]). Which way a ray crosses the triangle is
/// its winding, which the pipelines' culling reads. Laid out for the GPU (`render::VolumeVertex`
/// is this type, with its vertex-buffer layout); not [`super::volumes::VolumeVertex`], the
/// geometry stage's record of where a volume vertex came from.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VolumeVertex {
    pub position: [f32; 3],
    pub kind: u32,
    pub base: f32,
    pub num: f32,
    pub den: f32,
    /// The triangle's lit side in the light's plane ([`lit_side`]): where the light a receiver
    /// behind it sees lies, which `V exact` of a polygon light needs (a disk's is the same
    /// whichever way the chord runs).
    pub side: [f32; 2],
}

/// The direction, in the light's plane (coordinates in [`AreaLight::basis`]), from the part of
/// the light a volume triangle's caster hides toward the part it leaves: the triangle's outward
/// normal (both volumes are wound outward) projected onto the plane. Across a penumbra's outer
/// wall the caster is on the inner side and the light it leaves is beyond; across an umbra's
/// wall, likewise toward the penumbra. The chord a receiver's `t` stands for runs across it, so
/// `V exact` is the share of the light beyond the chord toward this side
/// (`geometry::outline::Outline2d::fraction_beyond`). Zero for a triangle parallel to the plane.
pub fn lit_side(corners: [Vec3; 3], light: &AreaLight) -> [f32; 2] {
    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let (u, w) = light.basis();
    let m = glam::Vec2::new(n.dot(u), n.dot(w));
    m.try_normalize().unwrap_or(glam::Vec2::ZERO).to_array()
}

/// The caster's volume triangles as GPU vertices, umbra and penumbra apart (their winding says
/// which way a ray crosses them).
///
/// `|cx_s|` (eq. 2 in words) needs the height `h` below the light's plane of the edge point `e`
/// a fragment `q` was extruded from: `e` is where the line from the extrusion point `p` through
/// `q` meets the edge (the CPU twin finds it as the closest point of the two lines). On the quad's
/// plane `q = p + μ(e − p)`; for any `w` across the edge, `μ = (q − p)·w / (a − p)·w` is affine in
/// `q`, so `h = (p − c)·n + ((q − p)·n) ((a − p)·w) / ((q − p)·w)` is `base + num/den` with `num`
/// and `den` affine over the triangle: their vertex values interpolate exactly, and the fragment
/// shader does one division instead of solving for `e`. A fan (its edge is its apex) and an edge
/// its extrusion point lies on have a constant `h`.
pub fn volume_vertices(
    g: &CasterGeometry,
    light: &AreaLight,
) -> (Vec<VolumeVertex>, Vec<VolumeVertex>) {
    volume_vertices_within(g, light, None, None, 0)
}

/// Texels of the D-buffer's corner texture a corner takes: the apex, the two edges' far ends,
/// the two faces' normals of each edge and the two extrusion points ([`super::FanCorner`]).
pub const TEXELS_PER_CORNER: usize = 9;

/// Corners to a row of the D-buffer's corner texture: 2,016 texels, within the smallest largest
/// texture a device has (WebGL2's 2048).
pub const CORNERS_PER_ROW: usize = 224;

/// The most corners the texture holds: 2048 rows, the smallest largest texture a device has
/// (WebGL2's). Every whole number below it is exact in an `f32`.
pub const MAX_CORNERS: usize = CORNERS_PER_ROW * 2048;

/// The `side` a closing fan's triangles carry instead of their lit side:
/// `-(2 + k)`, `k` the fan's corner in the scene's table (`corner_base` plus its index in the
/// caster's [`VolumeMesh::corners`]), which no unit vector's `x` can be. `None` past
/// [`MAX_CORNERS`]: the lit side then (the chord's V).
///
/// [`VolumeMesh::corners`]: super::VolumeMesh::corners
pub fn corner_marker(k: usize) -> Option<[f32; 2]> {
    (k < MAX_CORNERS).then(|| [-(2.0 + k as f32), 0.0])
}

/// [`volume_vertices`], each volume ended at its reach when one is given ([`end_at`]), made in
/// one pass: no full copy of a volume is held besides the one returned.
///
/// A closing fan's triangles carry their corner's marker
/// ([`corner_marker`], the caster's corners numbered from `corner_base`).
pub fn volume_vertices_within(
    g: &CasterGeometry,
    light: &AreaLight,
    umbra_reach: Option<f32>,
    penumbra_reach: Option<f32>,
    corner_base: usize,
) -> (Vec<VolumeVertex>, Vec<VolumeVertex>) {
    let (c, n) = (light.center, light.normal);
    let triangles = g.volumes.triangle_count();
    let umbrae = (0..triangles)
        .filter(|&i| g.volumes.triangle(i).1.kind.is_umbra())
        .count();
    let (mut umbra, mut penumbra) = (
        Vec::with_capacity(3 * umbrae),
        Vec::with_capacity(3 * (triangles - umbrae)),
    );
    for i in 0..triangles {
        let (corners, attrs) = g.volumes.triangle(i);
        let [a, b] = attrs.edge;
        let p = attrs.extrusion;
        let along = (b - a).normalize_or_zero();
        let w = (p - a) - along * (p - a).dot(along);
        let ratio = w.length_squared() > 1e-12 * (p - a).length_squared().max(1e-30);
        let (out, reach) = if attrs.kind.is_umbra() {
            (&mut umbra, umbra_reach)
        } else {
            (&mut penumbra, penumbra_reach)
        };
        // Only a corner V exact may be taken from: the others keep their lit side (the chord's V).
        let marker = g
            .volumes
            .corner_index(i)
            .filter(|&k| g.volumes.corners[k].exact)
            .and_then(|k| corner_marker(corner_base + k));
        let side = marker.unwrap_or_else(|| lit_side(corners, light));
        let t = corners.map(|q| {
            let (base, num, den) = if ratio {
                let k = (a - p).dot(w);
                ((p - c).dot(n), (q - p).dot(n) * k, (q - p).dot(w))
            } else {
                ((a - c).dot(n), 0.0, 1.0)
            };
            VolumeVertex {
                position: q.to_array(),
                kind: attrs.kind.code(),
                base,
                num,
                den,
                side,
            }
        });
        match reach {
            Some(r) => clip_into(t, light, r, out),
            None => out.extend(t),
        }
    }
    (umbra, penumbra)
}

/// The parts of volume triangles whose height below the light's plane is at most `reach`.
///
/// Along a ray from `c` the height grows with the distance, so a volume crossing beyond the
/// greatest height of any surface lies behind every receiver on its ray: a penumbra entry there
/// is never looked up (only points visible from `c` read that channel), and an umbra exit there
/// reads as "no exit", which is what a receiver in front of it must get anyway. The extruded
/// quads would otherwise run on to the far plane, and most of their fragments would be
/// rasterised only to die behind the ground. (Not for umbrae merged over casters: there a
/// caster's missing exit would let another caster's win.)
pub fn end_at(volume: &[VolumeVertex], light: &AreaLight, reach: f32) -> Vec<VolumeVertex> {
    let mut out = Vec::with_capacity(volume.len());
    for t in volume.chunks_exact(3) {
        clip_into([t[0], t[1], t[2]], light, reach, &mut out);
    }
    out
}

/// Append the part of triangle `t` whose height below the light's plane is at most `reach`
/// (none, all of it, a triangle or a quad as two) to `out`.
fn clip_into(t: [VolumeVertex; 3], light: &AreaLight, reach: f32, out: &mut Vec<VolumeVertex>) {
    let height = |v: &VolumeVertex| light.height_of(Vec3::from(v.position)) - reach;
    let h = [height(&t[0]), height(&t[1]), height(&t[2])];
    if h.iter().all(|&x| x <= 0.0) {
        out.extend_from_slice(&t);
        return;
    }
    if h.iter().all(|&x| x > 0.0) {
        return;
    }
    // Walk the edges, keeping inside corners and the crossings (Sutherland–Hodgman, one
    // plane); num and den are affine, so they interpolate exactly.
    let mut poly: [VolumeVertex; 4] = [t[0]; 4];
    let mut n = 0;
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let (hp, hq) = (h[k], h[(k + 1) % 3]);
        if hp <= 0.0 {
            poly[n] = p;
            n += 1;
        }
        if (hp <= 0.0) != (hq <= 0.0) {
            let s = hp / (hp - hq);
            let lerp = |a: f32, b: f32| a + (b - a) * s;
            let (pp, qp) = (Vec3::from(p.position), Vec3::from(q.position));
            poly[n] = VolumeVertex {
                position: (pp + (qp - pp) * s).to_array(),
                num: lerp(p.num, q.num),
                den: lerp(p.den, q.den),
                ..t[0]
            };
            n += 1;
        }
    }
    for k in 1..n.saturating_sub(1) {
        out.extend([poly[0], poly[k], poly[k + 1]]);
    }
}

/// Reorder the triangles of `volume` by the distance of their centroid from `c`, nearest first.
pub fn sort_near_first(volume: &mut [VolumeVertex], c: Vec3) {
    // In place, by whole triangles (no copy: a 1.4M-triangle volume is 118 MB).
    let whole = volume.len() / 3 * 3;
    let tris: &mut [[VolumeVertex; 3]] = bytemuck::cast_slice_mut(&mut volume[..whole]);
    let key = |t: &[VolumeVertex; 3]| {
        let centroid = t.iter().map(|v| Vec3::from(v.position)).sum::<Vec3>() / 3.0;
        (centroid - c).length_squared()
    };
    tris.sort_unstable_by(|a, b| key(a).total_cmp(&key(b)));
}

/// How far below the light's plane the surfaces within `bounds` (an axis-aligned box) reach, a
/// little beyond: where the volumes may end ([`end_at`]); `f32::MAX` when that is not finite.
pub fn reach_below(light: &AreaLight, (lo, hi): (Vec3, Vec3)) -> f32 {
    let reach = (0..8)
        .map(|k| {
            let corner = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            light.height_of(corner)
        })
        .fold(0.0f32, f32::max);
    if reach.is_finite() {
        reach * 1.01 + 1e-3
    } else {
        f32::MAX
    }
}

/// The volumes as the D-buffer's light pass draws them.
#[derive(Clone, Debug, Default)]
pub struct DrawnVolumes {
    /// Per caster: its umbra, and the part of the light view's image it can cover.
    pub umbrae: Vec<(Vec<VolumeVertex>, [f32; 4])>,
    /// Every caster's penumbra, drawn together.
    pub penumbra: Vec<VolumeVertex>,
}

/// Every caster's volumes ready to draw: ended at `reach` ([`reach_below`]; `None`: whole, to
/// the extrusion's far end), nearest the light first, with the rectangles of the light view
/// they can cover. An umbra ends too only where no other caster's umbra overlaps its rectangle
/// ([`disjoint_groups`]: merged umbrae need every caster's exits).
pub fn drawn_volumes(
    geometry: &SceneGeometry,
    light: &AreaLight,
    view: &LightView,
    reach: Option<f32>,
) -> DrawnVolumes {
    // Each caster's umbra rectangle (from its volume's corners, before any ending), to know
    // whether umbrae are merged over casters.
    let rects: Vec<[f32; 4]> = geometry
        .casters
        .iter()
        .map(|g| {
            let corners = (0..g.volumes.triangle_count())
                .map(|i| g.volumes.triangle(i))
                .filter(|(_, attrs)| attrs.kind.is_umbra())
                .flat_map(|(corners, _)| corners);
            light_view_rect(view, corners)
        })
        .collect();
    let merged = disjoint_groups(&rects).len() > 1;
    let umbra_reach = reach.filter(|_| !merged);
    let mut penumbra = Vec::new();
    let mut corner_base = 0;
    let umbrae = geometry
        .casters
        .iter()
        .zip(rects)
        .map(|(g, rect)| {
            let (mut umbra, pen) =
                volume_vertices_within(g, light, umbra_reach, reach, corner_base);
            corner_base += g.volumes.corners.len();
            penumbra.extend(pen);
            // Nearest first: the depth test then turns the farther crossings away before
            // shading.
            sort_near_first(&mut umbra, light.center);
            (umbra, rect)
        })
        .collect();
    sort_near_first(&mut penumbra, light.center);
    DrawnVolumes { umbrae, penumbra }
}

/// Groups of casters whose umbra rectangles do not overlap (greedy, in order), with the
/// rectangle each group covers; casters whose rectangle is empty belong to none.
pub fn disjoint_groups(rects: &[[f32; 4]]) -> Vec<(Vec<usize>, [f32; 4])> {
    let overlap =
        |a: [f32; 4], b: [f32; 4]| a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
    let mut groups: Vec<(Vec<usize>, Vec<[f32; 4]>)> = Vec::new();
    for (i, &rect) in rects.iter().enumerate() {
        if !(rect[0] < rect[2] && rect[1] < rect[3]) {
            continue;
        }
        match groups
            .iter_mut()
            .find(|(_, rs)| rs.iter().all(|r| !overlap(*r, rect)))
        {
            Some(g) => {
                g.0.push(i);
                g.1.push(rect);
            }
            None => groups.push((vec![i], vec![rect])),
        }
    }
    groups
        .into_iter()
        .map(|(members, rs)| (members, union_all(rs)))
        .collect()
}

/// The bounding rectangle of `rects` (a point is the rectangle `[u, v, u, v]`).
pub fn union_all(rects: impl IntoIterator<Item = [f32; 4]>) -> [f32; 4] {
    rects.into_iter().fold([1.0f32, 1.0, 0.0, 0.0], |h, r| {
        [
            h[0].min(r[0]),
            h[1].min(r[1]),
            h[2].max(r[2]),
            h[3].max(r[3]),
        ]
    })
}

/// The texels of a `size`² map of `view` that the triangles of `volume` cover, each triangle
/// over its whole footprint inside the view (clipped to it; overlaps counted as often as they
/// overlap, no depth test): the fragments the rasteriser makes for them. Divided by `size`², the
/// volumes' fill per texel.
pub fn footprint_texels(volume: &[VolumeVertex], view: &LightView, size: u32) -> f64 {
    let vp = view.view_projection();
    let half = f64::from(size) / 2.0;
    volume
        .chunks_exact(3)
        .map(|t| {
            let clip = [t[0], t[1], t[2]].map(|v| vp * Vec3::from(v.position).extend(1.0));
            clipped_area_ndc(&clip) * half * half
        })
        .filter(|a| a.is_finite())
        .sum()
}

/// The area in normalised device coordinates of a clip-space triangle's part inside the view
/// volume (`-w ≤ x, y ≤ w`, `0 ≤ z ≤ w`, `w > 0`).
fn clipped_area_ndc(triangle: &[Vec4; 3]) -> f64 {
    let planes: [fn(Vec4) -> f32; 7] = [
        |p| p.w + p.x,
        |p| p.w - p.x,
        |p| p.w + p.y,
        |p| p.w - p.y,
        |p| p.z,
        |p| p.w - p.z,
        |p| p.w - 1e-6,
    ];
    let mut poly: Vec<Vec4> = triangle.to_vec();
    for plane in planes {
        let mut next = Vec::with_capacity(poly.len() + 1);
        for (k, &p) in poly.iter().enumerate() {
            let q = poly[(k + 1) % poly.len()];
            let (dp, dq) = (plane(p), plane(q));
            if dp >= 0.0 {
                next.push(p);
            }
            if (dp >= 0.0) != (dq >= 0.0) {
                next.push(p + (q - p) * (dp / (dp - dq)));
            }
        }
        poly = next;
        if poly.len() < 3 {
            return 0.0;
        }
    }
    let xy: Vec<(f64, f64)> = poly
        .iter()
        .map(|p| (f64::from(p.x / p.w), f64::from(p.y / p.w)))
        .collect();
    let twice: f64 = (0..xy.len())
        .map(|k| {
            let (a, b) = (xy[k], xy[(k + 1) % xy.len()]);
            a.0 * b.1 - a.1 * b.0
        })
        .sum();
    twice.abs() / 2.0
}

/// The part `[x0, y0, x1, y1]` of the light view's image (`[0, 1]²`, y down) that triangles
/// with these corners can cover; all of it if a corner lies behind the light centre.
pub fn light_view_rect(view: &LightView, points: impl Iterator<Item = Vec3>) -> [f32; 4] {
    let vp = view.view_projection();
    let mut rect = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
    for p in points {
        let c = vp * p.extend(1.0);
        if c.w.is_nan() || c.w <= 1e-6 {
            return [0.0, 0.0, 1.0, 1.0];
        }
        let (u, v) = (c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
        rect = [
            rect[0].min(u),
            rect[1].min(v),
            rect[2].max(u),
            rect[3].max(v),
        ];
    }
    if rect[0] > rect[2] {
        return [0.0; 4];
    }
    [
        rect[0].clamp(0.0, 1.0),
        rect[1].clamp(0.0, 1.0),
        rect[2].clamp(0.0, 1.0),
        rect[3].clamp(0.0, 1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(points: [[f32; 3]; 3]) -> Vec<VolumeVertex> {
        points
            .iter()
            .map(|p| VolumeVertex {
                position: *p,
                kind: 3,
                base: 0.5,
                // Affine in position: num = x + 2y, den = 1 + z.
                num: p[0] + 2.0 * p[1],
                den: 1.0 + p[2],
                side: [0.6, 0.8],
            })
            .collect()
    }

    #[test]
    fn ending_volumes_keeps_the_part_in_reach_with_exact_attributes_and_winding() {
        let light = AreaLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
            outline: crate::scene::Outline::Disk,
        };
        // Heights below the light: 4 - y. A triangle from y = 3 (height 1) down to y = -1 (5).
        let t = tri([[0.0, 3.0, 0.0], [2.0, -1.0, 0.0], [0.0, -1.0, 2.0]]);
        assert_eq!(end_at(&t, &light, 10.0), t, "all in reach");
        assert!(end_at(&t, &light, 0.5).is_empty(), "all beyond");
        let kept = end_at(&t, &light, 3.0);
        assert_eq!(kept.len(), 3, "one corner in reach: one triangle");
        let normal = |v: &[VolumeVertex]| {
            let p = |i: usize| Vec3::from(v[i].position);
            (p(1) - p(0)).cross(p(2) - p(0))
        };
        for k in kept.chunks_exact(3) {
            assert!(normal(k).dot(normal(&t)) > 0.0, "winding kept");
            for v in k {
                let [x, y, z] = v.position;
                assert!(4.0 - y <= 3.0 + 1e-5, "{y}");
                assert!((v.num - (x + 2.0 * y)).abs() < 1e-5 && (v.den - (1.0 + z)).abs() < 1e-5);
                assert_eq!((v.kind, v.base), (3, 0.5));
            }
        }
        // Two corners in reach: a quad, two triangles.
        let t2 = tri([[0.0, 3.0, 0.0], [2.0, 3.0, 0.0], [0.0, -1.0, 2.0]]);
        assert_eq!(end_at(&t2, &light, 3.0).len(), 6);
    }

    fn builtin_scene() -> crate::scene::Scene {
        match crate::scene::builtin::get("fig7-concave") {
            Some(Ok(scene)) => scene,
            _ => panic!("the built-in scene fig7-concave"),
        }
    }

    #[test]
    fn volumes_ended_in_one_pass_are_the_whole_volumes_ended_after() {
        // A built-in scene's first caster: its volumes whole, and ended at reaches from above
        // the caster to below the ground.
        let scene = builtin_scene();
        let light = scene.light.area_or_centre();
        let prepared = crate::geometry::PreparedCasters::new(&scene);
        let geometry = prepared.build(&light, &crate::geometry::VolumeParams::for_scene(&scene));
        let g = &geometry.casters[0];
        let (umbra, penumbra) = volume_vertices(g, &light);
        assert!(!umbra.is_empty() && !penumbra.is_empty());
        let mut shortened = 0;
        for reach in [0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 100.0] {
            let (u, p) = volume_vertices_within(g, &light, Some(reach), Some(reach), 0);
            assert_eq!(u, end_at(&umbra, &light, reach), "umbra, reach {reach}");
            assert_eq!(
                p,
                end_at(&penumbra, &light, reach),
                "penumbra, reach {reach}"
            );
            shortened += usize::from(p != penumbra && !p.is_empty());
        }
        assert!(shortened > 0, "no reach ended a volume part way");
        let (u, p) = volume_vertices_within(g, &light, None, Some(3.0), 0);
        assert_eq!((u, p), (umbra, end_at(&penumbra, &light, 3.0)));
    }

    #[test]
    fn triangles_are_sorted_whole_nearest_first() {
        let c = Vec3::new(0.0, 4.0, 0.0);
        let far = tri([[0.0, -2.0, 0.0], [1.0, -2.0, 0.0], [0.0, -2.0, 1.0]]);
        let near = tri([[0.0, 3.0, 0.0], [1.0, 3.0, 0.0], [0.0, 3.0, 1.0]]);
        let mid = tri([[0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 1.0]]);
        let mut v: Vec<VolumeVertex> = [far.clone(), near.clone(), mid.clone()].concat();
        sort_near_first(&mut v, c);
        assert_eq!(v, [near, mid, far].concat());
    }

    #[test]
    fn the_light_view_rect_holds_the_corners_and_is_all_of_it_behind_the_light() {
        let scene = builtin_scene();
        let view = LightView::fit(&scene);
        let vp = view.view_projection();
        let corners: Vec<Vec3> = scene
            .casters()
            .flat_map(|o| o.mesh.triangle_corners())
            .flatten()
            .collect();
        let r = light_view_rect(&view, corners.iter().copied());
        assert!(r.iter().all(|v| (0.0..=1.0).contains(v)), "{r:?}");
        assert!(r[0] < r[2] && r[1] < r[3], "{r:?}");
        for &p in &corners {
            let c = vp * p.extend(1.0);
            let (u, v) = (c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
            assert!(
                (r[0]..=r[2]).contains(&u) && (r[1]..=r[3]).contains(&v),
                "{u} {v} {r:?}"
            );
        }
        // No corners: an empty rect; a corner behind the light centre: the whole image.
        assert_eq!(light_view_rect(&view, std::iter::empty()), [0.0; 4]);
        let light = scene.light.area_or_centre();
        let behind = light.center - light.normal;
        let whole = light_view_rect(&view, corners.iter().copied().chain([behind]));
        assert_eq!(whole, [0.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn casters_whose_umbrae_do_not_overlap_share_a_group() {
        let groups = disjoint_groups(&[
            [0.0, 0.0, 0.4, 0.4],
            [0.5, 0.5, 0.9, 0.9],
            [0.3, 0.3, 0.6, 0.6],
            [0.2, 0.2, 0.2, 0.2],
        ]);
        let members: Vec<Vec<usize>> = groups.iter().map(|g| g.0.clone()).collect();
        assert_eq!(
            members,
            [vec![0, 1], vec![2]],
            "the empty one belongs to none"
        );
        assert_eq!(groups[0].1, [0.0, 0.0, 0.9, 0.9]);
    }

    #[test]
    fn a_footprint_is_the_projected_area_inside_the_view() {
        let scene = builtin_scene();
        let view = LightView::fit(&scene);
        let inv = view.view_projection().inverse();
        let at = |x: f32, y: f32| {
            let p = inv * Vec4::new(x, y, 0.5, 1.0);
            VolumeVertex {
                position: (p.truncate() / p.w).to_array(),
                ..VolumeVertex::default()
            }
        };
        let quad = |x0: f32, y0: f32, x1: f32, y1: f32| {
            [
                at(x0, y0),
                at(x1, y0),
                at(x1, y1),
                at(x0, y0),
                at(x1, y1),
                at(x0, y1),
            ]
        };
        let close = |a: f64, b: f64| (a - b).abs() < 1e-3 * b.max(1.0);
        // The whole view: every texel once; twice as wide is clipped to the same.
        let whole = footprint_texels(&quad(-1.0, -1.0, 1.0, 1.0), &view, 64);
        assert!(close(whole, 4096.0), "{whole}");
        let wide = footprint_texels(&quad(-2.0, -2.0, 2.0, 2.0), &view, 64);
        assert!(close(wide, 4096.0), "{wide}");
        // A quarter of it, either winding; overlapping triangles count twice.
        let quarter = footprint_texels(&quad(0.0, 0.0, 1.0, 1.0), &view, 64);
        assert!(close(quarter, 1024.0), "{quarter}");
        let flipped = footprint_texels(&quad(1.0, 1.0, 0.0, 0.0), &view, 64);
        assert!(close(flipped, 1024.0), "{flipped}");
        let twice = [quad(0.0, 0.0, 1.0, 1.0), quad(0.0, 0.0, 1.0, 1.0)].concat();
        assert!(close(footprint_texels(&twice, &view, 64), 2048.0));
        // Behind the light centre: nothing.
        let c = scene.light.area_or_centre();
        let behind = VolumeVertex {
            position: (c.center - c.normal).to_array(),
            ..VolumeVertex::default()
        };
        assert_eq!(footprint_texels(&[behind; 3], &view, 64), 0.0);
    }

    #[test]
    fn volumes_ended_below_the_receivers_cover_less_of_the_map() {
        let scene = builtin_scene();
        let light = scene.light.area_or_centre();
        let view = LightView::fit(&scene);
        let prepared = crate::geometry::PreparedCasters::new(&scene);
        let geometry = prepared.build(&light, &crate::geometry::VolumeParams::for_scene(&scene));
        let fill = |reach| {
            let d = drawn_volumes(&geometry, &light, &view, reach);
            let umbra: f64 = d
                .umbrae
                .iter()
                .map(|(u, _)| footprint_texels(u, &view, 256))
                .sum();
            (umbra, footprint_texels(&d.penumbra, &view, 256))
        };
        let ended = fill(Some(reach_below(&light, scene.bounds())));
        let whole = fill(None);
        assert!(ended.0 > 0.0 && ended.1 > 0.0, "{ended:?}");
        assert!(
            ended.0 < 0.8 * whole.0 && ended.1 < 0.8 * whole.1,
            "{ended:?} {whole:?}"
        );
    }
}
