// The D-buffer's geometry stage on the GPU (render::passes::geometry_gpu): for one caster and
// one planar light, the face classes, the umbra and penumbra silhouettes, their extrusion points,
// the volume quads, the closing fans and the silhouette faces, written as the light pass's volume
// vertices (render::VolumeVertex, nine words each) with an atomic count per volume. The same
// arithmetic as the CPU stage, in the same order (src/geometry/classify.rs, silhouette.rs,
// outline.rs, volumes.rs, volumes/fans.rs, volume_vertices.rs), so that the classes and the
// silhouettes are the CPU's exactly; tests/gpu/geometry_gpu.rs holds the two together.
//
// Entry points, one dispatch each in this order: classify (a thread per face), edges (a thread
// per edge: silhouettes, extrusion points, quads, the ends scattered to their vertices), fans (a
// thread per vertex: pairs the ends there and closes both volumes), faces (a thread per face:
// the silhouette faces), finish (one thread: the budget and the indirect draws' arguments).

struct GeomParams {
    center: vec3<f32>,
    radius: f32,
    normal: vec3<f32>,
    far: f32,
    basis_u: vec3<f32>,
    // The radius the faces are classified against (0: the centre alone, dbuffer-center).
    class_radius: f32,
    basis_w: vec3<f32>,
    // Largest angle of a disk fan's triangle, in radians (at least 1e-3).
    fan_step: f32,
    // A polygon light's corners (xyz), counter-clockwise.
    corners: array<vec4<f32>, 16>,
    // faces, edges, vertices, corner count (0: a disk)
    counts: vec4<u32>,
    // classified as a polygon (0: as a disk), convex solid, umbra capacity, penumbra capacity
    // (triangles)
    flags: vec4<u32>,
    // the budget of volume triangles, the first corner's number, corners this caster may store,
    // whether the umbra is ended at its reach
    limits: vec4<u32>,
    // umbra reach, penumbra reach (heights below the light's plane; < 0: not ended), -, -
    reach: vec4<f32>,
};

@group(0) @binding(0) var<uniform> P: GeomParams;
@group(0) @binding(1) var<storage, read> topo: array<u32>;
@group(0) @binding(2) var<storage, read> geo: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> work: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> out_umbra: array<u32>;
@group(0) @binding(5) var<storage, read_write> out_penumbra: array<u32>;
@group(0) @binding(6) var<storage, read_write> state: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> corner_out: array<vec4<f32>>;

// state words
const S_UMBRA: u32 = 0u;
const S_PENUMBRA: u32 = 1u;
const S_CORNERS: u32 = 2u;
const S_REFUSED: u32 = 3u;
const S_WANTED: u32 = 4u;
const S_ALL_FRONT: u32 = 5u;
const S_NONE_FRONT: u32 = 6u;
const S_SIL_A: u32 = 7u;
const S_SIL_B: u32 = 8u;
const S_UMBRA_EDGES: u32 = 9u;
const S_PENUMBRA_EDGES: u32 = 10u;
const S_FANS: u32 = 11u;
const S_UMBRA_FANS: u32 = 12u;
const S_UNEXTRUDED: u32 = 13u;
const S_UMBRA_MADE: u32 = 14u;
const S_PENUMBRA_MADE: u32 = 15u;
const S_ARGS_UMBRA: u32 = 16u;
const S_ARGS_PENUMBRA: u32 = 20u;

const NO_FACE: u32 = 0xffffffffu;
const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
const MAX_ENDS: u32 = 64u;
const MAX_ARC_POINTS: u32 = 64u;
const ARC_SLACK: f32 = 1e-3;
const CORNER_CHECK_VERTICES: u32 = 4096u;
const TEXELS_PER_CORNER: u32 = 9u;
const MAX_CORNERS: u32 = 458752u;

fn faces() -> u32 { return P.counts.x; }
fn edges() -> u32 { return P.counts.y; }
fn vertices() -> u32 { return P.counts.z; }

