//! `dbuffer-fused`: the D-buffer with every silhouette chord a receiver needs, so that the parts
//! of the disk hidden by different casters (or different parts of one caster) combine as they do
//! in reality. `docs/method/dbuffer-fused.md` describes the method, its GPU mapping and what it
//! still gets wrong.
//!
//! The parts, one file each: [`chord`] (the candidate edges and the chord each cuts from the
//! disk), [`mask`] (the camera pass's disk samples, look-up tables and per-sample layer count),
//! [`lists`] (the light pass's per-texel edge lists, caster crossings and edge proxies), [`area`]
//! (the exact area of an edge's region) and [`twin`] (the CPU twin, [`FusedTwin`]: the whole
//! method on the CPU, the model the GPU passes are tested against). Everything public is
//! re-exported here, so callers name `geometry::fused::X`.
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

mod area;
mod candidates;
mod chord;
mod lists;
mod mask;
#[cfg(test)]
mod tests;
mod twin;

pub use area::{region_area, whole_segment};
pub use candidates::{
    covered_rect, edge_proxy, max_receiver_height, proxy_pad, scene_candidate_edges,
};
pub use chord::{candidate_edges, edge_chord, EdgeChord, FusedEdge};
pub use lists::{
    edge_in_texel, proxy_hull, wedge_proxy, CasterCrossings, Patch, TexelList, TexelRay,
};
pub use mask::{
    diamond_angle, mask_details, mask_visibility, Bits, CentreLayers, DiskMask, MaskDetails,
    MaskEval, MaskResult, VPath, LUT_ANGLES, LUT_OFFSETS,
};
pub use twin::{FusedParams, FusedPath, FusedSample, FusedTwin, LightFromPoint, PointChord};

/// Default number of disk samples in the camera pass's mask (four `u32` words per bit plane).
pub const DEFAULT_SAMPLES: usize = 128;

/// Largest mask the look-up tables support (the CPU twin's `[u64; 4]`).
pub const MAX_LUT_SAMPLES: usize = 256;

/// Largest mask the exact evaluation supports.
pub const MAX_SAMPLES: usize = 4096;

/// Default number of edges one list holds: the longest list of Table 1 (`table1-5760`'s rounded
/// box at grazing angles) is 243, which at 128 overflowed on 0.2 % of its pixels; at a 256² list
/// grid the ids take 64 MiB.
pub const DEFAULT_CAP: usize = 256;

/// The most candidate edges a receiver whose list overflowed walks instead of its list (the camera
/// pass's `WHOLE_WALK_EDGES`); with more, it gets the paper's V. Small casters of many edges under
/// a large light overflow (every edge of their silhouette seen from the ground is a chord of the
/// disk), and have few candidates in all.
pub const WHOLE_WALK_EDGES: usize = 4096;

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

/// Where V comes in closed form from one or two chords (each a whole circular segment), `L(c)`
/// is anchored as over the samples ([`ANCHOR_SAMPLES`]), by the smallest `Δ` of the parts of
/// the disk the chords make, leaving out parts smaller than this share of it (the area of
/// `ANCHOR_SAMPLES` − ½ samples of [`DEFAULT_SAMPLES`]).
pub const ANCHOR_SHARE: f64 = (ANCHOR_SAMPLES as f64 - 0.5) / DEFAULT_SAMPLES as f64;

/// The exact V of one convex caster (`1 − (L(c) + ∫Δ) / layers`) is used only within this much
/// of `[0, 1]` before it is clamped: further out, `L(c)` or a chord is off (a receiver at an
/// outline seen from `c`) and the samples decide.
pub const CONVEX_SLACK: f64 = 1e-3;

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
