//! `dbuffer-fused`: the D-buffer with every silhouette chord a receiver needs, so that the parts
//! of the disk hidden by different casters (or different parts of one caster) combine as they do
//! in reality. This is its CPU twin, the model the GPU passes are to be tested against;
//! `docs/method/dbuffer-fused.md` describes the method, its GPU mapping and what it still gets wrong.
//!
//! **The chord of an edge.** For a receiver `x` and an edge `e = (a, b)`, the plane through `x`
//! and `e` meets the light's plane in a line: the exact chord that edge cuts from the disk as
//! seen from `x`. Its normal is `m = (a − x) × (b − x)`; in unit-disk coordinates `(u, v)` of the
//! point `c + r(u e₁ + v e₂)` the line is `m·(c − x) + u r (m·e₁) + v r (m·e₂) = 0` — no division,
//! so edges parallel to the disk, or reaching past `x`, need no special case ([`edge_chord`]).
//!
//! **Why chords add up.** Let `L(q)` be the number of surface layers the segment from `x` to a
//! disk point `q` crosses (a closed caster contributes two per crossing, an open sheet one); `q`
//! is hidden iff `L(q) > 0`. Seen from `x`, `L` changes only across the projections of the edges
//! that are silhouettes *from `x`* (one face in front of `x`, the other not), by the edge's layer
//! count, and is larger on the side where the edge's two faces project (they fold onto one side).
//! So `L(q) = L(c) + Δ(q)`, where `Δ(q)` sums ±layers over the projected edges that the straight
//! path from the disk centre `c` to `q` crosses (Laine et al. 2005 integrate depth complexity the
//! same way). The path crosses edge `e` iff `q` lies beyond `e`'s chord (the far side from `c`) and
//! inside the sector from `c` spanned by the projected end points: one chord and two lines through
//! the centre. The camera pass adds this up per disk sample ([`mask_visibility`]).
//!
//! **`L(c)`**, the layers between `x` and the centre: the light pass counts the caster surfaces
//! along each D-buffer texel's ray; for a receiver beyond all of them, where the 3×3 texels around
//! agree on the count, that count is `L(c)` ([`CasterCrossings`]). Elsewhere the anchor is
//! `max(hidden from c ? 1 : 0, −min Δ)`: exact wherever a sample is visible.
//!
//! **Exact where one layer deep.** Where every sample sees either 0 or one layer's worth (a single
//! convex caster, and most penumbrae), `V = 1 − (L(c) + ∫Δ)/layers` and `∫Δ` is a sum of exact
//! areas, one per edge ([`region_area`]): no sampling error. Elsewhere V is the fraction of the
//! `N` samples with `L ≤ 0`.
//!
//! **Which edges.** An edge that is a silhouette from `x` and projects into the disk is a
//! silhouette from some disk point (the line from `x` through it hits the disk there), so its faces
//! are not both all-frontfacing nor both none-frontfacing: those are the *candidate edges*
//! ([`candidate_edges`]), from the face classes the D-buffer already has. They are more than the
//! umbra and penumbra silhouettes: an edge between two silhouette faces is on neither.
//!
//! **The light pass: bounded per-texel edge lists** on a grid coarser than the D-buffer. A point
//! sees `e`'s projection meet the disk iff it lies in `e`'s wedge; along a ray from `c` the wedge,
//! once entered, is never left (seen from `c`, the wedge at height `H` is the edge swept by a disk
//! of radius `(1 − H_e/H) r`, which grows with `H`). A list texel keeps the candidate edges whose
//! wedge holds its ray at the farthest receiver and that can be silhouettes from one of its
//! receivers (surfaces facing `c`, from the 3×3 texels around it): [`edge_in_texel`], the list
//! pass's fragment test, conservative by construction (the tests check it against every edge).
//! **Overflow rule:** the pass counts every edge that passes; when the count exceeds the cap, the
//! stored entries (whichever the GPU kept) are ignored and the camera pass falls back to the
//! paper's `dbuffer` V for that pixel. The set of edges, and so V, does not depend on the order in
//! which a GPU appends them.
//!
//! **The camera pass.** An empty list means no chord crosses the disk: V is 1 or 0 as the centre
//! is seen. Otherwise the mask (or the exact area) over the list's edges. The paper's D-buffer
//! is used for its `|cx_o|` (hidden from the centre, where `L(c)` is not counted) and for the
//! fallback on an overflowing list, nothing else: its penumbra and umbra volumes are not needed
//! (and are not trusted: a large light close to a caster leaves penumbra outside them, and
//! overlapping casters leave rays inside one caster's umbra volume after the umbra).

use glam::{Mat4, Vec2, Vec3};

use super::adjacency::{CasterMesh, NO_FACE};
use super::bvh::Bvh;
use super::classify::FaceClass;
use super::light_view::LightView;
use super::oracle::disk_samples;
use super::twin::{DBufferTwin, TwinSample};
use super::visibility::{Branch, VtVariant};
use super::{PreparedCasters, SceneGeometry};
use crate::scene::{DiskLight, Scene};

/// Default number of disk samples in the camera pass's mask (four `u32` words per bit plane).
pub const DEFAULT_SAMPLES: usize = 128;

/// Largest mask the look-up tables support (the twin's `[u64; 4]`).
pub const MAX_LUT_SAMPLES: usize = 256;

/// Largest mask the exact evaluation supports.
pub const MAX_SAMPLES: usize = 4096;

/// Default number of edges one list holds.
pub const DEFAULT_CAP: usize = 128;

/// Default size of the grid of edge lists (per side): with `DEFAULT_CAP` edges of 2 bytes, 64 MiB
/// of list entries.
pub const DEFAULT_LIST_SIZE: u32 = 512;

/// `L(c)` is anchored by the `ANCHOR_SAMPLES`-th smallest `Δ` over the samples, not the
/// smallest: a few samples next to a chord or a sector line can come out ±layers off (the look-up
/// tables quantise the lines, so two edges of one silhouette need not meet exactly), and with
/// the smallest one such sample would shift every sample's count (a black dot in a lit area,
/// seen in `fusion-many` with 371 pixels off by more than 0.1 at 256²; with 3, one). The price: a
/// visible part of the disk smaller than 3 samples is not seen where `L(c)` is anchored by `Δ`
/// (at most 2/128 of V).
pub const ANCHOR_SAMPLES: usize = 3;

/// Bit planes of the camera pass's per-sample layer counter (two's complement, wrapping): values
/// from −16 to 15.
pub const COUNTER_BITS: u32 = 5;

/// An edge is clipped where it comes closer than this fraction of `x`'s height to `x`'s own
/// height: the part beyond cannot hide the light from `x` (the oracle ignores hits this close, too).
const CLIP: f32 = 1e-4;

/// How far (in texel footprints) a receiver seen by a neighbouring texel's ray may lie from one of
/// this texel's receiver patches and still widen it (rather than join the deeper stretch).
const PATCH_TEXELS: f32 = 64.0;

/// Two receivers of neighbouring texels lie on one surface patch if their normals agree to
/// this cosine (and they are within `PATCH_TEXELS` footprints).
const PATCH_COS: f32 = 0.9;

/// How far (in texel footprints) a receiver may stray from its patch's tangent plane between the
/// sampled points (curvature).
const PATCH_BULGE: f32 = 0.5;

/// Tolerance of "x is in front of a face", in units of the coordinates' magnitude: a receiver on a
/// caster lies on its own face's plane (up to the rounding of its position, a few ulps) and
/// counts as in front of it: it sees the surface from outside.
const FACING_TOL: f32 = 16.0 * f32::EPSILON;