fn thread_id(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

fn position(v: u32) -> vec3<f32> { return geo[v].xyz; }
fn plane(f: u32) -> vec4<f32> { return geo[vertices() + f]; }
fn face_vertex(f: u32, k: u32) -> u32 { return topo[4u * f + k]; }
fn edge_word(e: u32, k: u32) -> u32 { return topo[4u * faces() + 4u * e + k]; }
fn vertex_run(v: u32) -> u32 { return topo[4u * faces() + 4u * edges() + v]; }

// work regions
fn class_at(f: u32) -> u32 { return atomicLoad(&work[f]); }
fn count_word(vol: u32, v: u32) -> u32 { return faces() + vol * vertices() + v; }
fn slot_word(vol: u32, s: u32) -> u32 { return faces() + 2u * vertices() + vol * 2u * edges() + s; }
fn point_word(e: u32, vol: u32) -> u32 {
    return faces() + 2u * vertices() + 4u * edges() + 4u * (2u * e + vol);
}
fn store_point(e: u32, vol: u32, p: vec3<f32>, flag: u32) {
    let w = point_word(e, vol);
    atomicStore(&work[w], bitcast<u32>(p.x));
    atomicStore(&work[w + 1u], bitcast<u32>(p.y));
    atomicStore(&work[w + 2u], bitcast<u32>(p.z));
    atomicStore(&work[w + 3u], flag);
}
fn load_point(e: u32, vol: u32) -> vec3<f32> {
    let w = point_word(e, vol);
    return vec3<f32>(
        bitcast<f32>(atomicLoad(&work[w])),
        bitcast<f32>(atomicLoad(&work[w + 1u])),
        bitcast<f32>(atomicLoad(&work[w + 2u]))
    );
}

// glam's arithmetic, written out so the order is the CPU's.
fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 { return a.x * b.x + a.y * b.y + a.z * b.z; }
fn len3(a: vec3<f32>) -> f32 { return sqrt(dot3(a, a)); }
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}
fn normalize_or_zero(a: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / len3(a);
    if is_finite(rcp) && rcp > 0.0 {
        return a * rcp;
    }
    return vec3<f32>(0.0);
}
// Rust's f32::signum: 1 for +0, -1 for -0.
fn signum(x: f32) -> f32 {
    if x != x {
        return x;
    }
    return select(1.0, -1.0, (bitcast<u32>(x) & 0x80000000u) != 0u);
}
fn corner(i: u32) -> vec3<f32> { return P.corners[i].xyz; }

// --- classify (geometry::classify, outline::plane_range) ---

@compute @workgroup_size(64)
fn classify(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let f = thread_id(gid, groups);
    if f >= faces() {
        return;
    }
    let pl = plane(f);
    let normal = pl.xyz;
    let fc = dot3(normal, P.center) - pl.w;
    var lo: f32;
    var hi: f32;
    if P.flags.x == 0u {
        let n_perp = normal - dot3(normal, P.normal) * P.normal;
        let reach = P.class_radius * len3(n_perp);
        lo = fc - reach;
        hi = fc + reach;
    } else {
        lo = 1e38;
        hi = -1e38;
        var first = true;
        for (var i = 0u; i < P.counts.w; i++) {
            let v = fc + dot3(normal, corner(i) - P.center);
            // f32::min / max: a NaN loses to a number.
            if first {
                lo = v;
                hi = v;
                first = false;
            } else {
                if v < lo || lo != lo { lo = v; }
                if v > hi || hi != hi { hi = v; }
            }
        }
    }
    var cls = 3u;
    if lo > 0.0 {
        cls = 0u;
    } else if hi <= 0.0 {
        cls = 1u;
    } else if fc < 0.0 {
        cls = 2u;
    }
    atomicStore(&work[f], cls);
    atomicAdd(&state[S_ALL_FRONT + cls], 1u);
}

// --- extrusion points (outline::tangent_points, silhouette::extrusion_points) ---

struct Tangents {
    ok: bool,
    t0: vec3<f32>,
    t1: vec3<f32>,
};

fn try_normalize(a: vec3<f32>) -> vec4<f32> {
    let rcp = 1.0 / len3(a);
    if is_finite(rcp) && rcp > 0.0 {
        return vec4<f32>(a * rcp, 1.0);
    }
    return vec4<f32>(0.0);
}

