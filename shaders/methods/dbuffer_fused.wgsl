// `dbuffer-fused`: the D-buffer with every silhouette chord a receiver needs
// (src/render/methods/dbuffer_fused.rs; docs/method/dbuffer-fused.md). Per pixel: its list texel's edges (the
// light pass's lists), each edge's chord as seen from x, the layers between x and each of 128
// disk samples added up from the centre (bit-sliced 5-bit counters), L(c) from the light pass's
// caster crossings, then V: exact where the disk is one layer deep, else the lit fraction of the
// samples. An overflowing list gets the paper's V. Its CPU twin is FusedTwin::sample
// (src/geometry/fused/twin.rs) with MaskEval::Lut, function by function.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/fused.wgsl
// #include shared/light_bits.wgsl

// The paper's D-buffer channels, as methods/dbuffer.wgsl binds them.
@group(1) @binding(2) var d_u: texture_2d<f32>;
@group(1) @binding(3) var d_p: texture_2d<f32>;
// Per D-buffer texel: caster crossings along its ray, the largest crossing height over the 3×3
// around it, its list's count, overflow (passes/fused_lists.wgsl, fs_maps).
@group(1) @binding(4) var fused_maps: texture_2d<f32>;
@group(1) @binding(5) var<uniform> fused: FusedUniforms;
@group(1) @binding(6) var<storage, read> edges: array<FusedEdge>;
@group(1) @binding(7) var<storage, read> counts: array<u32>;
@group(1) @binding(8) var<storage, read> lists: array<u32>;
// Half-plane masks of the samples (DiskMask::lut_words): LUT_ANGLES through the centre, then
// LUT_ANGLES × LUT_OFFSETS chords.
@group(1) @binding(9) var<storage, read> lut: array<vec4<u32>>;

// geometry::fused::ANCHOR_SAMPLES.
const ANCHOR_SAMPLES: u32 = 3u;
const PI: f32 = 3.14159265358979;