/// A candidate silhouette edge: what the light pass rasterises and the camera pass reads, per edge
/// (the GPU's storage-buffer record, 5 × `vec4<f32>`: see `docs/method/dbuffer-fused.md`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FusedEdge {
    pub a: Vec3,
    pub b: Vec3,
    /// Face planes `n·p − offset` (positive in front). For an open boundary edge, face 1 is the
    /// back of face 0.
    pub n0: Vec3,
    pub offset0: f32,
    pub n1: Vec3,
    pub offset1: f32,
    /// The sum of the two faces' unit directions away from the edge, within each face: the side of
    /// the plane through `x` and the edge that the faces project onto when the edge is a silhouette
    /// from `x` (they fold onto one side).
    pub fold: Vec3,
    /// Layers a crossing of the projected edge adds: 2 between two faces, 1 on an open boundary.
    pub layers: u32,
    /// Index of the caster.
    pub caster: u32,
}

impl FusedEdge {
    /// The edge as the GPU's storage-buffer record (`FusedEdge` of `shaders/shared/fused.wgsl`):
    /// `a.xyz, layers` · `b.xyz, max |aᵢ|` (the scale of the facing tolerance) ·
    /// `n0.xyz, offset0` · `n1.xyz, offset1` · `fold.xyz, 1 if a silhouette from the light
    /// centre c else 0` (an outline seen from `c`, which [`CasterCrossings::layers_at`] looks
    /// for) · `m_c.xyz, m_c·fold` with `m_c = (a − c) × (b − c)`, the normal of the plane through
    /// `c` and the edge. The same `f32`s the twin computes with.
    pub fn gpu_record(&self, c: Vec3) -> [[f32; 4]; 6] {
        let m = (self.a - c).cross(self.b - c);
        [
            self.a.extend(self.layers as f32).to_array(),
            self.b.extend(self.a.abs().max_element()).to_array(),
            self.n0.extend(self.offset0).to_array(),
            self.n1.extend(self.offset1).to_array(),
            self.fold
                .extend(f32::from(u8::from(self.is_silhouette_from(c))))
                .to_array(),
            m.extend(m.dot(self.fold)).to_array(),
        ]
    }

    /// Whether `x` sees one face from the front and the other from the back. A point on a face's
    /// plane counts as in front of it.
    pub fn is_silhouette_from(&self, x: Vec3) -> bool {
        let tol = FACING_TOL * (1.0 + x.abs().max_element() + self.a.abs().max_element());
        let front0 = self.n0.dot(x) - self.offset0 > -tol;
        let front1 = self.n1.dot(x) - self.offset1 > -tol;
        front0 != front1
    }
}

/// The candidate edges of one caster: every edge whose two faces are not both all-frontfacing nor
/// both none-frontfacing (an open boundary edge always is one).
pub fn candidate_edges(mesh: &CasterMesh, classes: &[FaceClass], caster: u32) -> Vec<FusedEdge> {
    let mut out = Vec::new();
    for e in &mesh.edges {
        let f0 = e.faces[0] as usize;
        let (Some(_), Some(&c0)) = (mesh.faces.get(f0), classes.get(f0)) else {
            continue;
        };
        let boundary = e.faces[1] == NO_FACE;
        let c1 = if boundary {
            c0.mirrored()
        } else {
            match classes.get(e.faces[1] as usize) {
                Some(&c) => c,
                None => continue,
            }
        };
        if c0 == c1 && matches!(c0, FaceClass::AllFront | FaceClass::NoneFront) {
            continue;
        }
        let (a, b) = (mesh.position(e.v[0]), mesh.position(e.v[1]));
        let along = (b - a).normalize_or_zero();
        let inward = |o: Vec3| {
            let d = o - a;
            (d - d.dot(along) * along).normalize_or_zero()
        };
        let d0 = inward(mesh.opposite_vertex(e.faces[0], e));
        let plane0 = mesh.plane(e.faces[0]);
        let (n1, offset1, d1) = if boundary {
            (-plane0.0, -plane0.1, d0)
        } else {
            let (normal1, offset1) = mesh.plane(e.faces[1]);
            (
                normal1,
                offset1,
                inward(mesh.opposite_vertex(e.faces[1], e)),
            )
        };
        out.push(FusedEdge {
            a,
            b,
            n0: plane0.0,
            offset0: plane0.1,
            n1,
            offset1,
            fold: d0 + d1,
            layers: if boundary { 1 } else { 2 },
            caster,
        });
    }
    out
}

/// What one edge does to the disk as seen from `x`: the samples `q` with `chord(q) > 0` and
/// `(end_a(q) > 0) != (end_b(q) > 0)` get `delta` layers. Coefficients are in unit-disk
/// coordinates `(u, v)`; `chord` is oriented so that the disk centre is on its negative side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeChord {
    /// `[A, B, C]`: `A u + B v + C`, `C < 0`.
    pub chord: [f32; 3],
    /// `[A, B]` of the line from the centre through the projection of one end point.
    pub end_a: [f32; 2],
    pub end_b: [f32; 2],
    /// ± the edge's layers: + where the far side of the chord is the caster's side.
    pub delta: i32,
    /// The exact area of the region, as a fraction of the disk's.
    pub area: f64,
    /// The (clipped) edge's end points projected from the receiver onto the light's plane, in
    /// unit-disk coordinates (radii from the centre along `e₁`, `e₂`): what a picture of the disk
    /// draws.
    pub ends: [Vec2; 2],
}

impl EdgeChord {
    /// Whether the unit-disk point `p` is in the region.
    #[inline]
    pub fn contains(&self, p: Vec2) -> bool {
        let [a, b, c] = self.chord;
        let beyond = a * p.x + b * p.y + c > 0.0;
        let sa = self.end_a[0] * p.x + self.end_a[1] * p.y > 0.0;
        let sb = self.end_b[0] * p.x + self.end_b[1] * p.y > 0.0;
        beyond && sa != sb
    }
}

/// The chord `edge` cuts from the disk as seen from `x`, or `None` when it changes nothing there:
/// not a silhouette from `x`, entirely beyond `x`'s height, or degenerate (chord through `c`).
pub fn edge_chord(edge: &FusedEdge, x: Vec3, light: &DiskLight) -> Option<EdgeChord> {
    let (e1, e2) = light.basis();
    let c = light.center;
    let hx = light.height_of(x);
    if hx.is_nan() || hx <= 0.0 || !edge.is_silhouette_from(x) {
        return None;
    }
    // Clip the edge to the part nearer the light than x.
    let limit = hx * (1.0 - CLIP);
    let (ha, hb) = (light.height_of(edge.a), light.height_of(edge.b));
    let (mut pa, mut pb) = (edge.a, edge.b);
    match (ha < limit, hb < limit) {
        (true, true) => {}
        (false, false) => return None,
        (true, false) => pb = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha)),
        (false, true) => pa = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha)),
    }
    let r = light.radius;
    let m = (edge.a - x).cross(edge.b - x);
    let cc = m.dot(c - x);
    let fold = m.dot(edge.fold);
    if cc == 0.0 || fold == 0.0 || !cc.is_finite() {
        return None;
    }
    // The caster's side of the chord is the side of `fold`. Crossing from c to a sample beyond the
    // chord enters the caster's projection (+) unless c is already on the caster's side (−).
    let c_on_caster_side = (cc > 0.0) == (fold > 0.0);
    let layers = edge.layers as i32;
    let delta = if c_on_caster_side { -layers } else { layers };
    let s = -cc.signum();
    let chord = [s * r * m.dot(e1), s * r * m.dot(e2), s * cc];
    // Side of the projected end point p relative to the line from c through a sample:
    // ((c − x) × (q − x))·(p − x) = r (u ((c − x) × e1)·(p − x) + v ((c − x) × e2)·(p − x)).
    let (k1, k2) = ((c - x).cross(e1), (c - x).cross(e2));
    let end = |p: Vec3| [r * k1.dot(p - x), r * k2.dot(p - x)];
    // The projected end points, in radii, for the exact area of the region.
    let project = |p: Vec3| {
        let q = x + (p - x) * (hx / (hx - light.height_of(p)));
        Vec2::new((q - c).dot(e1), (q - c).dot(e2)) / r
    };
    let ends = [project(pa), project(pb)];
    Some(EdgeChord {
        chord,
        end_a: end(pa),
        end_b: end(pb),
        delta,
        area: region_area(ends[0], ends[1]),
        ends,
    })
}