fn disk_tangents(v1: vec3<f32>, v2: vec3<f32>) -> Tangents {
    var none: Tangents;
    none.ok = false;
    let c = P.center;
    let n = P.normal;
    let r = P.radius;
    let dir = v2 - v1;
    let len = len3(dir);
    if len != len || len <= 0.0 || r != r || r <= 0.0 {
        return none;
    }
    let denom = dot3(dir, n);
    if abs(denom) <= 1e-6 * len {
        let side = try_normalize(cross3(dir, n));
        if side.w == 0.0 {
            return none;
        }
        return Tangents(true, c + r * side.xyz, c - r * side.xyz);
    }
    let a = v1 + dir * (-dot3(v1 - c, n) / denom);
    var ac = a - c;
    ac = ac - dot3(ac, n) * n;
    let d = len3(ac);
    if !is_finite(d) || d <= r * (1.0 + 1e-5) {
        return none;
    }
    let u = ac / d;
    let w = cross3(n, u);
    let cs = r / d;
    let sn = sqrt(max(1.0 - cs * cs, 0.0));
    return Tangents(true, c + r * (cs * u + sn * w), c + r * (cs * u - sn * w));
}

fn polygon_tangents(v1: vec3<f32>, v2: vec3<f32>) -> Tangents {
    var none: Tangents;
    none.ok = false;
    let d4 = try_normalize(v2 - v1);
    if d4.w == 0.0 {
        return none;
    }
    let dir = d4.xyz;
    let toward = P.center - v1;
    let e14 = try_normalize(toward - dir * dot3(toward, dir));
    if e14.w == 0.0 {
        return none;
    }
    let e1 = e14.xyz;
    let e2 = cross3(dir, e1);
    var lo = 1e38;
    var lo_i = 0u;
    var hi = -1e38;
    var hi_i = 0u;
    for (var i = 0u; i < P.counts.w; i++) {
        let q = corner(i) - v1;
        let a = atan2(dot3(q, e2), dot3(q, e1));
        if !is_finite(a) {
            return none;
        }
        if a < lo {
            lo = a;
            lo_i = i;
        }
        if a > hi {
            hi = a;
            hi_i = i;
        }
    }
    if hi - lo >= PI * (1.0 - 1e-5) {
        return none;
    }
    return Tangents(true, corner(hi_i), corner(lo_i));
}

fn tangent_points(v1: vec3<f32>, v2: vec3<f32>) -> Tangents {
    if P.counts.w == 0u {
        return disk_tangents(v1, v2);
    }
    return polygon_tangents(v1, v2);
}

fn same_side(v1: vec3<f32>, v2: vec3<f32>, t: vec3<f32>, caster_side: vec3<f32>) -> f32 {
    let n = cross3(v2 - v1, t - v1);
    return signum(dot3(n, P.center - v1)) * dot3(n, caster_side - v1);
}

// --- volume vertices (volumes::push_polygon, volume_vertices::volume_vertices_within) ---

struct Attrs {
    kind: u32,
    edge_a: vec3<f32>,
    edge_b: vec3<f32>,
    extrusion: vec3<f32>,
    // A fan's corner marker (x < -1), or 0: the lit side.
    marker: f32,
};

struct Out {
    p: vec3<f32>,
    num: f32,
    den: f32,
};

fn is_umbra(kind: u32) -> bool {
    return kind == 0u || kind == 1u || kind == 2u || kind == 5u;
}

