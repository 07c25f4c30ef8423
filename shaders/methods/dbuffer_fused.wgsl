// `dbuffer-fused`: the D-buffer with every silhouette chord a receiver needs
// (src/render/methods/dbuffer_fused.rs; docs/method/dbuffer-fused.md). Per pixel: its list texel's edges (the
// light pass's lists), each edge's chord as seen from x and its exact area, L(c) from the light
// pass's caster crossings, then V (geometry::fused::VPath): exact where the chords that cut the
// disk are one convex caster's; exact from the parts of the disk where at most two chords cut
// it, each a whole circular segment; else the layers between x and each of 128 disk samples
// added up from the centre (bit-sliced 5-bit counters, a second walk over the list): exact where
// that shows the disk one layer deep, the lit fraction of the samples otherwise. A pixel whose
// list overflowed walks every candidate edge instead (the same V as a list long enough, at more
// cost) where there are at most WHOLE_WALK_EDGES of them; else it gets the paper's V. Its CPU
// twin is FusedTwin::sample (src/geometry/fused/twin.rs) with MaskEval::Lut, function by
// function.
//
// A CPU rasteriser runs a SIMD group of pixels through both sides of every branch, but leaves a
// loop when all of its pixels have: so every piece of work that only some pixels need is a loop
// that runs once for them and not at all for the others (`for k < once(...)`), and a group where
// no pixel needs it skips it.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/fused.wgsl
// #include shared/light_bits.wgsl
// #include shared/frame_tag.wgsl

