//! The CPU twin of `dbuffer-fused` ([`FusedTwin`]): the light pass's lists and crossings and the
//! camera pass, computed on the CPU the way the GPU passes compute them, to test those against.

use glam::{Mat4, Vec2, Vec3};

use super::candidates::scene_candidate_edges;
use super::chord::{EdgeChord, FusedEdge};
use super::lists::{edge_in_texel, CasterCrossings, Patch, TexelList, TexelRay};
use super::mask::{mask_details, mask_visibility, CentreLayers, DiskMask, MaskEval, MaskResult};
use super::{
    DEFAULT_CAP, DEFAULT_LIST_SIZE, DEFAULT_SAMPLES, PATCH_BULGE, PATCH_COS, PATCH_TEXELS,
    WHOLE_WALK_EDGES,
};
use crate::geometry::bvh::Bvh;
use crate::geometry::light_view::LightView;
use crate::geometry::twin::{DBufferTwin, TwinSample};
use crate::geometry::visibility::{Branch, VtVariant};
use crate::geometry::{PreparedCasters, SceneGeometry};
use crate::scene::{AreaLight, Scene};

/// How the CPU twin of `dbuffer-fused` is set up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedParams {
    /// Texels per side of the light view: the D-buffer's size, where the caster surfaces along
    /// each texel's ray are counted.
    pub size: u32,
    /// Texels per side of the grid of edge lists (coarser than the D-buffer: the list pass's
    /// fragments, and its memory, go with its square).
    pub list_size: u32,
    /// Edges per list.
    pub cap: usize,
    /// Disk samples in the mask.
    pub samples: usize,
    pub eval: MaskEval,
    /// V(t) of the paper's method, where the fused one falls back to it (an overflowing list).
    pub vt: VtVariant,
}

impl Default for FusedParams {
    fn default() -> Self {
        Self {
            size: 1024,
            list_size: DEFAULT_LIST_SIZE,
            cap: DEFAULT_CAP,
            samples: DEFAULT_SAMPLES,
            eval: MaskEval::Exact,
            vt: VtVariant::Exact,
        }
    }
}

/// How the camera pass reached V.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FusedPath {
    /// Behind the light, or outside the light view: as the paper's camera pass.
    Outside,
    /// The texel's list is empty: no chord crosses the disk, V is 1 or 0 as the centre is seen.
    Uniform,
    /// The texel's list overflowed: V over every candidate edge, as over a list long enough
    /// (the paper's V(t) where there are more than [`WHOLE_WALK_EDGES`]).
    Overflow,
    /// The mask over the texel's list.
    Mask,
}

/// What the fused camera pass computes for one receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedSample {
    pub v: f64,
    pub path: FusedPath,
    /// The paper's D-buffer at `x` (branch, `t`).
    pub dbuffer: TwinSample,
    pub mask: Option<MaskResult>,
    /// The light-pass count of the texel's list.
    pub list_count: usize,
}

/// Coarse bins of the light view holding the edges whose wedge footprint (at any depth) touches
/// them: only a speed-up of the CPU twin (the GPU rasterises each edge's footprint instead).
struct EdgeBins {
    cells: u32,
    bins: Vec<Vec<u32>>,
}

