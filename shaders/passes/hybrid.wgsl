// Shadow volumes reconstructed from a depth map (render::passes::hybrid; McCool 2000). The CPU
// twin of the extraction is geometry::hybrid (wall_segments, WallSpace::quad): keep the two
// alike.
//
// 1. cs_find: per cell of 2×2 texel centres of the light's distance map, a cheap test (a jump
//    above the threshold between two of its texels) lists the cells worth a closer look;
//    cs_dispatch sizes the next dispatch (a CPU adapter runs every path of a branch for every
//    cell, so the costly part runs only over the listed ones). cs_extract: per listed cell, the
//    marching-squares template (or the star) of its discontinuous texel pairs, each segment
//    written as a wall quad (two triangles) standing on the light's rays from the near texel's
//    plane to the far texel's distance; cs_finish turns the count into indirect draw
//    arguments.
// 2. vs_wall: the walls over the screen prepass, z-pass, one stencil bit inverted per wall in
//    front of the surface (no fragment stage).
// 3. fs_even / fs_odd: the resolve, one pipeline per value of the bit: the parity, and whether
//    the camera ray starts in shadow (its point on the near plane, looked up in the map: the
//    near cap McCool's templates make simple) give V.
// #include shared/fullscreen_vs.wgsl

const NO_SURFACE_AT: f32 = 1.5e38;

struct HybridUniforms {
    // Light clip → world (image points to rays) and world → light clip (the near-cap lookup).
    inv_light_view_proj: mat4x4<f32>,
    light_view_proj: mat4x4<f32>,
    // The camera, far plane at infinity, reversed depth (ScreenView::infinite_view_proj), and
    // its inverse.
    infinite_view_proj: mat4x4<f32>,
    inv_infinite_view_proj: mat4x4<f32>,
    // xyz: the light point; w: the distance of a wall's bottom where nothing was seen.
    light: vec4<f32>,
    // x: map size in texels; y: threshold τ; z: 1 templates, 0 star; w: the walls' top bias.
    params: vec4<f32>,
    // x: the walls' bottom margin; y: the most walls; z: the near-cap lookup's bias; w: 1 for
    // the slope test (a jump that either neighbour's slope predicts is no edge), 0 without.
    limits: vec4<f32>,
    // xy: the camera image's width and height in pixels; z: the map copy's row stride in floats.
    screen: vec4<f32>,
};

struct DrawArgs {
    vertex_count: u32,
    instance_count: u32,
    first_vertex: u32,
    first_instance: u32,
};

@group(0) @binding(0) var<uniform> hybrid: HybridUniforms;
@group(0) @binding(1) var distances: texture_2d<f32>;

@group(1) @binding(0) var<storage, read_write> walls: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> wall_count: atomic<u32>;
@group(1) @binding(2) var<storage, read_write> draw_args: DrawArgs;
// The distance map copied into a buffer, rows `screen.z` floats apart (a CPU rasteriser reads a
// buffer in a compute shader far faster than a texture).
@group(1) @binding(3) var<storage, read> map_copy: array<f32>;

fn texel(p: vec2<i32>) -> f32 {
    return map_copy[u32(p.y) * u32(hybrid.screen.z) + u32(p.x)];
}

// The cells cs_find listed (x + y·65536), how many, and cs_extract's dispatch size.
@group(1) @binding(4) var<storage, read_write> candidates: array<u32>;
@group(1) @binding(5) var<storage, read_write> candidate_count: atomic<u32>;
@group(1) @binding(6) var<storage, read_write> extract_args: array<u32, 3>;

// The unit direction from the light through image point q (texel units).
fn direction(q: vec2<f32>) -> vec3<f32> {
    let s = hybrid.params.x;
    let ndc = vec4<f32>(2.0 * q.x / s - 1.0, 1.0 - 2.0 * q.y / s, 0.5, 1.0);
    let w = hybrid.inv_light_view_proj * ndc;
    return normalize(w.xyz / w.w - hybrid.light.xyz);
}

struct Edge {
    flagged: bool,
    mid: vec2<f32>,
    near: f32,
    far: f32,
};

// Whether a plane through `out` and `x` (light-view depths) predicts `y` within `limit`: 1/w is
// affine over the image for a plane. `out` <= 0 marks "no surface there".
fn predicts(out: f32, x: f32, y: f32, limit: f32) -> bool {
    let g = 2.0 / x - 1.0 / out;
    return out > 0.0 && g > 0.0 && abs(y - 1.0 / g) <= limit;
}

// The light-view depth (clip w) of the point at distance d through image point q.
fn view_depth(q: vec2<f32>, d: f32) -> f32 {
    let p = hybrid.light.xyz + direction(q) * d;
    return (hybrid.light_view_proj * vec4<f32>(p, 1.0)).w;
}