/// How the camera pass decides which samples a half-plane holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MaskEval {
    /// Every sample tested against every line (`u A + v B + C > 0`, in `f32`).
    #[default]
    Exact,
    /// Through look-up tables of precomputed half-plane masks (Schwarz & Stamminger 2007): lines
    /// through the centre by angle (`LUT_ANGLES` bins, uniform in [`diamond_angle`]), chords by
    /// angle and distance from the centre (`LUT_ANGLES` × `LUT_OFFSETS`). What the GPU does.
    Lut,
}

/// Angle bins of the half-plane look-up tables.
pub const LUT_ANGLES: usize = 256;
/// Distance bins (over `(0, 1)`) of the chord look-up table.
pub const LUT_OFFSETS: usize = 128;

type Bits = [u64; 4];

fn bit_set(bits: &mut Bits, i: usize) {
    bits[i / 64] |= 1 << (i % 64);
}

fn bit(bits: &Bits, i: usize) -> bool {
    bits[i / 64] >> (i % 64) & 1 == 1
}

fn and(a: Bits, b: Bits) -> Bits {
    [a[0] & b[0], a[1] & b[1], a[2] & b[2], a[3] & b[3]]
}

fn xor(a: Bits, b: Bits) -> Bits {
    [a[0] ^ b[0], a[1] ^ b[1], a[2] ^ b[2], a[3] ^ b[3]]
}

/// The disk samples of the camera pass's mask, and its look-up tables.
#[derive(Clone, Debug)]
pub struct DiskMask {
    /// Unit-disk coordinates, the oracle's stratified pattern for `N` samples.
    pub samples: Vec<Vec2>,
    pub eval: MaskEval,
    /// `LUT_ANGLES` masks of `{p : p·n_k > 0}` (`n_k` the direction of angle bin `k`).
    through_centre: Vec<Bits>,
    /// `LUT_ANGLES × LUT_OFFSETS` masks of `{p : p·n_k > ρ}`.
    chords: Vec<Bits>,
}

impl DiskMask {
    /// `samples` is clamped to `1..=MAX_SAMPLES` (`1..=MAX_LUT_SAMPLES` with look-up tables).
    pub fn new(samples: usize, eval: MaskEval) -> DiskMask {
        let max = match eval {
            MaskEval::Exact => MAX_SAMPLES,
            MaskEval::Lut => MAX_LUT_SAMPLES,
        };
        let samples = disk_samples(samples.clamp(1, max));
        let (mut through_centre, mut chords) = (Vec::new(), Vec::new());
        if eval == MaskEval::Lut {
            for k in 0..LUT_ANGLES {
                let n = lut_direction(k);
                let mut m = Bits::default();
                for (i, p) in samples.iter().enumerate() {
                    if p.dot(n) > 0.0 {
                        bit_set(&mut m, i);
                    }
                }
                through_centre.push(m);
                for j in 0..LUT_OFFSETS {
                    let rho = (j as f32 + 0.5) / LUT_OFFSETS as f32;
                    let mut m = Bits::default();
                    for (i, p) in samples.iter().enumerate() {
                        if p.dot(n) > rho {
                            bit_set(&mut m, i);
                        }
                    }
                    chords.push(m);
                }
            }
        }
        DiskMask {
            samples,
            eval,
            through_centre,
            chords,
        }
    }

    pub fn len(&self) -> usize {
        self.samples.len()
    }

    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// The look-up tables as the GPU reads them, 128 bits (four `u32`, sample `i` is bit `i % 32`
    /// of word `i / 32`) per mask: the [`LUT_ANGLES`] masks through the centre, then the
    /// [`LUT_ANGLES`] × [`LUT_OFFSETS`] chord masks (angle-major). Empty unless the mask was made
    /// with [`MaskEval::Lut`] and at most 128 samples (what the GPU's counter holds).
    pub fn lut_words(&self) -> Vec<[u32; 4]> {
        if self.eval != MaskEval::Lut || self.samples.len() > 128 {
            return Vec::new();
        }
        let words = |b: &Bits| {
            [
                b[0] as u32,
                (b[0] >> 32) as u32,
                b[1] as u32,
                (b[1] >> 32) as u32,
            ]
        };
        self.through_centre
            .iter()
            .chain(&self.chords)
            .map(words)
            .collect()
    }

    /// Adds `ch.delta` to the counter of every sample in the edge's region; returns whether any
    /// sample was in it.
    pub fn add_region(&self, ch: &EdgeChord, count: &mut [i32]) -> bool {
        match self.eval {
            MaskEval::Exact => {
                let mut any = false;
                for (k, &p) in count.iter_mut().zip(&self.samples) {
                    if ch.contains(p) {
                        *k += ch.delta;
                        any = true;
                    }
                }
                any
            }
            MaskEval::Lut => {
                let bits = self.lut_region(ch);
                for (i, k) in count.iter_mut().enumerate() {
                    if bit(&bits, i) {
                        *k += ch.delta;
                    }
                }
                bits != Bits::default()
            }
        }
    }

    /// The samples in an edge's region, through the look-up tables.
    fn lut_region(&self, ch: &EdgeChord) -> Bits {
        let [a, b, c] = ch.chord;
        let len = (a * a + b * b).sqrt();
        // C < 0: the chord lies at ρ = −C/|(A, B)| > 0 from the centre.
        let rho = -c / len;
        if len.is_nan() || len <= 0.0 || rho.is_nan() || rho >= 1.0 || self.chords.is_empty() {
            return Bits::default();
        }
        let j = ((rho * LUT_OFFSETS as f32) as usize).min(LUT_OFFSETS - 1);
        let beyond = self.chords[lut_bin(a, b) * LUT_OFFSETS + j];
        let sa = self.through_centre[lut_bin(ch.end_a[0], ch.end_a[1])];
        let sb = self.through_centre[lut_bin(ch.end_b[0], ch.end_b[1])];
        and(beyond, xor(sa, sb))
    }
}

/// The unit direction of angle bin `k`: the bins are uniform in the "diamond angle"
/// ([`diamond_angle`]), which a GPU computes with one division where an angle takes an arc
/// tangent.
fn lut_direction(k: usize) -> Vec2 {
    let d = k as f32 / LUT_ANGLES as f32 * 4.0;
    let v = if d < 1.0 {
        Vec2::new(1.0 - d, d)
    } else if d < 2.0 {
        Vec2::new(1.0 - d, 2.0 - d)
    } else if d < 3.0 {
        Vec2::new(d - 3.0, 2.0 - d)
    } else {
        Vec2::new(d - 3.0, d - 4.0)
    };
    v.normalize()
}

/// A monotone stand-in for the angle of `(a, b)`, in `[0, 4)`: the position along the diamond
/// `|u| + |v| = 1` where the ray through `(a, b)` meets it, counter-clockwise from `(1, 0)`.
/// `shaders/methods/dbuffer_fused.wgsl` computes it the same way.
pub fn diamond_angle(a: f32, b: f32) -> f32 {
    let s = a.abs() + b.abs();
    if s.is_nan() || s <= 0.0 {
        return 0.0;
    }
    let (x, y) = (a / s, b / s);
    if y >= 0.0 {
        if x >= 0.0 {
            y
        } else {
            1.0 - x
        }
    } else if x < 0.0 {
        2.0 - y
    } else {
        3.0 + x
    }
}

/// The angle bin of the normal `(a, b)`, rounded to the nearest.
fn lut_bin(a: f32, b: f32) -> usize {
    ((diamond_angle(a, b) * (LUT_ANGLES as f32 / 4.0)).round() as usize) % LUT_ANGLES
}