// DBufferFusedParams of src/render/methods/dbuffer_fused.rs.
struct DBufferFusedParams {
    // The frame tag of d_u and d_p.
    tag: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(1) @binding(2) var<uniform> params: DBufferFusedParams;

// The paper's D-buffer channels, as methods/dbuffer.wgsl binds them (frame tag params.tag).
@group(1) @binding(3) var d_u: texture_2d<f32>;
@group(1) @binding(4) var d_p: texture_2d<f32>;
// Per D-buffer texel: caster crossings along its ray, the largest crossing height over the 3×3
// around it, its list's count, overflow (passes/fused_lists.wgsl, fs_maps).
@group(1) @binding(5) var fused_maps: texture_2d<f32>;
@group(1) @binding(6) var<uniform> fused: FusedUniforms;
@group(1) @binding(7) var<storage, read> edges: array<FusedEdge>;
@group(1) @binding(8) var<storage, read> counts: array<u32>;
@group(1) @binding(9) var<storage, read> lists: array<u32>;
// Half-plane masks of the samples (DiskMask::lut_words): LUT_ANGLES through the centre, then
// LUT_ANGLES × LUT_OFFSETS chords.
@group(1) @binding(10) var<storage, read> lut: array<vec4<u32>>;

// geometry::fused::{ANCHOR_SAMPLES, ANCHOR_SHARE, CONVEX_SLACK}.
const ANCHOR_SAMPLES: u32 = 3u;
const ANCHOR_SHARE: f32 = 0.01953125;
const CONVEX_SLACK: f32 = 1e-3;
const PI: f32 = 3.14159265358979;
// geometry::fused::WHOLE_WALK_EDGES: the most candidate edges a pixel whose list overflowed walks.
const WHOLE_WALK_EDGES: u32 = 4096u;

// The paper's V at the pixel: methods/dbuffer.wgsl's lookup (where the candidate edges are over
// the budget, or a list overflowed and there are more than WHOLE_WALK_EDGES of them).
fn paper_visibility(l: LightLookup, hidden: bool) -> Visibility {
    let d = l.d;
    let xs = frame_untagged(
        select(textureLoad(d_p, l.texel, 0), textureLoad(d_u, l.texel, 0), hidden),
        params.tag
    ).xy;
    let crossed = xs.x > 0.0 && d > xs.x;
    let f = clamp(xs.y * (d - xs.x) / (2.0 * xs.x * (d - xs.y)), 0.0, 0.5);
    var out: Visibility;
    out.t = select(select(1.0, 1.0 - f, crossed), select(0.0, f, crossed), hidden);
    out.branch = select(
        select(BRANCH_LIT, BRANCH_PENUMBRA_VISIBLE, crossed),
        select(BRANCH_UMBRA, BRANCH_PENUMBRA_HIDDEN, crossed),
        hidden
    );
    out.v = v_of_t(out.t);
    return out;
}

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

fn sector(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return atan2(cross2(a, b), dot(a, b)) * 0.5;
}

// Signed area of the unit disk ∩ the triangle (0, p, q) (geometry::fused::disk_triangle_area;
// the segment's crossings with the circle from its distance to the centre, which stays accurate
// in f32 where projected ends lie far outside the disk).
fn disk_triangle_area(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let pin = dot(p, p) <= 1.0;
    let qin = dot(q, q) <= 1.0;
    if pin && qin {
        return cross2(p, q) * 0.5;
    }
    let d = q - p;
    let a = dot(d, d);
    let h2 = cross2(p, q) * cross2(p, q) / a;
    if !(a > 0.0) || !(h2 < 1.0) {
        return sector(p, q);
    }
    let t0 = -dot(p, d) / a;
    let half = sqrt((1.0 - h2) / a);
    let t1 = t0 - half;
    let t2 = t0 + half;
    let s1 = p + d * clamp(t1, 0.0, 1.0);
    let s2 = p + d * clamp(t2, 0.0, 1.0);
    if pin {
        return cross2(p, s2) * 0.5 + sector(s2, q);
    }
    if qin {
        return sector(p, s1) + cross2(s1, q) * 0.5;
    }
    if t1 >= 1.0 || t2 <= 0.0 {
        return sector(p, q);
    }
    return sector(p, s1) + cross2(s1, s2) * 0.5 + sector(s2, q);
}

// Whether the region of the segment p q is a whole circular segment: both ends outside the disk
// and the segment across it (geometry::fused::whole_segment).
fn whole_segment(p: vec2<f32>, q: vec2<f32>) -> bool {
    let c = cross2(p, q);
    let d = q - p;
    let a = dot(d, d);
    let h2 = c * c / a;
    let t0 = -dot(p, d) / a;
    let half = sqrt(max(1.0 - h2, 0.0) / a);
    return dot(p, p) > 1.0 && dot(q, q) > 1.0 && h2 < 1.0 && t0 - half > 0.0 && t0 + half < 1.0;
}

// The part of the disk beyond the segment p q seen from the centre, as a fraction of the disk
// (geometry::fused::region_area).
fn region_area(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let c = cross2(p, q);
    if !(abs(c) > 0.0) || !(abs(c) < 3.0e38) {
        return 0.0;
    }
    // The common case without an arc tangent: a whole circular segment, cut by the line at
    // distance h from the centre (what the general formula gives, in exact arithmetic).
    if whole_segment(p, q) {
        let d = q - p;
        let h2 = c * c / dot(d, d);
        let h = sqrt(h2);
        return (acos(h) - h * sqrt(max(1.0 - h2, 0.0))) / PI;
    }
    return abs((sector(p, q) - disk_triangle_area(p, q)) / PI);
}

// Whether an edge is a silhouette from x: one face in front of x, the other not.
fn edge_silhouette(e: FusedEdge, x: vec3<f32>) -> bool {
    let tol = FUSED_FACING_TOL * (1.0 + fused_max_abs(x) + e.b.w);
    return (dot(e.n0.xyz, x) - e.n0.w > -tol) != (dot(e.n1.xyz, x) - e.n1.w > -tol);
}

// Whether a silhouette edge changes something seen from x: partly nearer the light than x, its
// chord cutting the disk (geometry::fused::edge_chord also makes chords that miss the disk: no
// sample beyond them, area 0).
fn edge_cuts_disk(e: FusedEdge, x: vec3<f32>, hx: f32) -> bool {
    let limit = hx * (1.0 - FUSED_CLIP);
    let near = fused_height(fused, e.a.xyz) < limit || fused_height(fused, e.b.xyz) < limit;
    let m = cross(e.a.xyz - x, e.b.xyz - x);
    let cc = dot(m, fused.center - x);
    let fold = dot(m, e.fold.xyz);
    let ab = fused.radius * vec2<f32>(dot(m, fused.e1), dot(m, fused.e2));
    return near && cc != 0.0 && fold != 0.0 && abs(cc) < 3.0e38 && cc * cc < dot(ab, ab);
}

// An edge seen from x (geometry::fused::EdgeChord): its chord and what a path from the centre
// gains beyond it, the (clipped) edge's ends, and those ends projected onto the light's plane.
struct Chord {
    // A u + B v + C, C < 0 (the centre on the negative side).
    line: vec3<f32>,
    delta: i32,
    pa: vec3<f32>,
    pb: vec3<f32>,
    // The projected ends in unit-disk coordinates (radii along e1, e2).
    ua: vec2<f32>,
    ub: vec2<f32>,
};

// geometry::fused::edge_chord for an edge that cuts the disk (edge_cuts_disk), without its area
// and its sector lines.
fn edge_chord(e: FusedEdge, x: vec3<f32>, hx: f32) -> Chord {
    var out: Chord;
    let limit = hx * (1.0 - FUSED_CLIP);
    let ha = fused_height(fused, e.a.xyz);
    let hb = fused_height(fused, e.b.xyz);
    let c = fused.center;
    let r = fused.radius;
    let m = cross(e.a.xyz - x, e.b.xyz - x);
    let cc = dot(m, c - x);
    let fold = dot(m, e.fold.xyz);
    let ab = r * vec2<f32>(dot(m, fused.e1), dot(m, fused.e2));
    let cut = e.a.xyz + (e.b.xyz - e.a.xyz) * ((limit - ha) / (hb - ha));
    out.pa = select(cut, e.a.xyz, ha < limit);
    out.pb = select(cut, e.b.xyz, hb < limit);
    let layers = i32(e.a.w);
    out.delta = select(layers, -layers, (cc > 0.0) == (fold > 0.0));
    let s = -sign(cc);
    out.line = vec3<f32>(s * ab, s * cc);
    let qa = x + (out.pa - x) * (hx / (hx - fused_height(fused, out.pa)));
    let qb = x + (out.pb - x) * (hx / (hx - fused_height(fused, out.pb)));
    out.ua = vec2<f32>(dot(qa - c, fused.e1), dot(qa - c, fused.e2)) / r;
    out.ub = vec2<f32>(dot(qb - c, fused.e1), dot(qb - c, fused.e2)) / r;
    return out;
}

// The exact area of a chord's region, as a fraction of the light.
fn chord_area(ch: Chord) -> f32 {
    if polygon_light() {
        // The same region of the polygon (camera.light_corners are in metres along e1, e2).
        let r = fused.radius;
        return abs(polygon_edge_coverage(
            camera.light_corners,
            camera.light_corner_count,
            camera.light_area,
            ch.ua * r,
            ch.ub * r
        ));
    }
    return region_area(ch.ua, ch.ub);
}

// The samples in a chord's region (DiskMask::lut_region): beyond the chord, between the lines
// from the centre through the projected ends.
fn lut_region(ch: Chord, x: vec3<f32>) -> vec4<u32> {
    let len = length(ch.line.xy);
    let rho = -ch.line.z / len;
    if !(len > 0.0) || !(rho < 1.0) {
        return vec4<u32>(0u);
    }
    let c = fused.center;
    let r = fused.radius;
    let k1 = cross(c - x, fused.e1);
    let k2 = cross(c - x, fused.e2);
    let end_a = vec2<f32>(r * dot(k1, ch.pa - x), r * dot(k2, ch.pa - x));
    let end_b = vec2<f32>(r * dot(k1, ch.pb - x), r * dot(k2, ch.pb - x));
    let j = min(u32(rho * f32(LUT_OFFSETS)), LUT_OFFSETS - 1u);
    let beyond = lut[LUT_ANGLES + lut_bin(ch.line.xy) * LUT_OFFSETS + j];
    let sa = lut[lut_bin(end_a)];
    let sb = lut[lut_bin(end_b)];
    return beyond & (sa ^ sb);
}

// Whether the segment a b meets the triangle (v0, v1, v2): Möller–Trumbore
// (geometry::ray::intersect_triangle), hit parameter in [0, 1].
fn segment_meets_triangle(a: vec3<f32>, b: vec3<f32>, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> bool {
    let dir = b - a;
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if !(abs(det) >= 1.8807909e-37) {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - v0;
    let u = dot(s, p) * inv;
    if !(u >= 0.0 && u <= 1.0) {
        return false;
    }
    let q = cross(s, e1);
    let v = dot(dir, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = dot(e2, q) * inv;
    return t >= 0.0 && t <= 1.0;
}

// The bit-sliced counters of 128 samples: plane i holds bit i of every sample's 5-bit two's
// complement count (COUNTER_BITS; wrapping like the twin's). Five named planes, never an array
// indexed at run time: a CPU rasteriser keeps them in registers that way.
struct Counter {
    p0: vec4<u32>,
    p1: vec4<u32>,
    p2: vec4<u32>,
    p3: vec4<u32>,
    p4: vec4<u32>,
};

// One plane of a ripple-carry adder: plane `p` plus the constant's bit (`on`) where `bits`.
fn add_plane(p: ptr<function, vec4<u32>>, carry: ptr<function, vec4<u32>>, bits: vec4<u32>, on: bool) {
    let kb = select(vec4<u32>(0u), bits, on);
    let old = *p;
    *p = old ^ kb ^ *carry;
    *carry = (old & kb) | (*carry & (old ^ kb));
}

// Add `delta` to the samples in `bits`.
fn counter_add(c: ptr<function, Counter>, bits: vec4<u32>, delta: i32) {
    let k = u32(delta) & 31u;
    var carry = vec4<u32>(0u);
    var p0 = (*c).p0;
    var p1 = (*c).p1;
    var p2 = (*c).p2;
    var p3 = (*c).p3;
    var p4 = (*c).p4;
    add_plane(&p0, &carry, bits, (k & 1u) != 0u);
    add_plane(&p1, &carry, bits, (k & 2u) != 0u);
    add_plane(&p2, &carry, bits, (k & 4u) != 0u);
    add_plane(&p3, &carry, bits, (k & 8u) != 0u);
    add_plane(&p4, &carry, bits, (k & 16u) != 0u);
    (*c).p0 = p0;
    (*c).p1 = p1;
    (*c).p2 = p2;
    (*c).p3 = p3;
    (*c).p4 = p4;
}

// One plane of an unsigned comparison with a constant, from the top plane down.
fn at_most_plane(u: vec4<u32>, on: bool, lt: ptr<function, vec4<u32>>, eq: ptr<function, vec4<u32>>) {
    if on {
        *lt = *lt | (*eq & ~u);
        *eq = *eq & u;
    } else {
        *eq = *eq & ~u;
    }
}

// The samples whose u = count + 16 (offset binary: unsigned order is the counts' order) is at
// most k.
fn at_most(c: Counter, k: i32) -> vec4<u32> {
    if k < 0 {
        return vec4<u32>(0u);
    }
    if k >= 31 {
        return vec4<u32>(0xffffffffu);
    }
    let b = u32(k);
    var lt = vec4<u32>(0u);
    var eq = vec4<u32>(0xffffffffu);
    at_most_plane(~c.p4, (b & 16u) != 0u, &lt, &eq);
    at_most_plane(c.p3, (b & 8u) != 0u, &lt, &eq);
    at_most_plane(c.p2, (b & 4u) != 0u, &lt, &eq);
    at_most_plane(c.p1, (b & 2u) != 0u, &lt, &eq);
    at_most_plane(c.p0, (b & 1u) != 0u, &lt, &eq);
    return lt | eq;
}

// The samples whose u is exactly k (none outside 0 … 31).
fn equal_to(c: Counter, k: i32) -> vec4<u32> {
    if k < 0 || k > 31 {
        return vec4<u32>(0u);
    }
    let b = u32(k);
    return select(c.p4, ~c.p4, (b & 16u) != 0u)
        & select(~c.p3, c.p3, (b & 8u) != 0u)
        & select(~c.p2, c.p2, (b & 4u) != 0u)
        & select(~c.p1, c.p1, (b & 2u) != 0u)
        & select(~c.p0, c.p0, (b & 1u) != 0u);
}

// One step of the radix select: among `candidates`, those with a 0 in this plane of u if at
// least `rank` have one, else those with a 1 (and the rank among them).
fn select_plane(u: vec4<u32>, bit: i32, candidates: ptr<function, vec4<u32>>, rank: ptr<function, u32>, result: ptr<function, i32>) {
    let zeros = *candidates & ~u;
    let below = popcount(zeros);
    if below >= *rank {
        *candidates = zeros;
    } else {
        *rank -= below;
        *candidates = *candidates & u;
        *result |= bit;
    }
}

fn popcount(v: vec4<u32>) -> u32 {
    let c = countOneBits(v);
    return c.x + c.y + c.z + c.w;
}

// The share of the unit disk beyond the chord at distance h from its centre.
fn segment_share(h: f32) -> f32 {
    let k = clamp(h, -1.0, 1.0);
    return (acos(k) - k * sqrt(max(1.0 - k * k, 0.0))) / PI;
}

// V where at most two chords cut the disk, each a whole circular segment (geometry::fused's
// two_chords): the parts beyond neither, one or both (Jakobsen et al. 2004, §6.3; the part
// beyond both by disk_cut2_area), each delta layers deeper than the centre; L(c) anchored at
// least at floor_c, and no part larger than ANCHOR_SHARE below 0 layers.
fn two_chords(l1: vec3<f32>, d1: i32, l2: vec3<f32>, d2: i32, floor_c: i32) -> f32 {
    let len1 = length(l1.xy);
    let len2 = length(l2.xy);
    let m1 = select(vec2<f32>(1.0, 0.0), l1.xy / len1, len1 > 0.0);
    let m2 = select(vec2<f32>(1.0, 0.0), l2.xy / len2, len2 > 0.0);
    let h1 = select(2.0, -l1.z / len1, len1 > 0.0);
    let h2 = select(2.0, -l2.z / len2, len2 > 0.0);
    let a1 = segment_share(h1);
    let a2 = segment_share(h2);
    let both = disk_cut2_area(m1, h1, m2, h2) / PI;
    let area = vec4<f32>(1.0 - a1 - a2 + both, a1 - both, a2 - both, both);
    let delta = vec4<i32>(0, d1, d2, d1 + d2);
    // The lowest delta of a part larger than ANCHOR_SHARE (0 where none is).
    var lowest = 1048576;
    for (var j = 0u; j < 4u; j++) {
        if area[j] > ANCHOR_SHARE {
            lowest = min(lowest, delta[j]);
        }
    }
    let anchor = max(-select(lowest, 0, lowest == 1048576), floor_c);
    var v = 0.0;
    for (var j = 0u; j < 4u; j++) {
        if delta[j] + anchor <= 0 {
            v += max(area[j], 0.0);
        }
    }
    return clamp(v, 0.0, 1.0);
}

// What the walk over a list knows of L(c) and of the pixel.
struct Centre {
    // The layers between x and c counted along the texel's ray (known: x beyond every crossing)
    // and corrected by the sweep to x's ray.
    count: i32,
    known: bool,
    hidden: bool,
    hx: f32,
};

// What the samples' counters say (FusedTwin::sample's mask): L(c) anchored, the lit samples
// counted; exact where they show the disk one layer deep. V and the path (3: the samples'
// count, 6: one layer deep).
fn mask_result(counter: Counter, k: Centre, layers: i32, integral: f32) -> vec2<f32> {
    // The samples in use (the LUT leaves the others out of every region: they count 0).
    let n_samples = min(fused.samples, 128u);
    let filled = clamp(vec4<i32>(i32(n_samples)) - vec4<i32>(0, 32, 64, 96), vec4<i32>(0), vec4<i32>(32));
    let valid = select((vec4<u32>(1u) << vec4<u32>(filled)) - 1u, vec4<u32>(0xffffffffu), filled == vec4<i32>(32));
    // The ANCHOR_SAMPLES-th smallest count (geometry::fused::ANCHOR_SAMPLES says why not the
    // smallest), bit by bit from the top of u = count + 16: a radix select.
    var candidates = valid;
    var rank = min(ANCHOR_SAMPLES, n_samples);
    var min_u = 0;
    select_plane(~counter.p4, 16, &candidates, &rank, &min_u);
    select_plane(counter.p3, 8, &candidates, &rank, &min_u);
    select_plane(counter.p2, 4, &candidates, &rank, &min_u);
    select_plane(counter.p1, 2, &candidates, &rank, &min_u);
    select_plane(counter.p0, 1, &candidates, &rank, &min_u);
    let floor_c = select(select(0, 1, k.hidden), k.count, k.known);
    let anchor = max(16 - min_u, floor_c);
    let v = f32(popcount(at_most(counter, 16 - anchor) & valid)) / f32(max(n_samples, 1u));
    // One layer deep: every sample sees 0 or `layers` layers; then V is exact.
    let lc = select(select(0, layers, k.hidden), k.count, k.known);
    let one_deep = equal_to(counter, 16 - lc) | equal_to(counter, 16 + layers - lc);
    let exact = clamp(1.0 - (f32(lc) + integral) / f32(max(layers, 1)), 0.0, 1.0);
    return select(vec2<f32>(v, 3.0), vec2<f32>(exact, 6.0), all((one_deep & valid) == valid));
}

// V over a non-empty list of `count` edges starting at `first` (FusedTwin::sample): one walk
// over the list for L(c), the chords' exact areas and what decides the path, then the closed
// forms or the mask. `every`: the list overflowed, and the walk is over every candidate edge
// (ids 0 .. count) instead.
fn listed_visibility(x: vec3<f32>, l: LightLookup, first: u32, count: u32, every: bool, start: Centre) -> f32 {
    var k = start;
    let c = fused.center;
    // L(c) for a receiver beyond every caster crossing of its ray (CasterCrossings::layers_at):
    // the crossings along the D-buffer texel's ray, corrected where the ray, swept sideways to
    // x's, passes an outline seen from c (an edge of the list).
    let y = c + fused_texel_dir(fused, vec2<f32>(l.texel), fused.map_size) * distance(x, c);
    // ∫Δ over the disk, exactly, and the layers of a crossing.
    var integral = 0.0;
    var layers = 0;
    // The chords that cut the disk: how many, whether all one convex caster's, whether each a
    // whole circular segment, and the first two.
    var cuts = 0u;
    var caster = -1.0;
    var convex = true;
    var whole = true;
    var l1 = vec3<f32>(0.0, 0.0, -1.0);
    var l2 = vec3<f32>(0.0, 0.0, -1.0);
    var d1 = 0;
    var d2 = 0;
    // The samples beyond the chords, for where the closed forms do not hold.
    var counter = Counter(vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u));
    // One chord that cuts the disk a round of the outer loop; the pixels of a group skip the
    // other edges each at their own pace in the inner loop, so the rounds are as many as the
    // most such edges in the group, not as the longest list.
    var i = 0u;
    loop {
        var e: FusedEdge;
        var found = false;
        loop {
            if i >= count {
                break;
            }
            e = edges[select(lists[first + min(i, fused.cap - 1u)], i, every)];
            i++;
            count_work(1.0);
            // L(c): the sweep from the texel's ray to x passes the plane through c and an
            // outline seen from c, within the edge.
            let sx = dot(e.mc.xyz, x - c);
            let sy = dot(e.mc.xyz, y - c);
            if k.known && e.fold.w != 0.0 && e.mc.w != 0.0 && (sx > 0.0) != (sy > 0.0) {
                if segment_meets_triangle(e.a.xyz, e.b.xyz, c, y, x) {
                    let n = i32(e.a.w);
                    k.count += select(-n, n, (sx > 0.0) == (e.mc.w > 0.0));
                }
            }
            if edge_silhouette(e, x) && edge_cuts_disk(e, x, k.hx) {
                found = true;
                break;
            }
        }
        if !found {
            break;
        }
        let ch = edge_chord(e, x, k.hx);
        let area = chord_area(ch);
        if area > 0.0 {
            integral += f32(ch.delta) * area;
            layers = max(layers, abs(ch.delta));
        }
        cuts += 1u;
        convex = convex && e.caster.y > 0.5 && (cuts == 1u || e.caster.x == caster);
        caster = e.caster.x;
        whole = whole && whole_segment(ch.ua, ch.ub);
        l1 = select(l1, ch.line, cuts == 1u);
        d1 = select(d1, ch.delta, cuts == 1u);
        l2 = select(l2, ch.line, cuts == 2u);
        d2 = select(d2, ch.delta, cuts == 2u);
        counter_add(&counter, lut_region(ch, x), ch.delta);
    }
    // No chord cuts the disk: all of it is as the centre is.
    var v = select(1.0, 0.0, select(k.hidden, k.count > 0, k.known));
    // One convex caster: one layer deep, V exact from the chords' areas (VPath::Convex).
    let lc = select(select(0, layers, k.hidden), k.count, k.known);
    let one_layer = 1.0 - (f32(lc) + integral) / f32(max(layers, 1));
    let by_convex = convex && (lc == 0 || lc == layers)
        && one_layer >= -CONVEX_SLACK && one_layer <= 1.0 + CONVEX_SLACK;
    // At most two chords, each a whole circular segment (VPath::Chords).
    let by_chords = !by_convex && !polygon_light() && cuts <= 2u && whole;
    let closed = two_chords(l1, d1, l2, d2, select(select(0, 1, k.hidden), k.count, k.known));
    // Else the samples (VPath::OneLayer, VPath::Samples).
    let masked = mask_result(counter, k, layers, integral);
    if layers > 0 {
        v = select(select(masked.x, closed, by_chords), clamp(one_layer, 0.0, 1.0), by_convex);
        took_path(select(select(masked.y, 5.0, by_chords), 2.0, by_convex));
    }
    return v;
}

// What the first draw of the camera pass makes of a pixel (the surfaces drawn twice: fs_first,
// then fs_refine where the first marked): V where its list is empty or overflowed (or none, out
// of the light view or dark), or that it has a list (`listed`).
struct First {
    vis: Visibility,
    listed: bool,
};

// The list texel of a light lookup.
fn list_of(l: LightLookup) -> u32 {
    let size = u32(fused.list_size);
    let lt = vec2<u32>(clamp(floor(l.uv * fused.list_size), vec2<f32>(0.0), vec2<f32>(fused.list_size - 1.0)));
    return lt.y * size + lt.x;
}

// L(c) as the light pass counted it along the D-buffer texel's ray.
fn centre_of(x: vec3<f32>, l: LightLookup, hidden: bool) -> Centre {
    let crossings = textureLoad(fused_maps, l.texel, 0);
    var k: Centre;
    k.hx = fused_height(fused, x);
    k.known = k.hx > crossings.y * (1.0 + 1e-4);
    k.count = i32(crossings.x);
    k.hidden = hidden;
    return k;
}

fn fused_first(x: vec3<f32>, n: vec3<f32>) -> First {
    let l = light_lookup(x, n);
    let hidden = hidden_from_center(l);
    // Outside the fitted frustum no penumbra can reach: lit. Behind the one-sided light, or on
    // a side turned away from the centre: nothing arrives.
    let dark = !in_front_of_light(x) || !faces_light_center(x, n);
    var out: First;
    out.vis = plain(select(1.0, 0.0, dark));
    out.listed = false;
    let live = l.inside && !dark;
    let count = counts[list_of(l)];
    // More candidate edges than the budget (none is on the GPU), or a list over the cap with more
    // candidates than a pixel walks: the paper's V.
    let overflow = fused.all_overflow != 0u || (count > fused.cap && fused.edge_count > WHOLE_WALK_EDGES);
    if live && overflow {
        // With the receiver's horizon, as dbuffer's default (its fans' chords: no corners).
        out.vis = paper_visibility(l, hidden);
        took_path(7.0);
        let horizon = horizon_fraction(x, n);
        if horizon < out.vis.v {
            out.vis = plain(horizon);
        }
    }
    if live && !overflow {
        // An empty list: no chord crosses the disk, all of it is as the centre is. A list over
        // the cap is walked too, over every candidate edge.
        let k = centre_of(x, l, hidden);
        out.vis = plain(select(1.0, 0.0, select(hidden, k.count > 0, k.known)));
        took_path(1.0);
        out.listed = count > 0u;
    }
    return out;
}

// V at a pixel fused_first marked: its list's edges.
fn fused_listed(x: vec3<f32>, n: vec3<f32>) -> Visibility {
    let l = light_lookup(x, n);
    let hidden = hidden_from_center(l);
    let list = list_of(l);
    let count = counts[list];
    let whole = count > fused.cap;
    took_path(1.0);
    let v = listed_visibility(x, l, list * fused.cap, select(count, fused.edge_count, whole), whole, centre_of(x, l, hidden));
    if whole {
        took_path(4.0);
    }
    return plain(v);
}

// The method in one draw (what fs_main of shared/camera.wgsl calls).
fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    let first = fused_first(x, n);
    if first.listed {
        return fused_listed(x, n);
    }
    return first.vis;
}

// The first draw: every pixel's V but a listed one's, which it marks for the second by its depth
// one step (one float) farther than the surface's (reversed depth: smaller). Writing the depth
// puts this draw's depth test after its fragment shader.
struct FirstTargets {
    @location(0) color: vec4<f32>,
    @location(1) data: vec2<f32>,
    @location(2) cost: vec2<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_first(f: SurfaceOut) -> FirstTargets {
    let n = surface_normal(f);
    method_cost = vec2<f32>(0.0);
    let first = fused_first(f.world, n);
    let t = shade(f, n, first.vis);
    var out: FirstTargets;
    out.color = t.color;
    out.data = t.data;
    out.cost = t.cost;
    let z = f.clip.z;
    out.depth = select(z, bitcast<f32>(bitcast<u32>(z) - 1u), first.listed && z > 0.0);
    return out;
}

// The second draw, depth test greater (and its depth written back): only the marked pixels pass,
// and a group of pixels of which none passes runs none of this shader.
@fragment
fn fs_refine(f: SurfaceOut) -> Targets {
    let n = surface_normal(f);
    method_cost = vec2<f32>(0.0);
    return shade(f, n, fused_listed(f.world, n));
}