impl EdgeBins {
    fn build(edges: &[FusedEdge], light: &AreaLight, vp: &Mat4, cells: u32) -> EdgeBins {
        let (e1, e2) = light.basis();
        let r = light.radius;
        let mut bins = vec![Vec::new(); (cells * cells) as usize];
        for (k, e) in edges.iter().enumerate() {
            // The footprint seen from c is the edge swept by disks of radius at most r parallel to
            // the light: inside the projection of the squares around its ends (projection keeps
            // convex hulls).
            let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
            let mut everywhere = false;
            for p in [e.a, e.b] {
                for (s, t) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let q = p + r * 1.01 * (s * e1 + t * e2);
                    let clip = *vp * q.extend(1.0);
                    if clip.w.is_nan() || clip.w <= 1e-6 {
                        everywhere = true;
                        continue;
                    }
                    let ndc = Vec2::new(clip.x, clip.y) / clip.w;
                    lo = lo.min(ndc);
                    hi = hi.max(ndc);
                }
            }
            if everywhere {
                lo = Vec2::splat(-1.0);
                hi = Vec2::splat(1.0);
            }
            let cell = |v: f32| ((v * 0.5 + 0.5) * cells as f32).floor();
            let (x0, x1) = (cell(lo.x).max(0.0), cell(hi.x).min(cells as f32 - 1.0));
            let (y0, y1) = (cell(lo.y).max(0.0), cell(hi.y).min(cells as f32 - 1.0));
            if x0 > x1 || y0 > y1 {
                continue;
            }
            for y in y0 as u32..=y1 as u32 {
                for x in x0 as u32..=x1 as u32 {
                    bins[(y * cells + x) as usize].push(k as u32);
                }
            }
        }
        EdgeBins { cells, bins }
    }

    fn at(&self, ndc: Vec2) -> &[u32] {
        let cell = |v: f32| {
            (((v * 0.5 + 0.5) * self.cells as f32).floor() as i64).clamp(0, self.cells as i64 - 1)
                as u32
        };
        &self.bins[(cell(ndc.y) * self.cells + cell(ndc.x)) as usize]
    }
}

/// The receivers (surfaces facing the light centre) along one ray, as the light pass keeps them:
/// the first, the second and the last (points and normals), how many there are, and the height
/// of the last one on a caster.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ReceiverLayers {
    points: [(Vec3, Vec3); 3],
    count: u32,
    last_on_caster: Option<(Vec3, Vec3)>,
}

/// The texels of the 3×3 around `texel` inside a `size`-texel grid (the texel itself included).
fn neighbourhood(texel: [u32; 2], size: u32) -> impl Iterator<Item = [i64; 2]> {
    let (tx, ty, size) = (i64::from(texel[0]), i64::from(texel[1]), i64::from(size));
    (-1..=1)
        .flat_map(move |dy| (-1..=1).map(move |dx| [tx + dx, ty + dy]))
        .filter(move |&[x, y]| (0..size).contains(&x) && (0..size).contains(&y))
}

/// One edge's chord as [`FusedTwin::light_from`] gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointChord {
    /// The edge's index in [`FusedTwin::edges`].
    pub edge: u32,
    pub caster: u32,
    /// The chord: `chord.ends` are the projected end points (unit-disk coordinates),
    /// `chord.chord` the line `A u + B v + C = 0` through them (the centre on its negative side),
    /// `chord.delta` the layers a path from the centre gains beyond it (negative: loses) within
    /// the sector the ends span, `chord.area` that region's exact share of the disk.
    pub chord: EdgeChord,
}

/// The light as seen from one receiver by `dbuffer-fused` ([`FusedTwin::light_from`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LightFromPoint {
    /// The method's V there.
    pub v: f64,
    pub path: FusedPath,
    /// The light pass's count of the texel's list.
    pub list_count: usize,
    /// What the camera pass knew of the layers between the point and the disk centre.
    pub centre: Option<CentreLayers>,
    /// `L(c)` as anchored (see [`MaskResult::anchor`]).
    pub anchor: i32,
    pub chords: Vec<PointChord>,
    /// The mask's disk samples (unit-disk coordinates) ...
    pub samples: Vec<Vec2>,
    /// ... and the layers between the point and each: lit where ≤ 0 (empty unless the mask ran).
    pub layers: Vec<i32>,
    /// V exactly, where the disk is at most one layer deep there.
    pub exact: Option<f64>,
}

/// The CPU twin of `dbuffer-fused`: the paper's D-buffer twin, the candidate edges, the light
/// view's texels and their bounded lists, and the camera pass's mask.
pub struct FusedTwin {
    dbuffer: DBufferTwin,
    light: AreaLight,
    edges: Vec<FusedEdge>,
    surfaces: Bvh,
    /// Whether each triangle of `surfaces` belongs to a caster.
    is_caster: Vec<bool>,
    caster_bvh: Bvh,
    view: LightView,
    pub(super) vp: Mat4,
    inv_vp: Mat4,
    /// The view's extent in slope space (x, y): a texel of an `n`-texel grid spans this / `n`.
    pub(super) view_slope: Vec2,
    bins: EdgeBins,
    mask: DiskMask,
    params: FusedParams,
}