/// Wraps a layer count to the camera pass's `COUNTER_BITS`-bit two's complement.
fn wrap(v: i32) -> i32 {
    let span = 1 << COUNTER_BITS;
    (v + span / 2).rem_euclid(span) - span / 2
}

/// The result of the mask for one receiver.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaskResult {
    /// Samples visible.
    pub visible: u32,
    pub samples: u32,
    /// `L(c)` as anchored.
    pub anchor: i32,
    /// Edges that changed some sample.
    pub active_edges: u32,
    /// Layers of a crossing (2 for closed casters; 0 when no chord crosses the disk).
    pub layers: u32,
    /// Where every sample sees zero or one layer's worth, the exact visible fraction.
    pub exact: Option<f64>,
}

impl MaskResult {
    /// The visible fraction of the samples.
    pub fn v_samples(&self) -> f64 {
        f64::from(self.visible) / f64::from(self.samples.max(1))
    }

    /// V: exact one layer deep, else the samples' fraction.
    pub fn v(&self) -> f64 {
        self.exact.unwrap_or_else(|| self.v_samples())
    }
}

/// What the camera pass knows of `L(c)`, the layers between `x` and the disk centre.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CentreLayers {
    /// Exactly (the light pass counted the caster surfaces along the ray, and `x` lies beyond
    /// them all).
    Known(i32),
    /// Only whether `x` is hidden from `c` (the D-buffer's `|cx_o|` test).
    Hidden(bool),
}

/// The camera pass's mask over `edges` (any superset of the edges that matter) at `x`.
pub fn mask_visibility<'a>(
    edges: impl IntoIterator<Item = &'a FusedEdge>,
    x: Vec3,
    centre: CentreLayers,
    light: &DiskLight,
    mask: &DiskMask,
) -> MaskResult {
    mask_details(edges, x, centre, light, mask).result
}

/// What the mask saw at one receiver: the result, the chord of every edge that is one there
/// (with its position in the edges given), and each sample's `Δ` (the layers the path from the
/// centre to it crosses, wrapped to the GPU counter's `COUNTER_BITS` bits).
#[derive(Clone, Debug, PartialEq)]
pub struct MaskDetails {
    pub result: MaskResult,
    pub chords: Vec<(usize, EdgeChord)>,
    pub delta: Vec<i32>,
}

/// [`mask_visibility`] with what it saw ([`MaskDetails`]).
pub fn mask_details<'a>(
    edges: impl IntoIterator<Item = &'a FusedEdge>,
    x: Vec3,
    centre: CentreLayers,
    light: &DiskLight,
    mask: &DiskMask,
) -> MaskDetails {
    let n = mask.len();
    let mut count = vec![0i32; n];
    let mut active = 0;
    // ∫Δ over the disk, exactly, and the layers of a crossing.
    let mut integral = 0.0f64;
    let mut layers = 0;
    let mut chords = Vec::new();
    for (k, e) in edges.into_iter().enumerate() {
        let Some(ch) = edge_chord(e, x, light) else {
            continue;
        };
        if ch.area > 0.0 {
            integral += f64::from(ch.delta) * ch.area;
            layers = layers.max(ch.delta.abs());
        }
        if mask.add_region(&ch, &mut count) {
            active += 1;
        }
        chords.push((k, ch));
    }
    let count: Vec<i32> = count.into_iter().map(wrap).collect();
    // The smallest Δ, ignoring up to ANCHOR_SAMPLES − 1 samples below it (the ANCHOR_SAMPLES-th
    // smallest): a sample that a look-up table's quantised line put on the wrong side of one edge
    // of a silhouette and not of its neighbour reads ±layers off, and must not shift every
    // sample's count.
    let min = {
        let mut sorted = count.clone();
        sorted.sort_unstable();
        sorted
            .get(ANCHOR_SAMPLES.min(sorted.len()).max(1) - 1)
            .copied()
            .unwrap_or(0)
    };
    let (floor, hidden) = match centre {
        CentreLayers::Known(k) => (k, k > 0),
        CentreLayers::Hidden(h) => (i32::from(h), h),
    };
    let anchor = (-min).max(floor);
    let visible = count.iter().filter(|&&k| k + anchor <= 0).count() as u32;
    // One layer deep: where every sample sees 0 or `layers` layers (L(c) = `layers` if hidden),
    // the hidden fraction is the mean of L / layers, which the chords give exactly.
    let exact = if layers == 0 {
        Some(if hidden { 0.0 } else { 1.0 })
    } else {
        let lc = match centre {
            CentreLayers::Known(k) => k,
            CentreLayers::Hidden(h) => {
                if h {
                    layers
                } else {
                    0
                }
            }
        };
        count
            .iter()
            .all(|&k| k + lc == 0 || k + lc == layers)
            .then(|| (1.0 - (f64::from(lc) + integral) / f64::from(layers)).clamp(0.0, 1.0))
    };
    MaskDetails {
        result: MaskResult {
            visible,
            samples: n as u32,
            anchor,
            active_edges: active,
            layers: layers as u32,
            exact,
        },
        chords,
        delta: count,
    }
}

/// What the light pass stores for one texel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TexelList {
    /// Edges that passed the test (all of them, as the GPU's counter counts them).
    pub count: usize,
    /// The stored edges (indices into [`FusedTwin::edges`]); empty on overflow.
    pub edges: Vec<u32>,
    /// `count > cap`: the camera pass falls back to `dbuffer`.
    pub overflow: bool,
}

/// The caster surfaces along a D-buffer texel's ray, for `L(c)`: what the light pass counts
/// along the texel's centre ray (additive blend), and the largest height of a crossing over the
/// 3×3 texels around it (max blend, then a 3×3 max).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CasterCrossings {
    pub count: u32,
    pub far_height: f32,
    /// Unit direction of the texel's centre ray.
    pub dir: Vec3,
}

impl CasterCrossings {
    /// `L(c)` for a receiver `x` beyond every crossing: the count along the texel's ray, plus
    /// the layers gained or lost where the ray, swept sideways to `x`'s, passes an edge that is a
    /// silhouette from `c` (an outline of the casters seen from `c`). Those edges are in `x`'s
    /// list: seen from `x` they project next to the disk centre. `None` for a receiver among the
    /// casters.
    pub fn layers_at<'a>(
        &self,
        x: Vec3,
        edges: impl IntoIterator<Item = &'a FusedEdge>,
        light: &DiskLight,
    ) -> Option<i32> {
        let h = light.height_of(x);
        if h.is_nan() || h <= self.far_height * (1.0 + 1e-4) {
            return None;
        }
        let c = light.center;
        let y = c + self.dir * (x - c).length();
        let mut layers = self.count as i32;
        for e in edges {
            if !e.is_silhouette_from(c) {
                continue;
            }
            let m = (e.a - c).cross(e.b - c);
            let fold = m.dot(e.fold);
            let (sx, sy) = (m.dot(x - c), m.dot(y - c));
            // The edge is crossed when the sweep from y to x passes its plane through c within
            // the edge: the segment a–b meets the triangle c, y, x.
            if fold == 0.0
                || (sx > 0.0) == (sy > 0.0)
                || !segment_meets_triangle(e.a, e.b, [c, y, x])
            {
                continue;
            }
            let gained = (sx > 0.0) == (fold > 0.0);
            layers += if gained {
                e.layers as i32
            } else {
                -(e.layers as i32)
            };
        }
        Some(layers)
    }
}