// The paper's V at the pixel: methods/dbuffer.wgsl's lookup (tests/gpu/render_fused.rs holds the
// overflowing pixels to the paper's V).
fn paper_visibility(l: LightLookup, hidden: bool) -> Visibility {
    let d = l.d;
    let xs = select(textureLoad(d_p, l.texel, 0).xy, textureLoad(d_u, l.texel, 0).xy, hidden);
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

// An edge seen from x (geometry::fused::EdgeChord).
struct Chord {
    // A u + B v + C, C < 0 (the centre on the negative side).
    line: vec3<f32>,
    // Lines through the centre and the projected ends.
    end_a: vec2<f32>,
    end_b: vec2<f32>,
    delta: i32,
    area: f32,
};

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

// The part of the disk beyond the segment p q seen from the centre, as a fraction of the disk
// (geometry::fused::region_area).
fn region_area(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let c = cross2(p, q);
    if !(abs(c) > 0.0) || !(abs(c) < 3.0e38) {
        return 0.0;
    }
    // The common case without an arc tangent: both ends outside the disk and the segment across
    // it. The sectors beside the crossings cancel against the sector p 0 q, and the region is the
    // circular segment cut by the line at distance h from the centre (what the general formula
    // gives, in exact arithmetic).
    let d = q - p;
    let a = dot(d, d);
    let h2 = c * c / a;
    let t0 = -dot(p, d) / a;
    let half = sqrt(max(1.0 - h2, 0.0) / a);
    if dot(p, p) > 1.0 && dot(q, q) > 1.0 && h2 < 1.0 && t0 - half > 0.0 && t0 + half < 1.0 {
        let h = sqrt(h2);
        return (acos(h) - h * sqrt(1.0 - h2)) / PI;
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

// geometry::fused::edge_chord for an edge that cuts the disk (edge_cuts_disk).
fn edge_chord(e: FusedEdge, x: vec3<f32>, hx: f32) -> Chord {
    var out: Chord;
    let limit = hx * (1.0 - FUSED_CLIP);
    let ha = fused_height(fused, e.a.xyz);
    let hb = fused_height(fused, e.b.xyz);
    let a_near = ha < limit;
    let b_near = hb < limit;
    let c = fused.center;
    let r = fused.radius;
    let m = cross(e.a.xyz - x, e.b.xyz - x);
    let cc = dot(m, c - x);
    let fold = dot(m, e.fold.xyz);
    let ab = r * vec2<f32>(dot(m, fused.e1), dot(m, fused.e2));
    let cut = e.a.xyz + (e.b.xyz - e.a.xyz) * ((limit - ha) / (hb - ha));
    let pa = select(cut, e.a.xyz, a_near);
    let pb = select(cut, e.b.xyz, b_near);
    let layers = i32(e.a.w);
    out.delta = select(layers, -layers, (cc > 0.0) == (fold > 0.0));
    let s = -sign(cc);
    out.line = vec3<f32>(s * ab, s * cc);
    let k1 = cross(c - x, fused.e1);
    let k2 = cross(c - x, fused.e2);
    out.end_a = vec2<f32>(r * dot(k1, pa - x), r * dot(k2, pa - x));
    out.end_b = vec2<f32>(r * dot(k1, pb - x), r * dot(k2, pb - x));
    let qa = x + (pa - x) * (hx / (hx - fused_height(fused, pa)));
    let qb = x + (pb - x) * (hx / (hx - fused_height(fused, pb)));
    let ua = vec2<f32>(dot(qa - c, fused.e1), dot(qa - c, fused.e2)) / r;
    let ub = vec2<f32>(dot(qb - c, fused.e1), dot(qb - c, fused.e2)) / r;
    if polygon_light() {
        // The same region of the polygon (camera.light_corners are in metres along e1, e2).
        out.area = abs(polygon_edge_coverage(
            camera.light_corners,
            camera.light_corner_count,
            camera.light_area,
            ua * r,
            ub * r
        ));
    } else {
        out.area = region_area(ua, ub);
    }
    return out;
}

// The samples in an edge's region (DiskMask::lut_region).
fn lut_region(ch: Chord) -> vec4<u32> {
    let len = length(ch.line.xy);
    let rho = -ch.line.z / len;
    if !(len > 0.0) || !(rho < 1.0) {
        return vec4<u32>(0u);
    }
    let j = min(u32(rho * f32(LUT_OFFSETS)), LUT_OFFSETS - 1u);
    let beyond = lut[LUT_ANGLES + lut_bin(ch.line.xy) * LUT_OFFSETS + j];
    let sa = lut[lut_bin(ch.end_a)];
    let sb = lut[lut_bin(ch.end_b)];
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

// The mask over a list of `count` edges starting at `first` (FusedTwin::sample's Mask path).
fn mask_visibility(x: vec3<f32>, l: LightLookup, hidden: bool, first: u32, count: u32) -> f32 {
    // L(c) for a receiver beyond every caster crossing of its ray (CasterCrossings::layers_at):
    // the crossings along the D-buffer texel's ray, corrected where the ray, swept sideways to
    // x's, passes an outline seen from c (an edge of the list).
    let c = fused.center;
    let crossings = textureLoad(fused_maps, l.texel, 0);
    let hx = fused_height(fused, x);
    let known = hx > crossings.y * (1.0 + 1e-4);
    let y = c + fused_texel_dir(fused, vec2<f32>(l.texel), fused.map_size) * distance(x, c);
    var centre = i32(crossings.x);
    var counter = Counter(vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u), vec4<u32>(0u));
    // ∫Δ over the disk, exactly, and the layers of a crossing.
    var integral = 0.0;
    var layers = 0;
    // The chord of an edge that cuts the disk (its ends, area and samples) is made one per round
    // of the outer loop. A CPU rasteriser runs a SIMD group of pixels through both sides of every
    // branch but leaves a loop when all its pixels have: so the pixels skip the other edges each
    // at their own pace in the inner loop, and the rounds are as many as the most such edges in
    // the group, not as the longest list.
    var i = 0u;
    loop {
        var e: FusedEdge;
        var found = false;
        loop {
            if i >= count {
                break;
            }
            e = edges[lists[first + i]];
            i++;
            count_work(1.0);
            // L(c): the sweep from the texel's ray to x passes the plane through c and an
            // outline seen from c, within the edge.
            let sx = dot(e.mc.xyz, x - c);
            let sy = dot(e.mc.xyz, y - c);
            if known && e.fold.w != 0.0 && e.mc.w != 0.0 && (sx > 0.0) != (sy > 0.0) {
                if segment_meets_triangle(e.a.xyz, e.b.xyz, c, y, x) {
                    let k = i32(e.a.w);
                    centre += select(-k, k, (sx > 0.0) == (e.mc.w > 0.0));
                }
            }
            var cuts = false;
            if edge_silhouette(e, x) {
                cuts = edge_cuts_disk(e, x, hx);
            }
            if cuts {
                found = true;
                break;
            }
        }
        if !found {
            break;
        }
        let ch = edge_chord(e, x, hx);
        if ch.area > 0.0 {
            integral += f32(ch.delta) * ch.area;
            layers = max(layers, abs(ch.delta));
        }
        counter_add(&counter, lut_region(ch), ch.delta);
    }
    let hidden_c = select(hidden, centre > 0, known);
    // No chord cuts the disk: all of it is as the centre is.
    var v = select(1.0, 0.0, hidden_c);
    took_path(1.0);
    if layers > 0 {
        took_path(3.0);
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
        let floor_c = select(select(0, 1, hidden), centre, known);
        let anchor = max(16 - min_u, floor_c);
        v = f32(popcount(at_most(counter, 16 - anchor) & valid)) / f32(max(n_samples, 1u));
        // One layer deep: every sample sees 0 or `layers` layers; then V is exact.
        let lc = select(select(0, layers, hidden), centre, known);
        let one_deep = equal_to(counter, 16 - lc) | equal_to(counter, 16 + layers - lc);
        if all((one_deep & valid) == valid) {
            v = clamp(1.0 - (f32(lc) + integral) / f32(layers), 0.0, 1.0);
            took_path(2.0);
        }
    }
    return v;
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    let l = light_lookup(x, n);
    let hidden = hidden_from_center(l);
    // Outside the fitted frustum no penumbra can reach: lit. Behind the one-sided light, or on
    // a side turned away from the centre: nothing arrives.
    let dark = !in_front_of_light(x) || !faces_light_center(x, n);
    var out = plain(select(1.0, 0.0, dark));
    if l.inside && !dark {
        let size = u32(fused.list_size);
        let lt = vec2<u32>(clamp(floor(l.uv * fused.list_size), vec2<f32>(0.0), vec2<f32>(fused.list_size - 1.0)));
        let list = lt.y * size + lt.x;
        let count = counts[list];
        let overflow = count > fused.cap || fused.all_overflow != 0u;
        if overflow {
            // With the receiver's horizon, as dbuffer's default (its fans' chords: no corners).
            out = paper_visibility(l, hidden);
            took_path(4.0);
            let horizon = horizon_fraction(x, n);
            if horizon < out.v {
                out = plain(horizon);
            }
        } else {
            out = plain(mask_visibility(x, l, hidden, list * fused.cap, count));
        }
    }
    return out;
}