impl FusedTwin {
    pub fn new(
        scene: &Scene,
        prepared: &PreparedCasters,
        geometry: &SceneGeometry,
        params: FusedParams,
    ) -> FusedTwin {
        let edges = scene_candidate_edges(prepared, geometry);
        let view = LightView::fit(scene);
        let vp = view.view_projection();
        let view_slope = Vec2::new(
            2.0 / view.projection.x_axis.x.abs(),
            2.0 / view.projection.y_axis.y.abs(),
        );
        FusedTwin {
            dbuffer: DBufferTwin::new(scene, &geometry.casters),
            light: scene.light.area_or_centre(),
            bins: EdgeBins::build(&edges, &scene.light.area_or_centre(), &vp, 64),
            edges,
            surfaces: Bvh::build(scene.all_triangles()),
            is_caster: scene
                .objects
                .iter()
                .flat_map(|o| std::iter::repeat_n(o.casts_shadow, o.mesh.triangles.len()))
                .collect(),
            caster_bvh: Bvh::build(
                scene
                    .casters()
                    .flat_map(|o| o.mesh.triangle_corners())
                    .collect(),
            ),
            view,
            vp,
            inv_vp: vp.inverse(),
            view_slope,
            mask: DiskMask::for_light(&scene.light.area_or_centre(), params.samples, params.eval),
            params: FusedParams {
                size: params.size.max(1),
                list_size: params.list_size.max(1),
                ..params
            },
        }
    }

    pub fn edges(&self) -> &[FusedEdge] {
        &self.edges
    }

    pub fn light_view(&self) -> &LightView {
        &self.view
    }

    pub fn params(&self) -> &FusedParams {
        &self.params
    }

    pub fn dbuffer(&self) -> &DBufferTwin {
        &self.dbuffer
    }

    /// The texel of a `size`-texel grid over the light view under `x` (as `texel_of` in the
    /// camera pass), or `None` outside the light view.
    pub fn texel_of(&self, x: Vec3, size: u32) -> Option<[u32; 2]> {
        let clip = self.vp * x.extend(1.0);
        if clip.w.is_nan() || clip.w <= 0.0 {
            return None;
        }
        let ndc = Vec2::new(clip.x, clip.y) / clip.w;
        if !(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0) {
            return None;
        }
        let size = size as f32;
        let uv = Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        let t = (uv * size)
            .floor()
            .clamp(Vec2::ZERO, Vec2::splat(size - 1.0));
        Some([t.x as u32, t.y as u32])
    }

    /// Unit direction from `c` through the centre of `texel` of a `size`-texel grid, and its NDC
    /// position.
    fn texel_ray(&self, texel: [i64; 2], size: u32) -> (Vec3, Vec2) {
        let size = size as f32;
        let uv = (Vec2::new(texel[0] as f32, texel[1] as f32) + 0.5) / size;
        let ndc = Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
        let p = self.inv_vp.project_point3(ndc.extend(0.5));
        ((p - self.light.center).normalize_or_zero(), ndc)
    }

    /// The surfaces facing the light centre along the ray from `c` (the receivers): the first,
    /// second and last hit points and how many there are (what the light pass keeps per texel).
    fn receiver_layers(&self, w: Vec3) -> Option<ReceiverLayers> {
        let mut hits: Vec<(f32, Vec3)> = Vec::new();
        let mut last_on_caster: Option<(f32, Vec3)> = None;
        self.surfaces
            .for_each_hit(self.light.center, w, 0.0, f32::INFINITY, |h| {
                let [a, b, c] = self.surfaces.triangle(h.triangle as usize);
                let n = (*b - *a).cross(*c - *a).normalize_or_zero();
                if n.dot(w) < 0.0 {
                    hits.push((h.t, n));
                    if self.is_caster[h.triangle as usize]
                        && last_on_caster.is_none_or(|(t, _)| h.t > t)
                    {
                        last_on_caster = Some((h.t, n));
                    }
                }
            });
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        let at = |(t, n): (f32, Vec3)| (self.light.center + w * t, n);
        let first = *hits.first()?;
        let last = *hits.last()?;
        let second = hits.get(1).copied().unwrap_or(last);
        Some(ReceiverLayers {
            points: [at(first), at(second), at(last)],
            count: hits.len() as u32,
            last_on_caster: last_on_caster.map(at),
        })
    }

