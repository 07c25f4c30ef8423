// dbuffer-fused's per-texel edge lists (src/render/passes/fused_lists.rs). Twin:
// geometry::fused::FusedTwin::texel_ray_of (fs_merge), edge_in_texel (fs_list) and
// FusedTwin::crossings_of (fs_maps).
//   fs_merge  per list texel, its ray and where its receivers can be, from the receivers of the
//             3×3 texels around it (passes/fused_layers.wgsl): up to three patches and a deeper
//             stretch (TexelRay);
//   fs_list   per candidate edge its proxy (geometry::fused::proxy_hull, drawn once per texel),
//             per texel the list test; an edge that passes is counted (atomicAdd) and stored while
//             the count is below the cap. Overflow rule: a list whose count exceeds the cap is not
//             used (the camera pass walks every candidate edge instead); below it the set of
//             edges does not depend on the order in which fragments ran;
//   fs_maps   per D-buffer texel: the caster crossings along its ray, the largest crossing height
//             over the 3×3 texels around it, its list texel's count and whether it overflowed
//             (the method's light maps, and the camera pass's L(c)).
// #include shared/fused.wgsl
// #include shared/fullscreen_vs.wgsl

@group(0) @binding(0) var<uniform> fused: FusedUniforms;

// fs_merge
@group(1) @binding(0) var recv_first: texture_2d<f32>;
@group(1) @binding(1) var recv_second: texture_2d<f32>;
@group(1) @binding(2) var recv_last: texture_2d<f32>;
@group(1) @binding(3) var recv_last_caster: texture_2d<f32>;
@group(1) @binding(4) var recv_count: texture_2d<f32>;
@group(1) @binding(5) var<storage, read_write> rays_out: array<TexelRay>;

// fs_list (and vs_proxy)
@group(1) @binding(6) var<storage, read> rays: array<TexelRay>;
@group(1) @binding(7) var<storage, read> edges: array<FusedEdge>;
// Per edge its proxy's corners in the light view's NDC, 16 (the last repeated to fill).
@group(1) @binding(8) var<storage, read> hulls: array<array<vec2<f32>, 16>>;
@group(1) @binding(9) var<storage, read_write> list_counts: array<atomic<u32>>;
@group(1) @binding(10) var<storage, read_write> lists: array<u32>;

// fs_maps
@group(1) @binding(11) var cross_count: texture_2d<f32>;
@group(1) @binding(12) var cross_far: texture_2d<f32>;
@group(1) @binding(13) var<storage, read> counts: array<u32>;

// geometry::fused::{PATCH_TEXELS, PATCH_COS, PATCH_BULGE}.
const PATCH_TEXELS: f32 = 64.0;
const PATCH_COS: f32 = 0.9;
const PATCH_BULGE: f32 = 0.5;
const BIG: f32 = 3.0e38;

// ---- fs_merge ----

// One ray's receivers (geometry::fused::ReceiverLayers): first, second, last as (point, normal),
// and the last on a caster (or the second where there is none).
struct Layers {
    p0: vec3<f32>,
    n0: vec3<f32>,
    p1: vec3<f32>,
    n1: vec3<f32>,
    p2: vec3<f32>,
    n2: vec3<f32>,
    pc: vec3<f32>,
    nc: vec3<f32>,
};

fn receivers_at(t: vec2<i32>) -> u32 {
    return u32(round(textureLoad(recv_count, t, 0).x));
}

fn layers_at(t: vec2<i32>, count: u32) -> Layers {
    var l: Layers;
    let w = fused_texel_dir(fused, vec2<f32>(t), fused.list_size);
    let first = textureLoad(recv_first, t, 0);
    let last = textureLoad(recv_last, t, 0);
    let second = select(last, textureLoad(recv_second, t, 0), count >= 2u);
    let caster = textureLoad(recv_last_caster, t, 0);
    l.p0 = fused.center + w * first.x;
    l.n0 = first.yzw;
    l.p1 = fused.center + w * second.x;
    l.n1 = second.yzw;
    l.p2 = fused.center + w * last.x;
    l.n2 = last.yzw;
    l.pc = select(l.p1, fused.center + w * caster.x, caster.x > 0.0);
    l.nc = select(l.n1, caster.yzw, caster.x > 0.0);
    return l;
}

// The merge's state: the patches (point, radius) and (normal, bulge), how many, the deeper
// stretch (as heights) and the farthest receiver height.
struct Merge {
    p: array<vec4<f32>, 3>,
    n: array<vec4<f32>, 3>,
    patches: u32,
    lo: f32,
    hi: f32,
    far: f32,
    w: vec3<f32>,
};