fn lit_side(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec2<f32> {
    let n = cross3(b - a, c - a);
    let m = vec2<f32>(dot3(n, P.basis_u), dot3(n, P.basis_w));
    let rcp = 1.0 / sqrt(m.x * m.x + m.y * m.y);
    if is_finite(rcp) && rcp > 0.0 {
        return m * rcp;
    }
    return vec2<f32>(0.0);
}

fn write_vertex(umbra: bool, at: u32, v: Out, kind: u32, base: f32, side: vec2<f32>) {
    let w = 9u * at;
    var words = array<u32, 9>(
        bitcast<u32>(v.p.x), bitcast<u32>(v.p.y), bitcast<u32>(v.p.z), kind,
        bitcast<u32>(base), bitcast<u32>(v.num), bitcast<u32>(v.den),
        bitcast<u32>(side.x), bitcast<u32>(side.y)
    );
    for (var k = 0u; k < 9u; k++) {
        if umbra {
            out_umbra[w + k] = words[k];
        } else {
            out_penumbra[w + k] = words[k];
        }
    }
}

// Append `n` (1 or 2) triangles of `t` (corners in order) to a volume.
fn append(umbra: bool, tri: array<Out, 4>, n: u32, kind: u32, base: f32, side: vec2<f32>) {
    var t = tri;
    var at: u32;
    var cap: u32;
    if umbra {
        at = atomicAdd(&state[S_UMBRA], n);
        cap = P.flags.z;
    } else {
        at = atomicAdd(&state[S_PENUMBRA], n);
        cap = P.flags.w;
    }
    if at + n > cap {
        return;
    }
    for (var k = 0u; k < n; k++) {
        let v = 3u * (at + k);
        write_vertex(umbra, v, t[0], kind, base, side);
        write_vertex(umbra, v + 1u, t[k + 1u], kind, base, side);
        write_vertex(umbra, v + 2u, t[k + 2u], kind, base, side);
    }
}

fn height(p: vec3<f32>) -> f32 { return dot3(P.normal, p - P.center); }

// One volume triangle (its corners wound as drawn): its vertices' |cx_s| terms, ended at the
// volume's reach (volume_vertices::clip_into), appended.
fn emit(q0: vec3<f32>, q1: vec3<f32>, q2: vec3<f32>, at: Attrs) {
    let umbra = is_umbra(at.kind);
    if umbra {
        atomicAdd(&state[S_UMBRA_MADE], 1u);
    } else {
        atomicAdd(&state[S_PENUMBRA_MADE], 1u);
    }
    atomicAdd(&state[S_WANTED], 1u);
    let c = P.center;
    let n = P.normal;
    let a = at.edge_a;
    let p = at.extrusion;
    let along = normalize_or_zero(at.edge_b - a);
    let w = (p - a) - along * dot3(p - a, along);
    let pa = p - a;
    let ratio = dot3(w, w) > 1e-12 * max(dot3(pa, pa), 1e-30);
    var side = lit_side(q0, q1, q2);
    if at.marker < -1.0 {
        side = vec2<f32>(at.marker, 0.0);
    }
    var base: f32;
    var t: array<Out, 3>;
    var qs = array<vec3<f32>, 3>(q0, q1, q2);
    if ratio {
        let k = dot3(a - p, w);
        base = dot3(p - c, n);
        for (var i = 0u; i < 3u; i++) {
            t[i] = Out(qs[i], dot3(qs[i] - p, n) * k, dot3(qs[i] - p, w));
        }
    } else {
        base = dot3(a - c, n);
        for (var i = 0u; i < 3u; i++) {
            t[i] = Out(qs[i], 0.0, 1.0);
        }
    }
    var reach = P.reach.y;
    if umbra {
        reach = select(-1.0, P.reach.x, P.limits.w != 0u);
    }
    var poly: array<Out, 4>;
    if reach < 0.0 {
        poly[0] = t[0];
        poly[1] = t[1];
        poly[2] = t[2];
        append(umbra, poly, 1u, at.kind, base, side);
        return;
    }
    var h = array<f32, 3>(height(q0) - reach, height(q1) - reach, height(q2) - reach);
    if h[0] <= 0.0 && h[1] <= 0.0 && h[2] <= 0.0 {
        poly[0] = t[0];
        poly[1] = t[1];
        poly[2] = t[2];
        append(umbra, poly, 1u, at.kind, base, side);
        return;
    }
    if h[0] > 0.0 && h[1] > 0.0 && h[2] > 0.0 {
        return;
    }
    var m = 0u;
    for (var k = 0u; k < 3u; k++) {
        let j = (k + 1u) % 3u;
        let hp = h[k];
        let hq = h[j];
        if hp <= 0.0 {
            poly[m] = t[k];
            m++;
        }
        if (hp <= 0.0) != (hq <= 0.0) {
            let s = hp / (hp - hq);
            let pp = t[k].p;
            let qp = t[j].p;
            poly[m] = Out(
                pp + (qp - pp) * s,
                t[k].num + (t[j].num - t[k].num) * s,
                t[k].den + (t[j].den - t[k].den) * s
            );
            m++;
        }
    }
    if m >= 3u {
        append(umbra, poly, m - 2u, at.kind, base, side);
    }
}

// volumes::VolumeMesh::push_polygon for a triangle or a quad: wound toward c or away from it.
fn push_polygon(corners: array<vec3<f32>, 4>, n: u32, at: Attrs, toward_c: bool) {
    var q = corners;
    let normal = cross3(q[1] - q[0], q[2] - q[0]);
    let flip = (dot3(normal, P.center - q[0]) > 0.0) != toward_c;
    for (var k = 1u; k + 1u < n; k++) {
        if flip {
            emit(q[0], q[k + 1u], q[k], at);
        } else {
            emit(q[0], q[k], q[k + 1u], at);
        }
    }
}

fn extrude_away(v: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    return v + normalize_or_zero(v - p) * P.far;
}

// --- silhouettes, quads and ends (silhouette::silhouette_edge, volumes::build_caster_within) ---

fn opposite_vertex(f: u32, e0: u32, e1: u32) -> vec3<f32> {
    var k = face_vertex(f, 0u);
    for (var i = 0u; i < 3u; i++) {
        let v = face_vertex(f, i);
        if v != e0 && v != e1 {
            k = v;
            break;
        }
    }
    return position(k);
}

@compute @workgroup_size(64)
fn edges_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = thread_id(gid, groups);
    if e >= edges() {
        return;
    }
    let i0 = edge_word(e, 0u);
    let i1 = edge_word(e, 1u);
    let f0 = edge_word(e, 2u);
    let f1 = edge_word(e, 3u);
    let c0 = class_at(f0);
    var c1 = c0 ^ 1u;
    if f1 != NO_FACE {
        c1 = class_at(f1);
    }
    let umbra = (c0 == 1u) != (c1 == 1u);
    let penumbra = (c0 == 0u) != (c1 == 0u);
    store_point(e, 0u, vec3<f32>(0.0), 0u);
    store_point(e, 1u, vec3<f32>(0.0), 0u);
    if !umbra && !penumbra {
        return;
    }
    if umbra {
        atomicAdd(&state[S_UMBRA_EDGES], 1u);
    }
    if penumbra {
        atomicAdd(&state[S_PENUMBRA_EDGES], 1u);
    }
    let a = position(i0);
    let b = position(i1);
    let mid = 0.5 * (a + b);
    let along = normalize_or_zero(b - a);
    let d0 = opposite_vertex(f0, i0, i1) - mid;
    var inward = normalize_or_zero(d0 - dot3(d0, along) * along);
    if f1 != NO_FACE {
        let normals = plane(f0).xyz + plane(f1).xyz;
        let d1 = opposite_vertex(f1, i0, i1) - mid;
        inward = inward + (normalize_or_zero(d1 - dot3(d1, along) * along) - normals);
    }
    let caster_side = mid + inward * len3(b - a);
    let t = tangent_points(a, b);
    if !t.ok {
        atomicAdd(&state[S_UNEXTRUDED], 1u);
        // Flagged silhouette without a volume (bit 2).
        store_point(e, 0u, vec3<f32>(0.0), select(0u, 1u, umbra) | 4u);
        store_point(e, 1u, vec3<f32>(0.0), select(0u, 1u, penumbra) | 4u);
        return;
    }
    var pu = t.t1;
    var pp = t.t0;
    if same_side(a, b, t.t0, caster_side) >= same_side(a, b, t.t1, caster_side) {
        pu = t.t0;
        pp = t.t1;
    }
    store_point(e, 0u, pu, select(0u, 1u, umbra));
    store_point(e, 1u, pp, select(0u, 1u, penumbra));
    for (var vol = 0u; vol < 2u; vol++) {
        let on = select(penumbra, umbra, vol == 0u);
        if !on {
            continue;
        }
        let p = select(pp, pu, vol == 0u);
        let kind = select(3u, 0u, vol == 0u);
        let q = array<vec3<f32>, 4>(a, b, extrude_away(b, p), extrude_away(a, p));
        push_polygon(q, 4u, Attrs(kind, a, b, p, 0.0), vol != 0u);
        // The ends, walked with the volume's inside face (none-front, all-front) on the left.
        let inside = select(0u, 1u, vol == 0u);
        var v_from = i0;
        var v_to = i1;
        if c0 != inside {
            v_from = i1;
            v_to = i0;
        }
        let sf = vertex_run(v_from) + atomicAdd(&work[count_word(vol, v_from)], 1u);
        atomicStore(&work[slot_word(vol, sf)], (e << 1u) | 1u);
        let st = vertex_run(v_to) + atomicAdd(&work[count_word(vol, v_to)], 1u);
        atomicStore(&work[slot_word(vol, st)], e << 1u);
    }
}