/// The light pass's proxy for one edge: a solid whose projection from the light centre holds every
/// texel direction [`edge_in_texel`] can accept, for receivers no higher than `h_max` (measured
/// from the light plane). Seen from `c`, the edge's wedge up to that height is the edge swept by
/// disks parallel to the light, of radius `(1 − H_p / h_max) r` at an edge point at height `H_p`
/// (the radius is linear along the edge, so the sweep is the convex hull of the two end disks).
/// Here each disk is an octagon around it (grown by `1/cos(π/8)`) plus `pad[k]` metres, the
/// margin for a texel's width at that end. Rasterise the two octagons and the eight quads between
/// their corresponding corners: together they cover the hull's projection.
pub fn wedge_proxy(
    edge: &FusedEdge,
    light: &DiskLight,
    h_max: f32,
    pad: [f32; 2],
) -> [[Vec3; 8]; 2] {
    let (e1, e2) = light.basis();
    let grow = 1.0 / (std::f32::consts::PI / 8.0).cos();
    [(edge.a, pad[0]), (edge.b, pad[1])].map(|(p, pad)| {
        let kappa = (1.0 - light.height_of(p) / h_max).clamp(0.0, 1.0);
        let radius = (kappa * light.radius + pad) * grow;
        std::array::from_fn(|k| {
            let a = k as f32 * std::f32::consts::FRAC_PI_4;
            p + radius * (a.cos() * e1 + a.sin() * e2)
        })
    })
}

/// The light pass's proxy as the GPU draws it: the convex hull, in the light view's normalised
/// device coordinates, of [`wedge_proxy`]'s two octagons projected by `view_proj` (at most 16
/// corners, counter-clockwise). Drawing the hull, not the octagons and quads, draws each texel
/// once per edge, so an edge enters a list at most once. Where a corner lies at or behind the
/// light view's eye plane the projection is not convex: the whole view (`[-1, 1]²`).
pub fn proxy_hull(
    edge: &FusedEdge,
    light: &DiskLight,
    h_max: f32,
    pad: [f32; 2],
    view_proj: &Mat4,
) -> Vec<Vec2> {
    let whole = vec![
        Vec2::new(-1.0, -1.0),
        Vec2::new(1.0, -1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(-1.0, 1.0),
    ];
    let [o0, o1] = wedge_proxy(edge, light, h_max, pad);
    let mut points = Vec::with_capacity(16);
    for p in o0.iter().chain(&o1) {
        let clip = *view_proj * p.extend(1.0);
        if clip.w.is_nan() || clip.w <= 1e-6 {
            return whole;
        }
        let ndc = Vec2::new(clip.x, clip.y) / clip.w;
        if !ndc.is_finite() {
            return whole;
        }
        points.push(ndc);
    }
    hull_2d(points)
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise, without collinear
/// corners.
fn hull_2d(mut points: Vec<Vec2>) -> Vec<Vec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let turn = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let chain = |ordered: &mut dyn Iterator<Item = Vec2>| {
        let mut out: Vec<Vec2> = Vec::new();
        for p in ordered {
            while out.len() >= 2 && turn(out[out.len() - 2], out[out.len() - 1], p) <= 0.0 {
                out.pop();
            }
            out.push(p);
        }
        out.pop();
        out
    };
    let mut hull = chain(&mut points.iter().copied());
    hull.extend(chain(&mut points.iter().rev().copied()));
    hull
}

/// Whether the segment `a b` meets the triangle.
fn segment_meets_triangle(a: Vec3, b: Vec3, tri: [Vec3; 3]) -> bool {
    super::ray::intersect_triangle(a, b - a, &tri).is_some_and(|t| (0.0..=1.0).contains(&t))
}

/// How the fused twin is set up.
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
    /// The texel's list overflowed: the paper's V(t).
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
/// them: only a speed-up of the twin (the GPU rasterises each edge's footprint instead).
struct EdgeBins {
    cells: u32,
    bins: Vec<Vec<u32>>,
}

impl EdgeBins {
    fn build(edges: &[FusedEdge], light: &DiskLight, vp: &Mat4, cells: u32) -> EdgeBins {
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

/// A patch of receiver surface around one texel: a point on it, its unit normal, how far the
/// same surface reaches within the 3×3 texels around (`radius`) and how far it strays from the
/// plane there (`bulge`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    pub point: Vec3,
    pub normal: Vec3,
    pub radius: f32,
    pub bulge: f32,
}

impl Patch {
    /// The range of the plane function `n·p − offset` over the patch.
    fn range(&self, n: Vec3, offset: f32) -> (f32, f32) {
        let f = n.dot(self.point) - offset;
        let spread = self.radius * n.cross(self.normal).length() + self.bulge;
        (f - spread, f + spread)
    }
}

/// The ray of one texel as the light pass's fragment shader sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct TexelRay {
    /// Unit direction from the light centre through the texel's centre.
    pub dir: Vec3,
    /// Where the texel's receivers can be. Receivers are surfaces facing the light centre (the
    /// camera pass shades the others black). `patches`: the first, second and last such surface
    /// along the ray, each with the same receivers of the 3×3 texels around when they lie on the
    /// same surface; `deeper`: a stretch of distances along `dir` for the rest (receivers across
    /// an outline, or between the second and the last of a ray with more than three), converted
    /// from heights.
    pub patches: Vec<Patch>,
    pub deeper: Option<(f32, f32)>,
    /// The largest of them all: where the wedge test is made.
    pub far: f32,
    /// The texel's half-diagonal as a slope (lateral distance per unit of distance from `c`).
    pub half_slope: f32,
}

/// The light pass's test for one edge and one texel (its fragment shader does exactly this):
/// 1. *the wedge*: the point `y` of the ray at `far` sees the edge's projection meet the disk,
///    with a margin for the texel's width: moving `y` sideways by `l` moves the projection of an
///    edge point at height `H_p` by `l · H_p / (H_y − H_p)`. Wedges only grow with depth along a
///    ray from `c`, so this covers every depth up to `far`;
/// 2. *the silhouette*: some receiver of the texel may see one face of the edge in front and
///    the other behind. On the first surface: within the patch's radius of its point (a face
///    function changes by at most the distance); deeper: somewhere on the `deeper` stretch of
///    the ray beyond the edge, where each face function is linear along the ray and moves by at
///    most the pyramid's half-width sideways.
pub fn edge_in_texel(edge: &FusedEdge, ray: &TexelRay, light: &DiskLight) -> bool {
    let c = light.center;
    let along = ray.dir.dot(light.normal);
    if along.is_nan() || along <= 0.0 || ray.far.is_nan() || ray.far <= 0.0 {
        return false;
    }
    let y = c + ray.dir * ray.far;
    let hy = ray.far * along;
    let limit = hy * (1.0 - CLIP);
    let (ha, hb) = (light.height_of(edge.a), light.height_of(edge.b));
    let (mut pa, mut pb) = (edge.a, edge.b);
    let (mut qa, mut qb) = (ha, hb);
    match (ha < limit, hb < limit) {
        (true, true) => {}
        (false, false) => return false,
        (true, false) => {
            pb = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha));
            qb = limit;
        }
        (false, true) => {
            pa = edge.a + (edge.b - edge.a) * ((limit - ha) / (hb - ha));
            qa = limit;
        }
    }
    let (e1, e2) = light.basis();
    // Projection from y onto the light plane, in disk coordinates (metres).
    let project = |p: Vec3, hp: f32| {
        let q = y + (p - y) * (hy / (hy - hp));
        Vec2::new((q - c).dot(e1), (q - c).dot(e2))
    };
    let (sa, sb) = (project(pa, qa), project(pb, qb));
    // The pyramid's half-width at y, measured parallel to the light plane.
    let lateral = ray.far * ray.half_slope / along;
    let amplification = |hp: f32| hp.max(0.0) / (hy - hp);
    let margin = lateral * amplification(qa).max(amplification(qb));
    if distance_to_segment(Vec2::ZERO, sa, sb) > light.radius + margin {
        return false;
    }
    if edge.layers == 1 {
        return true; // an open boundary is a silhouette from everywhere
    }
    // Points of the ray nearer the light than the edge cannot see it in front of the disk.
    let t_edge = ha.min(hb) / along;
    // f_i(t) = f_i(c) + t n_i·w, give or take t · half_slope sideways; "maybe in front":
    // f_i + s t > −tol, "maybe behind": f_i − s t < tol.
    let tol = FACING_TOL * (1.0 + y.abs().max_element() + edge.a.abs().max_element());
    let (f0, g0) = (edge.n0.dot(c) - edge.offset0, edge.n0.dot(ray.dir));
    let (f1, g1) = (edge.n1.dot(c) - edge.offset1, edge.n1.dot(ray.dir));
    let s = ray.half_slope;
    let front = |f: f32, g: f32| positive_on(f + tol, g + s);
    let back = |f: f32, g: f32| positive_on(tol - f, s - g);
    let silhouette = [
        intersect(front(f0, g0), back(f1, g1)),
        intersect(back(f0, g0), front(f1, g1)),
    ];
    let deeper = ray.deeper.is_some_and(|(lo, hi)| {
        let lo = lo.max(t_edge);
        silhouette.iter().any(|&(a, b)| a.max(lo) <= b.min(hi))
    });
    let first = ray.patches.iter().any(|patch| {
        let (lo0, hi0) = patch.range(edge.n0, edge.offset0);
        let (lo1, hi1) = patch.range(edge.n1, edge.offset1);
        let (front0, back0) = (hi0 > -tol, lo0 < tol);
        let (front1, back1) = (hi1 > -tol, lo1 < tol);
        light.height_of(patch.point) + patch.radius > ha.min(hb)
            && ((front0 && back1) || (back0 && front1))
    });
    first || deeper
}