// How far up or down the same surface can reach into a texel's pyramid from a receiver of a
// neighbouring ray (FusedTwin::texel_ray_of's reach).
fn reach(q: vec3<f32>, nq: vec3<f32>, w: vec3<f32>) -> f32 {
    let base = distance(q, fused.center) * fused.half_slope;
    return 2.2 * base / max(abs(dot(nq, w)), 0.05);
}

// One receiver of the 3×3: it widens the first patch on the same surface (near, facing the
// same way), or else (across an outline) joins the deeper stretch.
fn absorb(m: ptr<function, Merge>, q: vec3<f32>, nq: vec3<f32>) {
    let h = fused_height(fused, q);
    (*m).far = max((*m).far, h);
    var found = false;
    for (var k = 0u; k < 3u; k++) {
        let p = (*m).p[k].xyz;
        let np = (*m).n[k].xyz;
        let base = distance(p, fused.center) * fused.half_slope;
        let d = distance(q, p);
        if !found && k < (*m).patches && d <= PATCH_TEXELS * base && dot(nq, np) >= PATCH_COS {
            found = true;
            (*m).p[k].w = max((*m).p[k].w, d + base);
            (*m).n[k].w = max((*m).n[k].w, abs(dot(np, q - p)) + base * PATCH_BULGE);
        }
    }
    if !found {
        let r = reach(q, nq, (*m).w);
        (*m).lo = min((*m).lo, h - r);
        (*m).hi = max((*m).hi, h + r);
    }
}

// The merge of list texel `id` into rays_out.
fn merge_texel(id: vec2<u32>) {
    let size = i32(fused.list_size);
    if i32(id.x) >= size || i32(id.y) >= size {
        return;
    }
    let index = id.y * u32(size) + id.x;
    let tc = vec2<i32>(id.xy);
    var ray: TexelRay;
    ray.dir = vec4<f32>(0.0);
    ray.span = vec4<f32>(1.0, 0.0, 0.0, 0.0);
    // The receivers of the 3×3 (rows, then columns; none outside the grid), each loaded once.
    var around: array<u32, 9>;
    for (var k = 0; k < 9; k++) {
        let t = tc + vec2<i32>(k % 3 - 1, k / 3 - 1);
        around[k] = 0u;
        if all(t >= vec2<i32>(0)) && all(t < vec2<i32>(size)) {
            around[k] = receivers_at(t);
        }
    }
    // The centre ray's receivers, or the first of the 3×3 that has any.
    var centre = tc;
    var centre_count = around[4];
    for (var k = 0; k < 9; k++) {
        if centre_count == 0u && around[k] > 0u {
            centre = tc + vec2<i32>(k % 3 - 1, k / 3 - 1);
            centre_count = around[k];
        }
    }
    let w = fused_texel_dir(fused, vec2<f32>(tc), fused.list_size);
    let along = dot(w, fused.normal);
    if centre_count == 0u || !(along > 1e-6) {
        rays_out[index] = ray;
        return;
    }
    var counts_differ = false;
    for (var k = 0; k < 9; k++) {
        counts_differ = counts_differ || (around[k] > 0u && around[k] != centre_count);
    }
    // Patches on the centre ray's first, second and last receivers (as many as it has).
    let c = layers_at(centre, centre_count);
    var m: Merge;
    m.patches = min(centre_count, 3u);
    m.w = w;
    m.lo = BIG;
    m.hi = -BIG;
    m.far = -BIG;
    let p1 = select(c.p1, c.p2, m.patches == 2u);
    let n1 = select(c.n1, c.n2, m.patches == 2u);
    let b0 = distance(c.p0, fused.center) * fused.half_slope;
    let b1 = distance(p1, fused.center) * fused.half_slope;
    let b2 = distance(c.p2, fused.center) * fused.half_slope;
    m.p[0] = vec4<f32>(c.p0, b0);
    m.n[0] = vec4<f32>(c.n0, b0 * PATCH_BULGE);
    m.p[1] = vec4<f32>(p1, b1);
    m.n[1] = vec4<f32>(n1, b1 * PATCH_BULGE);
    m.p[2] = vec4<f32>(c.p2, b2);
    m.n[2] = vec4<f32>(c.n2, b2 * PATCH_BULGE);
    for (var k = 0; k < 9; k++) {
        let n = around[k];
        if n == 0u {
            continue;
        }
        let l = layers_at(tc + vec2<i32>(k % 3 - 1, k / 3 - 1), n);
        if n > 3u || (counts_differ && n > 1u) {
            m.lo = min(m.lo, fused_height(fused, l.p1) - reach(l.p1, l.n1, w));
            m.hi = max(m.hi, fused_height(fused, l.pc) + reach(l.pc, l.nc, w));
        }
        absorb(&m, l.p0, l.n0);
        absorb(&m, l.p1, l.n1);
        absorb(&m, l.p2, l.n2);
    }
    ray.point = m.p;
    ray.normal = m.n;
    ray.dir = vec4<f32>(w, 1.0);
    let deeper = m.lo <= m.hi;
    ray.span = vec4<f32>(
        select(1.0, m.lo / along, deeper),
        select(0.0, m.hi / along, deeper),
        m.far / along,
        f32(m.patches)
    );
    rays_out[index] = ray;
}