// --- closing fans (volumes::fans) ---

fn other_end(e: u32, v: u32) -> vec3<f32> {
    let i0 = edge_word(e, 0u);
    return position(select(i0, edge_word(e, 1u), i0 == v));
}

fn face_normal_or_zero(f: u32) -> vec3<f32> {
    if f == NO_FACE || f >= faces() {
        return vec3<f32>(0.0);
    }
    return plane(f).xyz;
}

fn angle_of(p: vec3<f32>) -> f32 {
    let d = p - P.center;
    return atan2(dot3(d, P.basis_w), dot3(d, P.basis_u));
}

fn outward_dir(apex: vec3<f32>, far: vec3<f32>, ext: vec3<f32>) -> vec2<f32> {
    let n = cross3(far - apex, ext - apex);
    let m = vec2<f32>(dot3(n, P.basis_u), dot3(n, P.basis_w));
    let tc = vec2<f32>(dot3(P.center - ext, P.basis_u), dot3(P.center - ext, P.basis_w));
    if m.x * tc.x + m.y * tc.y > 0.0 {
        return -m;
    }
    return m;
}

fn support_turn(apex: vec3<f32>, far_a: vec3<f32>, ext_a: vec3<f32>, far_b: vec3<f32>, ext_b: vec3<f32>) -> f32 {
    let a = outward_dir(apex, far_a, ext_a);
    let b = outward_dir(apex, far_b, ext_b);
    let turn = a.x * b.y - a.y * b.x;
    if is_finite(turn) {
        return signum(turn) * select(0.0, 1.0, turn != 0.0);
    }
    return 0.0;
}