/// The texels of the 3×3 around `texel` inside a `size`-texel grid (the texel itself included).
fn neighbourhood(texel: [u32; 2], size: u32) -> impl Iterator<Item = [i64; 2]> {
    let (tx, ty, size) = (i64::from(texel[0]), i64::from(texel[1]), i64::from(size));
    (-1..=1)
        .flat_map(move |dy| (-1..=1).map(move |dx| [tx + dx, ty + dy]))
        .filter(move |&[x, y]| (0..size).contains(&x) && (0..size).contains(&y))
}

/// Where `alpha + beta t > 0`, as an interval of `t`.
fn positive_on(alpha: f32, beta: f32) -> (f32, f32) {
    if beta > 0.0 {
        (-alpha / beta, f32::INFINITY)
    } else if beta < 0.0 {
        (f32::NEG_INFINITY, -alpha / beta)
    } else if alpha > 0.0 {
        (f32::NEG_INFINITY, f32::INFINITY)
    } else {
        (f32::INFINITY, f32::NEG_INFINITY)
    }
}

fn intersect(a: (f32, f32), b: (f32, f32)) -> (f32, f32) {
    (a.0.max(b.0), a.1.min(b.1))
}

/// The area, as a fraction of the unit disk's, of the part of the disk beyond the segment `p q`
/// as seen from the centre: the disk within the angle `p 0 q`, less the triangle `0 p q`.
pub fn region_area(p: Vec2, q: Vec2) -> f64 {
    let (p, q) = (p.as_dvec2(), q.as_dvec2());
    let cross = p.perp_dot(q);
    if !cross.is_finite() || cross == 0.0 {
        return 0.0;
    }
    let sector = cross.atan2(p.dot(q)) / 2.0;
    ((sector - disk_triangle_area(p, q)) / std::f64::consts::PI).abs()
}

/// Signed area of the unit disk ∩ the triangle (0, p, q).
fn disk_triangle_area(p: glam::DVec2, q: glam::DVec2) -> f64 {
    let sector = |a: glam::DVec2, b: glam::DVec2| a.perp_dot(b).atan2(a.dot(b)) / 2.0;
    let triangle = |a: glam::DVec2, b: glam::DVec2| a.perp_dot(b) / 2.0;
    let (pin, qin) = (p.length_squared() <= 1.0, q.length_squared() <= 1.0);
    if pin && qin {
        return triangle(p, q);
    }
    // |p + t d|² = 1.
    let d = q - p;
    let (a, b, c) = (d.length_squared(), 2.0 * p.dot(d), p.length_squared() - 1.0);
    let disc = b * b - 4.0 * a * c;
    if a == 0.0 || disc <= 0.0 {
        return sector(p, q);
    }
    let root = disc.sqrt();
    let (t1, t2) = ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a));
    let (s1, s2) = (p + d * t1.clamp(0.0, 1.0), p + d * t2.clamp(0.0, 1.0));
    match (pin, qin) {
        (true, false) => triangle(p, s2) + sector(s2, q),
        (false, true) => sector(p, s1) + triangle(s1, q),
        _ if t1 >= 1.0 || t2 <= 0.0 => sector(p, q),
        _ => sector(p, s1) + triangle(s1, s2) + sector(s2, q),
    }
}