// A fragment shader over the list grid (no colour written; the rays go to rays_out), so that a
// scissor keeps it to the texels a proxy can cover: no other texel's ray is read.
@fragment
fn fs_merge(f: FullscreenVertex) -> @location(0) vec4<f32> {
    merge_texel(vec2<u32>(f.position.xy));
    return vec4<f32>(0.0);
}

// ---- fs_list ----

// What the list test reads of the edge, the same for every fragment of its proxy: handed down
// flat from the vertex stage rather than loaded by every fragment (a fifth off the pass).
struct ProxyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) edge: u32,
    @location(1) @interpolate(flat) a: vec4<f32>,
    @location(2) @interpolate(flat) b: vec4<f32>,
    @location(3) @interpolate(flat) n0: vec4<f32>,
    @location(4) @interpolate(flat) n1: vec4<f32>,
    // The ends' heights and the face planes at the light centre: (ha, hb, f0, f1).
    @location(5) @interpolate(flat) at_c: vec4<f32>,
};

// 14 triangles per edge: a fan over its hull's 16 corners (those past the last corner repeat it,
// so their triangles have no area).
@vertex
fn vs_proxy(@builtin(vertex_index) v: u32, @builtin(instance_index) e: u32) -> ProxyOut {
    let j = v / 3u;
    let k = v % 3u;
    let corner = select(0u, j + k, k > 0u);
    var out: ProxyOut;
    out.clip = vec4<f32>(hulls[e][min(corner, 15u)], 0.5, 1.0);
    out.edge = e;
    let edge = edges[e];
    out.a = edge.a;
    out.b = edge.b;
    out.n0 = edge.n0;
    out.n1 = edge.n1;
    let c = fused.center;
    out.at_c = vec4<f32>(
        fused_height(fused, edge.a.xyz),
        fused_height(fused, edge.b.xyz),
        dot(edge.n0.xyz, c) - edge.n0.w,
        dot(edge.n1.xyz, c) - edge.n1.w
    );
    return out;
}

// Where alpha + beta t > 0, as an interval of t (geometry::fused::positive_on).
fn positive_on(alpha: f32, beta: f32) -> vec2<f32> {
    if beta > 0.0 {
        return vec2<f32>(-alpha / beta, BIG);
    }
    if beta < 0.0 {
        return vec2<f32>(-BIG, -alpha / beta);
    }
    return select(vec2<f32>(BIG, -BIG), vec2<f32>(-BIG, BIG), alpha > 0.0);
}

fn meet(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(max(a.x, b.x), min(a.y, b.y));
}

fn distance_to_segment(a: vec2<f32>, b: vec2<f32>) -> f32 {
    let d = b - a;
    let len2 = dot(d, d);
    let t = select(0.0, clamp(dot(-a, d) / len2, 0.0, 1.0), len2 > 0.0);
    return length(a + d * t);
}