// Some(true) = 1, Some(false) = 0, None = 2 (fans::corner_convexity).
fn corner_convexity(apex: vec3<f32>, edge_ids: array<u32, 2>, far: array<vec3<f32>, 2>, eye: vec3<f32>) -> u32 {
    var fa = far;
    var ids = edge_ids;
    var inside = array<bool, 2>(false, false);
    for (var k = 0u; k < 2u; k++) {
        let n = cross3(fa[k] - apex, eye - apex);
        let other = dot3(n, fa[1u - k] - apex);
        let e = ids[k];
        let outward = face_normal_or_zero(edge_word(e, 2u)) + face_normal_or_zero(edge_word(e, 3u));
        let caster = -dot3(n, outward);
        if other != other || caster != caster || other == 0.0 || caster == 0.0 {
            return 2u;
        }
        inside[k] = signum(other) == signum(caster);
    }
    if inside[0] != inside[1] {
        return 2u;
    }
    return select(0u, 1u, inside[0]);
}

fn caster_in_wedge(apex: vec3<f32>, far: array<vec3<f32>, 2>, eye: vec3<f32>) -> bool {
    if P.flags.y != 0u {
        return true;
    }
    if vertices() > CORNER_CHECK_VERTICES {
        return false;
    }
    var fa = far;
    var ns: array<vec3<f32>, 2>;
    var ds: array<f32, 2>;
    for (var k = 0u; k < 2u; k++) {
        var n = normalize_or_zero(cross3(fa[k] - apex, eye - apex));
        if dot3(n, fa[1u - k] - apex) < 0.0 {
            n = -n;
        }
        ns[k] = n;
        ds[k] = dot3(n, apex);
    }
    let tol = 1e-4 * max(len3(apex - far[0]), len3(apex - far[1]));
    for (var v = 0u; v < vertices(); v++) {
        let p = position(v);
        for (var k = 0u; k < 2u; k++) {
            if !(dot3(ns[k], p) - ds[k] >= -tol) {
                return false;
            }
        }
    }
    return true;
}