// Where a wall's top belongs on the ray through `mid`: the near texel's own plane (1/w
// extrapolated from the texel beyond it and itself) half a texel toward the far side, within
// [near, far] (geometry::hybrid::wall_top).
fn wall_top(near_w_out: f32, near_w: f32, mid: vec2<f32>, near: f32, far: f32) -> f32 {
    let g = 1.5 / near_w - 0.5 / near_w_out;
    let k0 = view_depth(mid, 0.0);
    let k1 = view_depth(mid, 1.0) - k0;
    if !(near_w_out > 0.0 && g > 0.0 && k1 > 0.0) {
        return near;
    }
    return clamp((1.0 / g - k0) / k1, near, far);
}

// The edge between texels a and b; t = the distances of (a's neighbour beyond a, a, b, b's
// beyond b), w = their light-view depths (0 where there is none).
fn edge(t: vec4<f32>, w: vec4<f32>, mid: vec2<f32>) -> Edge {
    let da = t.y;
    let db = t.z;
    var e: Edge;
    e.mid = mid;
    e.flagged = false;
    let na = da >= NO_SURFACE_AT;
    let nb = db >= NO_SURFACE_AT;
    if na && nb {
        return e;
    }
    if na != nb {
        e.flagged = true;
        e.far = hybrid.light.w;
        if na {
            e.near = wall_top(w.w, w.z, mid, db, e.far);
        } else {
            e.near = wall_top(w.x, w.y, mid, da, e.far);
        }
        return e;
    }
    let lo = min(da, db);
    let hi = max(da, db);
    e.flagged = hi - lo > hybrid.params.y * lo;
    if e.flagged && hybrid.limits.w > 0.5 {
        let limit = hybrid.params.y * min(w.y, w.z);
        e.flagged = !(predicts(w.x, w.y, w.z, limit) || predicts(w.w, w.z, w.y, limit));
    }
    if !e.flagged {
        return e;
    }
    e.far = hi;
    if da <= db {
        e.near = wall_top(w.x, w.y, mid, lo, hi);
    } else {
        e.near = wall_top(w.w, w.z, mid, lo, hi);
    }
    return e;
}

// The distance at texel p (3e38: outside the map, like nothing seen).
fn at(p: vec2<i32>) -> f32 {
    let n = i32(hybrid.params.x);
    if any(p < vec2<i32>(0)) || any(p >= vec2<i32>(n)) {
        return 3.0e38;
    }
    return texel(p);
}

// The light-view depth of texel p's surface point, 0 where it has none.
fn depth_at(p: vec2<i32>, d: f32) -> f32 {
    if d >= NO_SURFACE_AT {
        return 0.0;
    }
    return view_depth(vec2<f32>(p) + vec2<f32>(0.5), d);
}

// Distances of four texels from `p` on, `step` apart, and their light-view depths.
struct Line {
    d: vec4<f32>,
    w: vec4<f32>,
};

fn line(p: vec2<i32>, step: vec2<i32>) -> Line {
    var out: Line;
    for (var k = 0; k < 4; k++) {
        let q = p + step * k;
        let d = at(q);
        out.d[k] = d;
        out.w[k] = depth_at(q, d);
    }
    return out;
}

fn emit(a: vec2<f32>, b: vec2<f32>, near: vec2<f32>, far: vec2<f32>) {
    let i = atomicAdd(&wall_count, 1u);
    if i >= u32(hybrid.limits.y) {
        return;
    }
    let p = hybrid.light.xyz;
    let da = direction(a);
    let db = direction(b);
    let top = 1.0 + hybrid.params.w;
    let bottom = 1.0 + hybrid.limits.x;
    let top_a = vec4<f32>(p + da * near.x * top, 1.0);
    let top_b = vec4<f32>(p + db * near.y * top, 1.0);
    let bottom_a = vec4<f32>(p + da * far.x * bottom, 1.0);
    let bottom_b = vec4<f32>(p + db * far.y * bottom, 1.0);
    let k = 6u * i;
    walls[k] = top_a;
    walls[k + 1u] = top_b;
    walls[k + 2u] = bottom_b;
    walls[k + 3u] = top_a;
    walls[k + 4u] = bottom_b;
    walls[k + 5u] = bottom_a;
}

// Whether the pair is worth a closer look: a jump above the threshold, or exactly one texel
// without a surface (the slope test can only clear it).
fn jumps(a: f32, b: f32) -> bool {
    let na = a >= NO_SURFACE_AT;
    let nb = b >= NO_SURFACE_AT;
    return (na != nb) || (!na && abs(a - b) > hybrid.params.y * min(a, b));
}

// The most cells cs_find lists (render::passes::hybrid::MAX_CANDIDATES).
const MAX_CANDIDATES: u32 = 262144u;