    /// Caster surfaces crossed along the ray from `c`, and the largest height of one.
    fn caster_crossings(&self, w: Vec3) -> (u32, f32) {
        let (mut n, mut far) = (0u32, 0.0f32);
        self.caster_bvh
            .for_each_hit(self.light.center, w, 0.0, f32::INFINITY, |h| {
                n += 1;
                far = far.max(h.t);
            });
        (n, far * w.dot(self.light.normal))
    }

    /// The caster crossings of the D-buffer texel `texel` (the count along its ray, the farthest
    /// crossing over the 3×3 around it).
    pub fn crossings_of(&self, texel: [u32; 2]) -> CasterCrossings {
        let size = self.params.size;
        let (dir, _) = self.texel_ray([i64::from(texel[0]), i64::from(texel[1])], size);
        let (count, _) = self.caster_crossings(dir);
        let far_height = neighbourhood(texel, size)
            .map(|t| self.caster_crossings(self.texel_ray(t, size).0).1)
            .fold(0.0, f32::max);
        CasterCrossings {
            count,
            far_height,
            dir,
        }
    }

    /// The list texel's ray with its receivers, as the light pass and its 3×3 merge give it
    /// (`None`: no receiver around it, so no list).
    pub fn texel_ray_of(&self, texel: [u32; 2]) -> Option<TexelRay> {
        let size = self.params.list_size;
        let (tx, ty) = (i64::from(texel[0]), i64::from(texel[1]));
        let mut layers: Vec<ReceiverLayers> = Vec::new();
        let mut centre: Option<ReceiverLayers> = None;
        for [nx, ny] in neighbourhood(texel, size) {
            let (w, _) = self.texel_ray([nx, ny], size);
            if let Some(l) = self.receiver_layers(w) {
                layers.push(l);
                if nx == tx && ny == ty {
                    centre = Some(l);
                }
            }
        }
        let (w, _) = self.texel_ray([tx, ty], size);
        let along = w.dot(self.light.normal);
        let half_slope = 0.5 * self.view_slope.length() / size as f32;
        let centre = centre.or_else(|| layers.first().copied());
        let ray = centre.filter(|_| along > 1e-6).map(|centre| {
            let (points, count) = (centre.points, centre.count);
            // Patches on the centre ray's first, second and last receivers (as many as it has):
            // a receiver of the 3×3 on the same surface (near, and facing the same way) widens
            // one. The others (across an outline), and the receivers between the second and the
            // last of a ray that has more than three (on casters, so no deeper than the last
            // receiver on a caster: a non-casting receiver between the casters and the last one
            // would need one more layer), join the deeper stretch.
            let distinct = count.min(3) as usize;
            let centres: Vec<(Vec3, Vec3)> = match distinct {
                1 => vec![points[0]],
                2 => vec![points[0], points[2]],
                _ => points.to_vec(),
            };
            let base = |p: Vec3| p.distance(self.light.center) * half_slope;
            let mut patches: Vec<Patch> = centres
                .iter()
                .map(|&(point, normal)| Patch {
                    point,
                    normal,
                    radius: base(point),
                    bulge: base(point) * PATCH_BULGE,
                })
                .collect();
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            let mut far = f32::NEG_INFINITY;
            // A receiver seen at `q` with normal `nq` by a ray of the 3×3: the same surface can
            // reach into this texel's pyramid within about 1.5 texel diagonals sideways, which
            // along a surface tilted away from the ray is a longer way, up or down.
            let reach = |q: Vec3, nq: Vec3| 2.2 * base(q) / nq.dot(w).abs().max(0.05);
            // Where the rays of the 3×3 see different numbers of receivers, a surface starts or
            // ends between them (an outline seen from `c`): rays between them can meet it
            // between the second receiver and the last on a caster.
            let counts_differ = layers.iter().any(|l| l.count != centre.count);
            for l in &layers {
                if l.count > 3 || (counts_differ && l.count > 1) {
                    let (p2, n2) = l.points[1];
                    let (pc, nc) = l.last_on_caster.unwrap_or(l.points[1]);
                    lo = lo.min(self.light.height_of(p2) - reach(p2, n2));
                    hi = hi.max(self.light.height_of(pc) + reach(pc, nc));
                }
                for (q, nq) in l.points {
                    far = far.max(self.light.height_of(q));
                    let same = patches.iter_mut().find(|p| {
                        q.distance(p.point) <= PATCH_TEXELS * base(p.point)
                            && nq.dot(p.normal) >= PATCH_COS
                    });
                    match same {
                        Some(p) => {
                            let b = base(p.point);
                            p.radius = p.radius.max(q.distance(p.point) + b);
                            p.bulge = p
                                .bulge
                                .max(p.normal.dot(q - p.point).abs() + b * PATCH_BULGE);
                        }
                        None => {
                            // Across an outline.
                            let h = self.light.height_of(q);
                            lo = lo.min(h - reach(q, nq));
                            hi = hi.max(h + reach(q, nq));
                        }
                    }
                }
            }
            TexelRay {
                dir: w,
                patches,
                deeper: (lo <= hi).then(|| (lo / along, hi / along)),
                far: far / along,
                half_slope,
            }
        });
        ray
    }