// The fan at `apex` from p1 to p2 round the light's boundary (fans::push_fan,
// outline::boundary_between).
fn push_fan(apex: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, turn: f32, kind: u32, marker: f32) {
    let c = P.center;
    let a1 = angle_of(p1);
    var delta = angle_of(p2) - a1;
    if delta > PI {
        delta -= TAU;
    } else if delta < -PI {
        delta += TAU;
    }
    let toward_c = !is_umbra(kind);
    if P.counts.w == 0u {
        let n = min(u32(max(ceil(abs(delta) / max(P.fan_step, 1e-3) - ARC_SLACK), 0.0)), MAX_ARC_POINTS);
        var q0 = p1;
        let steps = max(n, 1u);
        for (var k = 1u; k <= steps; k++) {
            var q1 = p2;
            if k < n {
                let a = a1 + delta * f32(k) / f32(n);
                q1 = c + P.radius * (cos(a) * P.basis_u + sin(a) * P.basis_w);
            }
            let q = array<vec3<f32>, 4>(apex, extrude_away(apex, q0), extrude_away(apex, q1), apex);
            push_polygon(q, 3u, Attrs(kind, apex, apex, q0, marker), toward_c);
            q0 = q1;
        }
        return;
    }
    if turn > 0.0 && delta < 0.0 {
        delta += TAU;
    } else if turn < 0.0 && delta > 0.0 {
        delta -= TAU;
    }
    var ds: array<f32, 16>;
    var ids: array<u32, 16>;
    var m = 0u;
    for (var i = 0u; i < P.counts.w; i++) {
        var d = angle_of(corner(i)) - a1;
        if delta < 0.0 {
            d = -d;
        }
        // rem_euclid
        d = d - TAU * floor(d / TAU);
        if d >= TAU {
            d -= TAU;
        }
        if d > 1e-5 && d < abs(delta) - 1e-5 {
            var j = m;
            loop {
                if j == 0u {
                    break;
                }
                if ds[j - 1u] <= d {
                    break;
                }
                ds[j] = ds[j - 1u];
                ids[j] = ids[j - 1u];
                j -= 1u;
            }
            ds[j] = d;
            ids[j] = i;
            m++;
        }
    }
    var q0 = p1;
    for (var k = 0u; k <= m; k++) {
        var q1 = p2;
        if k < m {
            q1 = corner(ids[k]);
        }
        let q = array<vec3<f32>, 4>(apex, extrude_away(apex, q0), extrude_away(apex, q1), apex);
        push_polygon(q, 3u, Attrs(kind, apex, apex, q0, marker), toward_c);
        q0 = q1;
    }
}

fn store_corner(k: u32, apex: vec3<f32>, far: array<vec3<f32>, 2>, ea: u32, eb: u32, sa: vec3<f32>, sb: vec3<f32>) {
    let base = TEXELS_PER_CORNER * k;
    corner_out[base] = vec4<f32>(apex, 0.0);
    corner_out[base + 1u] = vec4<f32>(far[0], 0.0);
    corner_out[base + 2u] = vec4<f32>(far[1], 0.0);
    corner_out[base + 3u] = vec4<f32>(face_normal_or_zero(edge_word(ea, 2u)), 0.0);
    corner_out[base + 4u] = vec4<f32>(face_normal_or_zero(edge_word(ea, 3u)), 0.0);
    corner_out[base + 5u] = vec4<f32>(face_normal_or_zero(edge_word(eb, 2u)), 0.0);
    corner_out[base + 6u] = vec4<f32>(face_normal_or_zero(edge_word(eb, 3u)), 0.0);
    corner_out[base + 7u] = vec4<f32>(sa, 0.0);
    corner_out[base + 8u] = vec4<f32>(sb, 0.0);
}

@compute @workgroup_size(64)
fn fans(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = thread_id(gid, groups);
    if v >= vertices() {
        return;
    }
    // The penumbra's fans first, then the umbra's, as the CPU closes them.
    for (var round = 0u; round < 2u; round++) {
        let vol = 1u - round;
        let count = atomicLoad(&work[count_word(vol, v)]);
        if count < 2u {
            continue;
        }
        if count > MAX_ENDS {
            // The CPU pairs so many ends by a window around the rim: not here. The caster
            // casts nothing (S_REFUSED 2: too many ends at a vertex).
            atomicStore(&state[S_REFUSED], 2u);
            continue;
        }
        close_vertex(v, vol, count);
    }
}