// The list test (geometry::fused::edge_in_texel) for the proxy's edge and the ray of list texel
// `texel`.
fn edge_in_texel(e: ProxyOut, texel: u32) -> bool {
    let c = fused.center;
    let dir = rays[texel].dir.xyz;
    let span = rays[texel].span;
    let along = dot(dir, fused.normal);
    let far = span.z;
    if !(along > 0.0) || !(far > 0.0) {
        return false;
    }
    let y = c + dir * far;
    let hy = far * along;
    let limit = hy * (1.0 - FUSED_CLIP);
    let ha = e.at_c.x;
    let hb = e.at_c.y;
    var pa = e.a.xyz;
    var pb = e.b.xyz;
    var qa = ha;
    var qb = hb;
    let a_near = ha < limit;
    let b_near = hb < limit;
    if !a_near && !b_near {
        return false;
    }
    let cut = e.a.xyz + (e.b.xyz - e.a.xyz) * ((limit - ha) / (hb - ha));
    if a_near && !b_near {
        pb = cut;
        qb = limit;
    }
    if !a_near && b_near {
        pa = cut;
        qa = limit;
    }
    // Projection from y onto the light plane, in disk coordinates (metres).
    let ya = y + (pa - y) * (hy / (hy - qa));
    let yb = y + (pb - y) * (hy / (hy - qb));
    let sa = vec2<f32>(dot(ya - c, fused.e1), dot(ya - c, fused.e2));
    let sb = vec2<f32>(dot(yb - c, fused.e1), dot(yb - c, fused.e2));
    // The pyramid's half-width at y, parallel to the light plane.
    let lateral = far * fused.half_slope / along;
    let amp = max(max(qa, 0.0) / (hy - qa), max(qb, 0.0) / (hy - qb));
    if distance_to_segment(sa, sb) > fused.radius + lateral * amp {
        return false;
    }
    if e.a.w == 1.0 {
        return true; // an open boundary is a silhouette from everywhere
    }
    let t_edge = min(ha, hb) / along;
    let tol = FUSED_FACING_TOL * (1.0 + fused_max_abs(y) + fused_max_abs(e.a.xyz));
    let f0 = e.at_c.z;
    let g0 = dot(e.n0.xyz, dir);
    let f1 = e.at_c.w;
    let g1 = dot(e.n1.xyz, dir);
    let s = fused.half_slope;
    let sil0 = meet(positive_on(f0 + tol, g0 + s), positive_on(tol - f1, s - g1));
    let sil1 = meet(positive_on(tol - f0, s - g0), positive_on(f1 + tol, g1 + s));
    var deeper = false;
    if span.x <= span.y {
        let lo = max(span.x, t_edge);
        let hi = span.y;
        deeper = max(sil0.x, lo) <= min(sil0.y, hi) || max(sil1.x, lo) <= min(sil1.y, hi);
    }
    if deeper {
        return true;
    }
    var first = false;
    let patches = u32(span.w);
    for (var k = 0u; k < patches; k++) {
        let p = rays[texel].point[k].xyz;
        let radius = rays[texel].point[k].w;
        let np = rays[texel].normal[k].xyz;
        let bulge = rays[texel].normal[k].w;
        let v0 = dot(e.n0.xyz, p) - e.n0.w;
        let r0 = radius * length(cross(e.n0.xyz, np)) + bulge;
        let v1 = dot(e.n1.xyz, p) - e.n1.w;
        let r1 = radius * length(cross(e.n1.xyz, np)) + bulge;
        let front0 = v0 + r0 > -tol;
        let back0 = v0 - r0 < tol;
        let front1 = v1 + r1 > -tol;
        let back1 = v1 - r1 < tol;
        first = first || (fused_height(fused, p) + radius > min(ha, hb)
            && ((front0 && back1) || (back0 && front1)));
    }
    return first || deeper;
}

@fragment
fn fs_list(f: ProxyOut) -> @location(0) vec4<f32> {
    let size = u32(fused.list_size);
    let t = vec2<u32>(f.clip.xy);
    let texel = min(t.y, size - 1u) * size + min(t.x, size - 1u);
    if rays[texel].dir.w > 0.0 && edge_in_texel(f, texel) {
        let k = atomicAdd(&list_counts[texel], 1u);
        if k < fused.cap {
            lists[texel * fused.cap + k] = f.edge;
        }
    }
    return vec4<f32>(0.0);
}

// ---- fs_maps ----

// Per D-buffer texel: (crossings along its ray, the largest crossing height over the 3×3 around
// it, the count of its list texel, 1 where that list overflowed). A fragment shader over the
// whole target rather than a compute one: lavapipe writes a colour target in tiles, where a
// storage texture takes a store of its own per texel (11 of the 24 ms a compute pass took at
// 1024²).
@fragment
fn fs_maps(f: FullscreenVertex) -> @location(0) vec4<f32> {
    let size = i32(fused.map_size);
    let t = vec2<i32>(f.position.xy);
    var far = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = clamp(t + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(size - 1));
            far = max(far, textureLoad(cross_far, q, 0).r);
        }
    }
    let crossings = round(textureLoad(cross_count, t, 0).x);
    let l = u32(fused.list_size);
    let lt = min(vec2<u32>((vec2<f32>(t) + 0.5) / fused.map_size * fused.list_size), vec2<u32>(l - 1u));
    let count = counts[lt.y * l + lt.x];
    let overflow = count > fused.cap || fused.all_overflow != 0u;
    return vec4<f32>(crossings, far / fused.inv_far, f32(count), select(0.0, 1.0, overflow));
}