@compute @workgroup_size(8, 8)
fn cs_find(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = u32(hybrid.params.x);
    if id.x + 1u >= n || id.y + 1u >= n {
        return;
    }
    let i = vec2<i32>(id.xy);
    let d00 = texel(i);
    let d10 = texel(i + vec2<i32>(1, 0));
    let d01 = texel(i + vec2<i32>(0, 1));
    let d11 = texel(i + vec2<i32>(1, 1));
    if jumps(d00, d10) || jumps(d10, d11) || jumps(d01, d11) || jumps(d00, d01) {
        let k = atomicAdd(&candidate_count, 1u);
        if k < MAX_CANDIDATES {
            candidates[k] = id.x | (id.y << 16u);
        }
    }
}

@compute @workgroup_size(1)
fn cs_dispatch() {
    let n = min(atomicLoad(&candidate_count), MAX_CANDIDATES);
    extract_args[0] = (n + 63u) / 64u;
    extract_args[1] = 1u;
    extract_args[2] = 1u;
}

@compute @workgroup_size(64)
fn cs_extract(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= min(atomicLoad(&candidate_count), MAX_CANDIDATES) {
        return;
    }
    let c = candidates[id.x];
    extract_cell(vec2<u32>(c & 0xffffu, c >> 16u));
}

fn extract_cell(id: vec2<u32>) {
    let i = vec2<i32>(id.xy);
    let right = vec2<i32>(1, 0);
    let down = vec2<i32>(0, 1);
    let row0 = line(i - right, right);
    let row1 = line(i + down - right, right);
    let col0 = line(i - down, down);
    let col1 = line(i + right - down, down);
    let f = vec2<f32>(id.xy);
    var edges = array<Edge, 4>(
        edge(row0.d, row0.w, f + vec2<f32>(1.0, 0.5)),
        edge(col1.d, col1.w, f + vec2<f32>(1.5, 1.0)),
        edge(row1.d, row1.w, f + vec2<f32>(1.0, 1.5)),
        edge(col0.d, col0.w, f + vec2<f32>(0.5, 1.0)),
    );
    var count = 0u;
    for (var e = 0u; e < 4u; e++) {
        count += select(0u, 1u, edges[e].flagged);
    }
    if count == 0u {
        return;
    }
    if count == 2u && hybrid.params.z > 0.5 {
        var first = -1;
        for (var e = 0; e < 4; e++) {
            if !edges[e].flagged {
                continue;
            }
            if first < 0 {
                first = e;
            } else {
                let a = edges[first];
                let b = edges[e];
                emit(a.mid, b.mid, vec2<f32>(a.near, b.near), vec2<f32>(a.far, b.far));
            }
        }
        return;
    }
    let centre = f + vec2<f32>(1.0);
    for (var e = 0u; e < 4u; e++) {
        let g = edges[e];
        if g.flagged {
            emit(g.mid, centre, vec2<f32>(g.near), vec2<f32>(g.far));
        }
    }
}

@compute @workgroup_size(1)
fn cs_finish() {
    let n = min(atomicLoad(&wall_count), u32(hybrid.limits.y));
    draw_args.vertex_count = 6u * n;
    draw_args.instance_count = 1u;
    draw_args.first_vertex = 0u;
    draw_args.first_instance = 0u;
}

struct WallOut {
    @builtin(position) @invariant clip: vec4<f32>,
};

@vertex
fn vs_wall(@location(0) p: vec4<f32>) -> WallOut {
    var out: WallOut;
    out.clip = hybrid.infinite_view_proj * p;
    return out;
}

// Whether the camera ray through this pixel starts in shadow: its point on the near plane,
// farther from the light than the map's surface in its texel.
fn near_in_shadow(pixel: vec2<f32>, size: vec2<f32>) -> bool {
    let ndc = vec4<f32>(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y, 1.0, 1.0);
    let w = hybrid.inv_infinite_view_proj * ndc;
    let q = w.xyz / w.w;
    let clip = hybrid.light_view_proj * vec4<f32>(q, 1.0);
    if clip.w <= 0.0 {
        return false;
    }
    let l = clip.xy / clip.w;
    if any(abs(l) > vec2<f32>(1.0)) {
        return false;
    }
    let n = hybrid.params.x;
    let uv = vec2<f32>(l.x * 0.5 + 0.5, 0.5 - l.y * 0.5);
    let texel = vec2<i32>(clamp(floor(uv * n), vec2<f32>(0.0), vec2<f32>(n - 1.0)));
    let o = textureLoad(distances, texel, 0).x;
    let d = distance(q, hybrid.light.xyz);
    return o < NO_SURFACE_AT && d > o * (1.0 + hybrid.limits.z);
}

fn resolve(pixel: vec2<f32>, odd: bool) -> vec4<f32> {
    let shadowed = odd != near_in_shadow(pixel, hybrid.screen.xy);
    return vec4<f32>(select(1.0, 0.0, shadowed), 0.0, 0.0, 0.0);
}

@fragment
fn fs_even(f: FullscreenVertex) -> @location(0) vec4<f32> {
    return resolve(f.position.xy, false);
}

@fragment
fn fs_odd(f: FullscreenVertex) -> @location(0) vec4<f32> {
    return resolve(f.position.xy, true);
}