    /// What the light pass stores for `texel`.
    pub fn texel_list(&self, texel: [u32; 2]) -> TexelList {
        let Some(ray) = self.texel_ray_of(texel) else {
            return TexelList::default();
        };
        let (_, ndc) = self.texel_ray(
            [i64::from(texel[0]), i64::from(texel[1])],
            self.params.list_size,
        );
        let passed: Vec<u32> = self
            .bins
            .at(ndc)
            .iter()
            .copied()
            .filter(|&k| edge_in_texel(&self.edges[k as usize], &ray, &self.light))
            .collect();
        let count = passed.len();
        let overflow = count > self.params.cap;
        TexelList {
            count,
            edges: if overflow { Vec::new() } else { passed },
            overflow,
        }
    }

    /// The fused camera pass at `x`.
    pub fn sample(&self, x: Vec3) -> FusedSample {
        let dbuffer = self.dbuffer.sample(x);
        let outside = FusedSample {
            v: self.params.vt.apply(dbuffer.t),
            path: FusedPath::Outside,
            dbuffer,
            mask: None,
            list_count: 0,
        };
        if dbuffer.branch == Branch::Umbra && dbuffer.texel == Default::default() {
            return outside; // behind the light
        }
        let (Some(texel), Some(list_texel)) = (
            self.texel_of(x, self.params.size),
            self.texel_of(x, self.params.list_size),
        ) else {
            return FusedSample { v: 1.0, ..outside };
        };
        let list = self.texel_list(list_texel);
        if list.overflow && self.edges.len() > WHOLE_WALK_EDGES {
            return FusedSample {
                path: FusedPath::Overflow,
                list_count: list.count,
                ..outside
            };
        }
        // An overflowing list is not used: every candidate edge is walked instead (a superset
        // of any list, so V is what a list long enough gives).
        let edges = || -> Box<dyn Iterator<Item = &FusedEdge> + '_> {
            if list.overflow {
                Box::new(self.edges.iter())
            } else {
                Box::new(list.edges.iter().map(|&k| &self.edges[k as usize]))
            }
        };
        let centre = match self.crossings_of(texel).layers_at(x, edges(), &self.light) {
            Some(k) => CentreLayers::Known(k),
            None => CentreLayers::Hidden(dbuffer.hidden),
        };
        if list.count == 0 {
            // No chord crosses the disk: all of it is as the centre is.
            let hidden = match centre {
                CentreLayers::Known(k) => k > 0,
                CentreLayers::Hidden(h) => h,
            };
            return FusedSample {
                v: if hidden { 0.0 } else { 1.0 },
                path: FusedPath::Uniform,
                ..outside
            };
        }
        let m = mask_visibility(edges(), x, centre, &self.light, &self.mask);
        FusedSample {
            v: m.v(),
            path: if list.overflow {
                FusedPath::Overflow
            } else {
                FusedPath::Mask
            },
            dbuffer,
            mask: Some(m),
            list_count: list.count,
        }
    }

    /// V at `x` (the method's output).
    pub fn visibility(&self, x: Vec3) -> f64 {
        self.sample(x).v
    }

    /// The light as seen from `x` by the method: for the lab's "light as seen from this pixel"
    /// panel. The chords of the edges of `x`'s list (each edge's clipped ends projected onto the
    /// light's plane, in unit-disk coordinates, the side where the path from the centre gains or
    /// loses layers, and the exact area of its region), the disk samples and how many layers lie
    /// between `x` and each (`L(c) + Δ`, as anchored: lit where ≤ 0). Where the method did not
    /// run its mask (outside the light view, an empty or an overflowing list), `chords` and
    /// `layers` are empty and `path` says why; V is the method's V either way.
    pub fn light_from(&self, x: Vec3) -> LightFromPoint {
        let s = self.sample(x);
        let mut out = LightFromPoint {
            v: s.v,
            path: s.path,
            list_count: s.list_count,
            centre: None,
            anchor: 0,
            chords: Vec::new(),
            samples: self.mask.samples.clone(),
            layers: Vec::new(),
            exact: None,
        };
        if s.path != FusedPath::Mask {
            return out;
        }
        let (Some(texel), Some(list_texel)) = (
            self.texel_of(x, self.params.size),
            self.texel_of(x, self.params.list_size),
        ) else {
            return out;
        };
        let list = self.texel_list(list_texel);
        let edges = || list.edges.iter().map(|&k| &self.edges[k as usize]);
        let centre = match self.crossings_of(texel).layers_at(x, edges(), &self.light) {
            Some(k) => CentreLayers::Known(k),
            None => CentreLayers::Hidden(s.dbuffer.hidden),
        };
        let d = mask_details(edges(), x, centre, &self.light, &self.mask);
        out.centre = Some(centre);
        out.anchor = d.result.anchor;
        out.exact = d.result.exact;
        out.layers = d.delta.iter().map(|k| k + d.result.anchor).collect();
        out.chords = d
            .chords
            .into_iter()
            .map(|(i, chord)| {
                let edge = list.edges[i];
                PointChord {
                    edge,
                    caster: self.edges[edge as usize].caster,
                    chord,
                }
            })
            .collect();
        out
    }

    /// The method without its bounds: no texels, no cap, every candidate edge near `x`, and no
    /// D-buffer classes (only its hidden-from-centre test, for the anchor), with `mask`'s samples.
    /// With the oracle's own samples this is the oracle up to numerical ties; the tests use it to
    /// check the geometry of the method apart from its storage.
    pub fn unbounded(&self, x: Vec3, mask: &DiskMask) -> MaskResult {
        let centre = CentreLayers::Known(self.layers_to_centre(x));
        let clip = self.vp * x.extend(1.0);
        let edges: Box<dyn Iterator<Item = &FusedEdge>> = if clip.w > 0.0 {
            let ndc = Vec2::new(clip.x, clip.y) / clip.w;
            if ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 {
                Box::new(self.bins.at(ndc).iter().map(|&k| &self.edges[k as usize]))
            } else {
                Box::new(self.edges.iter())
            }
        } else {
            Box::new(self.edges.iter())
        };
        mask_visibility(edges, x, centre, &self.light, mask)
    }

    /// `L(c)` by ray casting: the caster surfaces between `x` and the disk centre (as the oracle
    /// counts them: not within `SELF_EPS` of either end).
    pub fn layers_to_centre(&self, x: Vec3) -> i32 {
        let d = self.light.center - x;
        let eps = crate::geometry::oracle::SELF_EPS;
        let mut n = 0;
        self.caster_bvh
            .for_each_hit(x, d, eps, 1.0 - eps, |_| n += 1);
        n
    }
}