// The fans of one volume at vertex `v`, whose `count` ends (2 to MAX_ENDS) are in its run: a
// function of its own, so that only such a vertex sets up the arrays (most have no end).
fn close_vertex(v: u32, vol: u32, count: u32) {
    let apex = position(v);
    let run = vertex_run(v);
    // Ends sorted by (edge, outgoing): the slot's own order.
    var ends: array<u32, 64>;
    for (var i = 0u; i < count; i++) {
        let s = atomicLoad(&work[slot_word(vol, run + i)]);
        // (Each test its own statement: wgpu's GL backend got `j > 0 && ends[j - 1] > s`
        // wrong as a loop condition.)
        var j = i;
        loop {
            if j == 0u {
                break;
            }
            if ends[j - 1u] <= s {
                break;
            }
            ends[j] = ends[j - 1u];
            j -= 1u;
        }
        ends[j] = s;
    }
    var exts: array<vec3<f32>, 64>;
    for (var i = 0u; i < count; i++) {
        exts[i] = load_point(ends[i] >> 1u, vol);
    }
    var used: array<bool, 64>;
    for (var i = 0u; i < count; i++) {
        used[i] = false;
    }
    let kind = select(4u, 5u, vol == 0u);
    loop {
        // The best pair left (fans::Fans::pairs): an incoming end with an outgoing one
        // first, then the closest extrusion points, then the first in order.
        var bi = 0xffffffffu;
        var bj = 0u;
        var b_same = true;
        var b_gap = 0.0;
        if count == 2u {
            if !used[0] {
                bi = 0u;
                bj = 1u;
            }
        } else {
            for (var i = 0u; i < count; i++) {
                if used[i] {
                    continue;
                }
                for (var j = i + 1u; j < count; j++) {
                    if used[j] {
                        continue;
                    }
                    let same = (ends[i] & 1u) == (ends[j] & 1u);
                    let gap = len3(exts[i] - exts[j]);
                    var better = bi == 0xffffffffu;
                    if !better {
                        better = (!same && b_same) || (same == b_same && gap < b_gap);
                    }
                    if better {
                        bi = i;
                        bj = j;
                        b_same = same;
                        b_gap = gap;
                    }
                }
            }
        }
        if bi == 0xffffffffu {
            break;
        }
        used[bi] = true;
        used[bj] = true;
        let ea = ends[bi] >> 1u;
        let eb = ends[bj] >> 1u;
        let p1 = exts[bi];
        let p2 = exts[bj];
        if all(p1 == p2) {
            continue;
        }
        let far = array<vec3<f32>, 2>(other_end(ea, v), other_end(eb, v));
        let turn = support_turn(apex, far[0], p1, far[1], p2);
        let behind = apex + (apex - 0.5 * (p1 + p2));
        var marker = 0.0;
        if corner_convexity(apex, array<u32, 2>(ea, eb), far, behind) == 1u
            && caster_in_wedge(apex, far, behind) {
            let k = atomicAdd(&state[S_CORNERS], 1u);
            if k < P.limits.z && P.limits.y + k < MAX_CORNERS {
                store_corner(P.limits.y + k, apex, far, ea, eb, p1, p2);
                marker = -(2.0 + f32(P.limits.y + k));
            }
        }
        push_fan(apex, p1, p2, turn, kind, marker);
        atomicAdd(&state[select(S_FANS, S_UMBRA_FANS, vol == 0u)], 1u);
    }
}

// --- silhouette faces (volumes::build_caster_within) ---

@compute @workgroup_size(64)
fn faces_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let f = thread_id(gid, groups);
    if f >= faces() {
        return;
    }
    let cls = class_at(f);
    if cls < 2u {
        return;
    }
    let a = position(face_vertex(f, 0u));
    let b = position(face_vertex(f, 1u));
    let c = position(face_vertex(f, 2u));
    emit(a, b, c, Attrs(cls - 1u, a, a, P.center, 0.0));
}

// --- the budget and the draws ---

@compute @workgroup_size(1)
fn finish() {
    let umbra = atomicLoad(&state[S_UMBRA]);
    let penumbra = atomicLoad(&state[S_PENUMBRA]);
    let over = atomicLoad(&state[S_WANTED]) > P.limits.x
        || umbra > P.flags.z || penumbra > P.flags.w || atomicLoad(&state[S_REFUSED]) != 0u;
    if over && atomicLoad(&state[S_REFUSED]) == 0u {
        atomicStore(&state[S_REFUSED], 1u);
    }
    atomicStore(&state[S_ARGS_UMBRA], select(3u * umbra, 0u, over));
    atomicStore(&state[S_ARGS_UMBRA + 1u], 1u);
    atomicStore(&state[S_ARGS_UMBRA + 2u], 0u);
    atomicStore(&state[S_ARGS_UMBRA + 3u], 0u);
    atomicStore(&state[S_ARGS_PENUMBRA], select(3u * penumbra, 0u, over));
    atomicStore(&state[S_ARGS_PENUMBRA + 1u], 1u);
    atomicStore(&state[S_ARGS_PENUMBRA + 2u], 0u);
    atomicStore(&state[S_ARGS_PENUMBRA + 3u], 0u);
}