fn distance_to_segment(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let d = b - a;
    let len2 = d.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - p).length()
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
    light: DiskLight,
    edges: Vec<FusedEdge>,
    surfaces: Bvh,
    /// Whether each triangle of `surfaces` belongs to a caster.
    is_caster: Vec<bool>,
    caster_bvh: Bvh,
    view: LightView,
    vp: Mat4,
    inv_vp: Mat4,
    /// The view's extent in slope space (x, y): a texel of an `n`-texel grid spans this / `n`.
    view_slope: Vec2,
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
        let edges: Vec<FusedEdge> = prepared
            .meshes
            .iter()
            .zip(&geometry.casters)
            .enumerate()
            .flat_map(|(k, (mesh, g))| candidate_edges(mesh, &g.classes, k as u32))
            .collect();
        let view = LightView::fit(scene);
        let vp = view.view_projection();
        let view_slope = Vec2::new(
            2.0 / view.projection.x_axis.x.abs(),
            2.0 / view.projection.y_axis.y.abs(),
        );
        FusedTwin {
            dbuffer: DBufferTwin::new(scene, &geometry.casters),
            light: scene.light.disk_or_centre(),
            bins: EdgeBins::build(&edges, &scene.light.disk_or_centre(), &vp, 64),
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
            mask: DiskMask::new(params.samples, params.eval),
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
        if list.overflow {
            return FusedSample {
                path: FusedPath::Overflow,
                list_count: list.count,
                ..outside
            };
        }
        let edges = || list.edges.iter().map(|&k| &self.edges[k as usize]);
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
            path: FusedPath::Mask,
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
        let eps = super::oracle::SELF_EPS;
        let mut n = 0;
        self.caster_bvh
            .for_each_hit(x, d, eps, 1.0 - eps, |_| n += 1);
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::classify::classify;
    use crate::geometry::oracle::Oracle;
    use crate::geometry::visibility::disk_segment_fraction;
    use crate::scene::{Camera, Mesh, Object};

    fn light() -> DiskLight {
        DiskLight {
            center: Vec3::new(0.1, 4.0, -0.2),
            normal: Vec3::new(0.05, -1.0, 0.1).normalize(),
            radius: 0.7,
            intensity: 1.0,
        }
    }

    /// A box from its centre and half sizes, as a closed mesh.
    fn slab(centre: Vec3, half: Vec3) -> Mesh {
        let mut m = crate::scene::shapes::cube();
        for p in &mut m.positions {
            *p = centre + *p * 2.0 * half;
        }
        m
    }

    fn scene_of(casters: Vec<Mesh>, light: DiskLight) -> Scene {
        let mut objects: Vec<Object> = casters
            .into_iter()
            .enumerate()
            .map(|(i, mesh)| Object {
                name: format!("caster {i}"),
                mesh,
                casts_shadow: true,
            })
            .collect();
        objects.push(Object {
            name: "ground".into(),
            mesh: slab(Vec3::new(0.0, -0.5, 0.0), Vec3::new(10.0, 0.5, 10.0)),
            casts_shadow: false,
        });
        Scene {
            name: "test".into(),
            camera: Camera {
                eye: Vec3::new(0.0, 3.0, 5.0),
                target: Vec3::ZERO,
                fov_y_deg: 45.0,
            },
            light: light.into(),
            objects,
        }
    }

    fn edges_of(scene: &Scene) -> Vec<FusedEdge> {
        let prepared = PreparedCasters::new(scene);
        prepared
            .meshes
            .iter()
            .enumerate()
            .flat_map(|(k, m)| {
                candidate_edges(m, &classify(m, &scene.light.disk_or_centre()), k as u32)
            })
            .collect()
    }

    /// The chord is where the edge projects from x: every projected point of the edge satisfies
    /// the line's equation, and the chord's negative side holds the disk centre.
    #[test]
    fn chord_is_the_edge_seen_from_the_receiver() {
        let l = light();
        let (e1, e2) = l.basis();
        let x = Vec3::new(0.3, 0.0, 0.4);
        for (a, b) in [
            (Vec3::new(-0.5, 1.5, 0.2), Vec3::new(0.9, 1.7, 0.5)),
            (Vec3::new(0.2, 2.0, -0.4), Vec3::new(0.25, 1.0, 0.6)),
        ] {
            let n = (b - a).cross(x - a).normalize();
            let edge = FusedEdge {
                a,
                b,
                n0: n,
                offset0: n.dot(a) + 1.0, // x behind face 0 ...
                n1: -n,
                offset1: -n.dot(a) - 1.0, // ... and in front of face 1: a silhouette from x
                fold: n,
                layers: 2,
                caster: 0,
            };
            let ch = edge_chord(&edge, x, &l).expect("a silhouette from x");
            let [ca, cb, cc] = ch.chord;
            assert!(cc < 0.0);
            for t in [0.0, 0.3, 0.7, 1.0] {
                let p = a.lerp(b, t);
                let q = x + (p - x) * (l.height_of(x) / (l.height_of(x) - l.height_of(p)));
                let (u, v) = (
                    (q - l.center).dot(e1) / l.radius,
                    (q - l.center).dot(e2) / l.radius,
                );
                let value = ca * u + cb * v + cc;
                assert!(
                    value.abs() < 1e-4 * (ca.abs() + cb.abs() + cc.abs()),
                    "{value}"
                );
            }
        }
    }

    /// One straight edge parallel to the disk: the exact path gives the disk segment beyond the
    /// chord, found by similar triangles.
    #[test]
    fn one_straight_edge_is_exact() {
        let l = DiskLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
        };
        // A wide plate 2 below the light, its edge along z at x = 0, the plate toward −x.
        let plate = slab(Vec3::new(-3.0, 2.0, 0.0), Vec3::new(3.0, 0.01, 3.0));
        let scene = scene_of(vec![plate], l);
        let edges = edges_of(&scene);
        let mask = DiskMask::new(128, MaskEval::Exact);
        for s in [-0.45f32, -0.2, -0.05, 0.1, 0.3, 0.45] {
            let x = Vec3::new(s, 0.0, 0.0);
            // The ray from x through the silhouette edge (the top one, y = 2.01, for s > 0; the
            // bottom one, y = 1.99, for s < 0) meets the light plane at q = s − s·4/(4 − y); the
            // plate hides the disk at x < q.
            let (hx, he) = (4.0f64, if s < 0.0 { 4.0 - 1.99 } else { 4.0 - 2.01 });
            let q = f64::from(s) + (0.0 - f64::from(s)) * hx / (hx - he);
            // The plate hides the part of the disk at x < q (toward −x).
            let expected = 1.0 - disk_segment_fraction(-q / f64::from(l.radius));
            // The ray from x to the centre passes under the plate (two layers) when s < 0.
            let lc = if s < 0.0 { 2 } else { 0 };
            let m = mask_visibility(&edges, x, CentreLayers::Known(lc), &l, &mask);
            let exact = m.exact.expect("one layer deep");
            assert!(
                (exact - expected).abs() < 2e-3,
                "s = {s}: {exact} against {expected}"
            );
            assert!((m.v_samples() - expected).abs() < 0.04, "s = {s}: {m:?}");
        }
    }

    /// Two bars at different heights crossing in the light's view: the method with the oracle's
    /// own samples sees the same samples hidden, where each bar alone would hide a strip.
    #[test]
    fn two_crossing_bars_hide_the_union_of_their_strips() {
        let l = light();
        let scene = scene_of(
            vec![
                slab(Vec3::new(0.0, 2.4, 0.0), Vec3::new(1.5, 0.05, 0.12)),
                slab(Vec3::new(0.1, 1.2, 0.0), Vec3::new(0.1, 0.05, 1.5)),
            ],
            l,
        );
        let edges = edges_of(&scene);
        let oracle = Oracle::from_scene(&scene, 256);
        let mask = DiskMask::new(256, MaskEval::Exact);
        let casters = Bvh::build(
            scene
                .casters()
                .flat_map(|o| o.mesh.triangle_corners())
                .collect(),
        );
        let mut fused_points = 0;
        for i in 0..21 {
            for j in 0..21 {
                let x = Vec3::new(-1.0 + 0.1 * i as f32, 0.0, -1.0 + 0.1 * j as f32);
                let d = l.center - x;
                let mut lc = 0;
                casters.for_each_hit(x, d, 1e-4, 1.0 - 1e-4, |_| lc += 1);
                let m = mask_visibility(&edges, x, CentreLayers::Known(lc), &l, &mask);
                let v = f64::from(oracle.visibility(x));
                assert!(
                    (m.v_samples() - v).abs() <= 2.0 / 256.0,
                    "{x}: {} samples visible, the oracle {v}",
                    m.visible
                );
                fused_points += usize::from(m.exact.is_none() && v > 0.0 && v < 1.0);
            }
        }
        assert!(
            fused_points > 10,
            "points where both bars hide the disk: {fused_points}"
        );
    }

    /// `region_area` against a grid count of the same region.
    #[test]
    fn region_area_matches_a_grid_count() {
        let n = 600;
        for (p, q) in [
            (Vec2::new(-1.5, 0.4), Vec2::new(1.5, 0.3)),
            (Vec2::new(0.2, 0.1), Vec2::new(0.9, -0.6)),
            (Vec2::new(-0.3, 0.5), Vec2::new(0.6, 2.0)),
            (Vec2::new(0.5, 0.5), Vec2::new(0.5, -0.5)),
            (Vec2::new(2.0, 2.0), Vec2::new(3.0, 1.0)),
        ] {
            let (a, b, c) = {
                let n = (q - p).perp();
                let n = if n.dot(-p) > 0.0 { -n } else { n };
                (n.x, n.y, -n.dot(p))
            };
            let ch = EdgeChord {
                chord: [a, b, c],
                end_a: [p.y, -p.x],
                end_b: [q.y, -q.x],
                delta: 2,
                area: 0.0,
                ends: [p, q],
            };
            let mut inside = 0usize;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new(
                        -1.0 + 2.0 * (i as f32 + 0.5) / n as f32,
                        -1.0 + 2.0 * (j as f32 + 0.5) / n as f32,
                    );
                    inside += usize::from(u.length() <= 1.0 && ch.contains(u));
                }
            }
            let grid = inside as f64 * 4.0 / (n * n) as f64 / std::f64::consts::PI;
            let exact = region_area(p, q);
            assert!(
                (grid - exact).abs() < 2e-3,
                "{p} {q}: {exact} against {grid}"
            );
        }
    }

    /// The look-up tables differ from the exact test only on samples next to a line.
    #[test]
    fn lut_masks_agree_with_the_exact_test() {
        let (exact, lut) = (
            DiskMask::new(128, MaskEval::Exact),
            DiskMask::new(128, MaskEval::Lut),
        );
        let mut worst = 0;
        for k in 0..200 {
            let f = k as f32;
            let phi = f * 2.399;
            let rho = (f * 0.618).fract() * 0.95 + 0.02;
            let (s, c) = phi.sin_cos();
            let ch = EdgeChord {
                chord: [c, s, -rho],
                end_a: [(phi + 0.7).sin(), -(phi + 0.7).cos()],
                end_b: [(phi - 1.1).sin(), -(phi - 1.1).cos()],
                delta: 2,
                area: 0.0,
                ends: [Vec2::ZERO; 2],
            };
            let (mut a, mut b) = (vec![0; 128], vec![0; 128]);
            exact.add_region(&ch, &mut a);
            lut.add_region(&ch, &mut b);
            worst = worst.max(a.iter().zip(&b).filter(|(x, y)| x != y).count());
        }
        assert!(worst <= 3, "{worst} samples differ");
    }

    /// A sphere under a light wider than itself: the edges between two silhouette faces are
    /// candidates (they are silhouettes from some disk points) though neither the umbra nor the
    /// penumbra silhouette; edges between two all-frontfacing faces are not.
    #[test]
    fn candidates_include_edges_between_silhouette_faces() {
        let l = DiskLight {
            radius: 1.5,
            ..light()
        };
        let mut sphere = crate::scene::shapes::sphere(24, 12);
        for p in &mut sphere.positions {
            *p = *p * 0.6 + Vec3::new(0.0, 2.0, 0.0);
        }
        let mesh = CasterMesh::new("sphere", &sphere);
        let classes = classify(&mesh, &l);
        let edges = candidate_edges(&mesh, &classes, 0);
        let (mut between_silhouette_faces, mut all_front) = (0, 0);
        for e in &mesh.edges {
            let (c0, c1) = (classes[e.faces[0] as usize], classes[e.faces[1] as usize]);
            let a = mesh.position(e.v[0]);
            let listed = edges
                .iter()
                .any(|f| f.a == a && f.b == mesh.position(e.v[1]));
            if c0.is_silhouette_face() && c1.is_silhouette_face() {
                between_silhouette_faces += 1;
                assert!(listed);
            }
            if c0 == FaceClass::AllFront && c1 == FaceClass::AllFront {
                all_front += 1;
                assert!(!listed);
            }
        }
        assert!(between_silhouette_faces > 20 && all_front > 20);
    }

    /// Every list texel whose test accepts an edge lies inside the projection of the edge's
    /// proxy (what the GPU rasterises), padded by three list texels' footprint: the proxy loses
    /// no list entry. Checked on every texel of a coarse grid over three built-ins.
    #[test]
    fn wedge_proxies_hold_every_accepted_texel() {
        for name in ["fig8c-complex", "overlap", "fusion-many"] {
            let Ok(scene) = crate::scene::load(name) else {
                panic!("{name} loads");
            };
            let prepared = PreparedCasters::new(&scene);
            let geometry = prepared.build(
                &scene.light.disk_or_centre(),
                &crate::geometry::VolumeParams::for_scene(&scene),
            );
            let params = FusedParams {
                list_size: 96,
                ..FusedParams::default()
            };
            let twin = FusedTwin::new(&scene, &prepared, &geometry, params);
            let l = scene.light.disk_or_centre();
            let h_max = scene
                .objects
                .iter()
                .flat_map(|o| o.mesh.positions.iter())
                .map(|&p| l.height_of(p))
                .filter(|h| h.is_finite())
                .fold(0.0, f32::max);
            let half_slope = 0.5 * twin.view_slope.length() / 96.0;
            let vp = twin.vp;
            let project = |p: Vec3| {
                let c = vp * p.extend(1.0);
                Vec2::new(c.x, c.y) / c.w
            };
            let mut accepted = 0;
            for ty in 0..96u32 {
                for tx in 0..96u32 {
                    let Some(ray) = twin.texel_ray_of([tx, ty]) else {
                        continue;
                    };
                    let ndc = project(l.center + ray.dir);
                    for (k, e) in twin.edges().iter().enumerate() {
                        if !edge_in_texel(e, &ray, &l) {
                            continue;
                        }
                        accepted += 1;
                        let pad = [e.a, e.b].map(|p| 3.0 * p.distance(l.center) * half_slope);
                        let [o0, o1] = wedge_proxy(e, &l, h_max, pad);
                        let pts: Vec<Vec2> = o0.iter().chain(&o1).map(|&p| project(p)).collect();
                        assert!(
                            inside_hull(ndc, &pts),
                            "{name}: texel {tx},{ty} accepts edge {k} outside its proxy"
                        );
                        // The polygon the GPU draws (counter-clockwise) holds it too.
                        let poly = proxy_hull(e, &l, h_max, pad, &vp);
                        let inside_polygon = (0..poly.len()).all(|i| {
                            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                            (b - a).perp_dot(ndc - a) >= -1e-6
                        });
                        assert!(
                            poly.len() <= 16 && inside_polygon,
                            "{name}: texel {tx},{ty} accepts edge {k} outside its drawn proxy"
                        );
                    }
                }
            }
            assert!(accepted > 1000, "{name}: {accepted}");
        }
    }

    fn inside_hull(p: Vec2, pts: &[Vec2]) -> bool {
        // Inside the convex hull iff no line through two of the points has all of them on one
        // side and p strictly on the other.
        for (i, &a) in pts.iter().enumerate() {
            for &b in &pts[i + 1..] {
                let side = |q: Vec2| (b - a).perp_dot(q - a);
                let (lo, hi) = pts.iter().fold((0.0f32, 0.0f32), |(lo, hi), &q| {
                    (lo.min(side(q)), hi.max(side(q)))
                });
                let s = side(p);
                if (lo >= -1e-7 && s < -1e-6) || (hi <= 1e-7 && s > 1e-6) {
                    return false;
                }
            }
        }
        true
    }

    /// The light as seen from a point, on the knot's ground where two loops fuse: its layers
    /// give the method's visible samples, each chord's line passes through its projected ends,
    /// and the path says where the mask did not run.
    #[test]
    fn the_light_from_a_point_is_what_the_mask_saw() {
        let Ok(scene) = crate::scene::load("fig8c-complex") else {
            panic!("fig8c-complex loads");
        };
        let prepared = PreparedCasters::new(&scene);
        let geometry = prepared.build(
            &scene.light.disk_or_centre(),
            &crate::geometry::VolumeParams::for_scene(&scene),
        );
        let twin = FusedTwin::new(&scene, &prepared, &geometry, FusedParams::default());
        let (mut masked, mut fused) = (0, 0);
        for i in 0..40 {
            for j in 0..40 {
                let x = Vec3::new(-1.2 + 0.06 * i as f32, 0.0, -1.2 + 0.06 * j as f32);
                let l = twin.light_from(x);
                let s = twin.sample(x);
                assert_eq!((l.v, l.path), (s.v, s.path));
                if l.path != FusedPath::Mask {
                    assert!(l.chords.is_empty() && l.layers.is_empty());
                    continue;
                }
                masked += 1;
                let m = s.mask.expect("the mask ran");
                assert_eq!(l.layers.len(), l.samples.len());
                let lit = l.layers.iter().filter(|&&k| k <= 0).count() as u32;
                assert_eq!(lit, m.visible, "{x}");
                fused += usize::from(l.layers.iter().any(|&k| k > 2));
                for c in &l.chords {
                    let [a, b, cc] = c.chord.chord;
                    let scale = a.abs() + b.abs() + cc.abs();
                    for p in c.chord.ends {
                        let on = a * p.x + b * p.y + cc;
                        assert!(on.abs() <= 1e-3 * scale * (1.0 + p.length()), "{x}: {on}");
                    }
                    assert!(twin.edges()[c.edge as usize].caster == c.caster);
                }
            }
        }
        assert!(masked > 100 && fused > 0, "{masked} masked, {fused} fused");
    }

    #[test]
    fn counters_wrap_like_the_gpus() {
        assert_eq!(wrap(15), 15);
        assert_eq!(wrap(16), -16);
        assert_eq!(wrap(-17), 15);
        assert_eq!(wrap(3 - 4), -1);
    }
}
