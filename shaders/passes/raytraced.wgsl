// The `raytraced` method's passes before the camera pass (src/render/passes/raytraced.rs): shadow
// rays traced against the scene's BVH and denoised in the manner of NVIDIA's SIGMA, one compute
// entry point each, every buffer one vec4 per pixel of the camera image (row-major):
//
// 1. cs_trace: from the surface point of each pixel (the screen prepass's positions), `rays`
//    shadow rays toward points of the light taken from a low-discrepancy sequence (R2, Roberts
//    2018) that runs on from frame to frame, its start scrambled per pixel; writes the raw V of
//    this frame, the mean distance to what blocked its rays, and the pixel's geometry (position,
//    normal) for the passes after it.
// 2. cs_temporal: the pixel's history reprojected from the previous frame (bilinear, each tap
//    kept only where the previous frame saw the same surface there: position within a share of
//    the view distance, normals alike) and blended with this frame's rays as a running mean over
//    at most `history` frames; while the light or a caster moves the history is clamped to the
//    range of this frame's rays around the pixel and held short, so old shadow fades fast.
// 3. cs_spatial: a disk of taps whose radius follows the penumbra's width at the pixel, estimated
//    from the accumulated hit distance as PCSS does from its blockers (light size × receiver-to-
//    blocker / blocker-to-light), projected to pixels and shrunk as samples accumulate; taps
//    weighted by distance, by the receiver's plane and by normal.
//
// The camera pass (methods/raytraced.wgsl) reads V from cs_spatial's output, or this frame's raw
// V when the denoiser is off.

// #include shared/bvh_trace.wgsl
// #include shared/hash.wgsl

// RtUniforms of src/render/passes/raytraced.rs.
struct RtUniforms {
    view_proj: mat4x4<f32>,
    // The previous frame's world → clip transform (reprojection).
    prev_view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // The frame's index: the sequence's position (frame · rays + ray).
    frame: u32,
    light_center: vec3<f32>,
    // 0 disk, 1 line, 2 rectangle or polygon (shared/camera.wgsl's LIGHT_*).
    light_kind: u32,
    light_normal: vec3<f32>,
    light_corner_count: u32,
    light_u: vec3<f32>,
    light_area: f32,
    light_w: vec3<f32>,
    // The disk's radius (0 for the others).
    light_radius: f32,
    // A line light's ends (zero for the others).
    line_a: vec3<f32>,
    // Shadow rays per pixel this frame.
    rays: u32,
    line_b: vec3<f32>,
    // Frames the running mean spans at most (1: this frame alone).
    history: u32,
    // The image, in pixels.
    width: u32,
    height: u32,
    // tan of half the vertical field of view.
    tan_half_fov: f32,
    // The spatial filter's largest radius, in pixels (0: no spatial filter).
    radius: f32,
    node_count: u32,
    triangle_count: u32,
    // RT_* bits below.
    flags: u32,
    // The light's extent across (a disk's or polygon's diameter, a line's length): the penumbra
    // estimate's light size.
    light_size: f32,
    // The corners about the centre in (light_u, light_w), two per vector (CameraUniforms').
    light_corners: array<vec4<f32>, 8>,
};

// The previous frame's history is there and seen from a camera whose transform is valid.
const RT_HISTORY: u32 = 1u;
// The light or a caster moved since the previous frame.
const RT_MOTION: u32 = 2u;

const LIGHT_LINE: u32 = 1u;
const LIGHT_POLYGON: u32 = 2u;
// Hits closer than this fraction of the segment to either end are ignored (the reference's
// geometry::oracle::SELF_EPS).
const SELF_EPS: f32 = 1e-4;
// While something moves, the history spans at most this many frames.
const MOTION_HISTORY: f32 = 2.0;
// The previous frame saw the same surface at a tap when its position is within this share of
// the distance to the camera, and its normal within about 25 degrees.
const SAME_SURFACE: f32 = 0.01;
const SAME_NORMAL: f32 = 0.9;
// Spatial taps (a Vogel disk) besides the centre.
const TAPS: u32 = 12u;

@group(0) @binding(0) var<uniform> rt: RtUniforms;
// The nodes, then the triangles (shared/bvh_trace.wgsl).
@group(0) @binding(1) var<storage, read> bvh: array<vec4<f32>>;
// The screen prepass's world positions (w = 1 where a surface is).
@group(0) @binding(2) var positions: texture_2d<f32>;
// This frame's rays: (V of its rays, mean distance to the blockers, rays blocked, BVH nodes
// visited).
@group(0) @binding(3) var<storage, read_write> raw: array<vec4<f32>>;
// This frame's geometry: (position, normal code; 0 where no surface is) (rt_normal_code).
@group(0) @binding(4) var<storage, read_write> geo: array<vec4<f32>>;
// The previous frame's geometry and history.
@group(0) @binding(5) var<storage, read> prev_geo: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> prev_history: array<vec4<f32>>;
// The history after this frame: (V's running mean, the hit distance's running mean, frames in
// the mean, frames with a blocked ray in the hit distance's mean).
@group(0) @binding(7) var<storage, read_write> history: array<vec4<f32>>;
// What the camera pass reads: (V denoised, BVH nodes this frame, the spatial radius in pixels,
// frames in the mean).
@group(0) @binding(8) var<storage, read_write> denoised: array<vec4<f32>>;

fn pixel_index(p: vec2<i32>) -> u32 {
    return u32(p.y) * rt.width + u32(p.x);
}

fn in_image(p: vec2<i32>) -> bool {
    return p.x >= 0 && p.y >= 0 && p.x < i32(rt.width) && p.y < i32(rt.height);
}

// A unit normal in one f32: octahedral, 1024 steps a side, + 1 (0 is "no surface").
fn rt_normal_code(n: vec3<f32>) -> f32 {
    var o = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        o = (1.0 - abs(o.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), o >= vec2<f32>(0.0));
    }
    let q = vec2<u32>(clamp(round((o * 0.5 + 0.5) * 1023.0), vec2<f32>(0.0), vec2<f32>(1023.0)));
    return f32(q.x * 1024u + q.y + 1u);
}

fn rt_normal_of(code: f32) -> vec3<f32> {
    let c = u32(code) - 1u;
    let o = vec2<f32>(f32(c / 1024u), f32(c % 1024u)) / 1023.0 * 2.0 - 1.0;
    var n = vec3<f32>(o, 1.0 - abs(o.x) - abs(o.y));
    if n.z < 0.0 {
        n = vec3<f32>((1.0 - abs(n.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0)), n.z);
    }
    return normalize(n);
}

// Point k of the R2 sequence shifted by `seed`, in 0.32 fixed point so that it never loses
// precision however many frames have run.
fn r2(seed: vec2<u32>, k: u32) -> vec2<f32> {
    let q = seed + k * vec2<u32>(3242174889u, 2447445413u);
    return vec2<f32>(q >> vec2<u32>(8u)) * 5.96046448e-8;
}

fn corner(i: u32) -> vec2<f32> {
    let c = rt.light_corners[i / 2u];
    return select(c.xy, c.zw, (i % 2u) == 1u);
}

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// The point of the light at u in [0, 1)², uniform over its area (its length for a line), with
// neighbouring u kept near: a disk by the concentric map (Shirley and Chiu), a convex polygon by
// its fan from corner 0 (u.x picks a triangle by area, and is spread again within it).
fn light_point(u: vec2<f32>) -> vec3<f32> {
    if rt.light_kind == LIGHT_LINE {
        return mix(rt.line_a, rt.line_b, u.x);
    }
    var p = vec2<f32>(0.0);
    if rt.light_kind == LIGHT_POLYGON {
        let c0 = corner(0u);
        let n = rt.light_corner_count;
        var target_area = u.x * rt.light_area;
        for (var i = 1u; i + 1u < n; i++) {
            let a = corner(i);
            let b = corner(i + 1u);
            let area = 0.5 * abs(cross2(a - c0, b - c0));
            if target_area <= area || i + 2u == n {
                let s = clamp(target_area / max(area, 1e-30), 0.0, 1.0);
                let r = sqrt(s);
                p = c0 * (1.0 - r) + a * (r * (1.0 - u.y)) + b * (r * u.y);
                break;
            }
            target_area -= area;
        }
    } else {
        let a = 2.0 * u - 1.0;
        var r = 0.0;
        var phi = 0.0;
        if abs(a.x) > abs(a.y) {
            r = a.x;
            phi = 0.78539816 * (a.y / a.x);
        } else if a.y != 0.0 {
            r = a.y;
            phi = 1.5707963 - 0.78539816 * (a.x / a.y);
        }
        p = rt.light_radius * r * vec2<f32>(cos(phi), sin(phi));
    }
    return rt.light_center + p.x * rt.light_u + p.y * rt.light_w;
}

// The one-sided planar light reaches x (every point, for a line light).
fn lit_side(x: vec3<f32>) -> bool {
    return rt.light_kind == LIGHT_LINE || dot(x - rt.light_center, rt.light_normal) > 0.0;
}

fn position_at(p: vec2<i32>) -> vec4<f32> {
    return textureLoad(positions, p, 0);
}

// The surface's normal from the positions about it: in each direction the neighbour nearer in
// space (so an edge between two surfaces does not bend it), turned toward the camera.
fn normal_at(p: vec2<i32>, x: vec3<f32>) -> vec3<f32> {
    var d = array<vec3<f32>, 2>(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var axis = 0; axis < 2; axis++) {
        let step = select(vec2<i32>(0, 1), vec2<i32>(1, 0), axis == 0);
        var best = vec3<f32>(0.0);
        var best_len = 3.4e38;
        for (var s = -1; s <= 1; s += 2) {
            let q = p + step * s;
            if !in_image(q) {
                continue;
            }
            let y = position_at(q);
            if y.w == 0.0 {
                continue;
            }
            let e = (y.xyz - x) * f32(s);
            let len = length(e);
            if len < best_len {
                best = e;
                best_len = len;
            }
        }
        d[axis] = best;
    }
    let to_eye = rt.eye - x;
    var n = cross(d[0], d[1]);
    if dot(n, n) < 1e-30 {
        return normalize(to_eye);
    }
    n = normalize(n);
    return select(-n, n, dot(n, to_eye) >= 0.0);
}

@compute @workgroup_size(8, 8)
fn cs_trace(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let x4 = position_at(p);
    if x4.w == 0.0 {
        raw[i] = vec4<f32>(0.0);
        geo[i] = vec4<f32>(0.0);
        return;
    }
    let x = x4.xyz;
    geo[i] = vec4<f32>(x, rt_normal_code(normal_at(p, x)));
    if !lit_side(x) {
        raw[i] = vec4<f32>(0.0);
        return;
    }
    let seed = vec2<u32>(hash2(u32(p.x), u32(p.y)), hash2(u32(p.y) + 0x632be5abu, u32(p.x)));
    var seen = 0u;
    var blocked = 0u;
    var hit_distance = 0.0;
    var nodes = 0u;
    for (var r = 0u; r < rt.rays; r++) {
        let s = light_point(r2(seed, rt.frame * rt.rays + r));
        let d = s - x;
        let h = bvh_any_hit(x, d, SELF_EPS, 1.0 - SELF_EPS, rt.node_count, rt.triangle_count);
        nodes += h.nodes;
        if h.hit {
            blocked += 1u;
            hit_distance += h.t * length(d);
        } else {
            seen += 1u;
        }
    }
    let n = f32(max(rt.rays, 1u));
    raw[i] = vec4<f32>(f32(seen) / n, hit_distance / max(f32(blocked), 1.0), f32(blocked), f32(nodes));
}

// The range of this frame's raw V over the 3 × 3 pixels about p (surfaces only).
fn raw_range(p: vec2<i32>) -> vec2<f32> {
    var lo = 1.0;
    var hi = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2<i32>(dx, dy);
            if !in_image(q) || geo[pixel_index(q)].w == 0.0 {
                continue;
            }
            let v = raw[pixel_index(q)].x;
            lo = min(lo, v);
            hi = max(hi, v);
        }
    }
    return vec2<f32>(lo, max(hi, lo));
}

@compute @workgroup_size(8, 8)
fn cs_temporal(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let g = geo[i];
    let now = raw[i];
    if g.w == 0.0 {
        history[i] = vec4<f32>(0.0);
        return;
    }
    // The previous frame's history at this surface point, bilinear over the taps that saw it.
    var old = vec4<f32>(0.0);
    var weight = 0.0;
    if (rt.flags & RT_HISTORY) != 0u && rt.history > 1u {
        let clip = rt.prev_view_proj * vec4<f32>(g.xyz, 1.0);
        if clip.w > 0.0 {
            let ndc = clip.xy / clip.w;
            let at = vec2<f32>((ndc.x * 0.5 + 0.5) * f32(rt.width), (0.5 - ndc.y * 0.5) * f32(rt.height)) - 0.5;
            let base = vec2<i32>(floor(at));
            let f = at - floor(at);
            let n = rt_normal_of(g.w);
            let tolerance = SAME_SURFACE * distance(g.xyz, rt.eye);
            for (var k = 0; k < 4; k++) {
                let o = vec2<i32>(k % 2, k / 2);
                let q = base + o;
                let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
                if w <= 0.0 || !in_image(q) {
                    continue;
                }
                let j = pixel_index(q);
                let pg = prev_geo[j];
                if pg.w == 0.0 || distance(pg.xyz, g.xyz) > tolerance || dot(rt_normal_of(pg.w), n) < SAME_NORMAL {
                    continue;
                }
                old += w * prev_history[j];
                weight += w;
            }
        }
    }
    var frames = 0.0;
    var hit_frames = 0.0;
    var v_mean = 0.0;
    var hit_mean = 0.0;
    if weight > 0.01 {
        old /= weight;
        let cap = select(f32(rt.history), min(f32(rt.history), MOTION_HISTORY), (rt.flags & RT_MOTION) != 0u);
        frames = min(old.z, cap - 1.0);
        hit_frames = min(old.w, cap - 1.0);
        v_mean = old.x;
        hit_mean = old.y;
        if (rt.flags & RT_MOTION) != 0u {
            let range = raw_range(p);
            v_mean = clamp(v_mean, range.x, range.y);
        }
    }
    frames = max(frames, 0.0);
    hit_frames = max(hit_frames, 0.0);
    v_mean = mix(v_mean, now.x, 1.0 / (frames + 1.0));
    if now.z > 0.0 {
        hit_mean = mix(hit_mean, now.y, 1.0 / (hit_frames + 1.0));
        hit_frames += 1.0;
    }
    history[i] = vec4<f32>(v_mean, hit_mean, frames + 1.0, hit_frames);
}

// The penumbra's half width at surface point x in pixels, from the mean distance to the
// blockers h (PCSS's estimate: light size × h / (distance to the light − h)); 0 where no ray of
// the history was blocked.
fn penumbra_pixels(x: vec3<f32>, h: vec4<f32>) -> f32 {
    if h.w == 0.0 {
        return 0.0;
    }
    let to_light = distance(x, rt.light_center);
    let blocker = clamp(h.y, 0.0, 0.999 * to_light);
    let width = rt.light_size * blocker / max(to_light - blocker, 1e-6);
    let pixel = 2.0 * distance(x, rt.eye) * rt.tan_half_fov / f32(rt.height);
    return 0.5 * width / max(pixel, 1e-12);
}

@compute @workgroup_size(8, 8)
fn cs_spatial(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if !in_image(p) {
        return;
    }
    let i = pixel_index(p);
    let g = geo[i];
    let h = history[i];
    let work = raw[i].w;
    if g.w == 0.0 {
        denoised[i] = vec4<f32>(0.0);
        return;
    }
    // The radius: the pixel's own penumbra estimate, or its neighbours' where none of its rays
    // was blocked yet (a lit pixel at a penumbra's edge).
    var pen = penumbra_pixels(g.xyz, h);
    for (var k = 0u; k < 8u; k++) {
        let a = f32(k) * 0.78539816;
        let reach = select(2.0, 0.5 * rt.radius, (k % 2u) == 1u);
        let q = p + vec2<i32>(round(reach * vec2<f32>(cos(a), sin(a))));
        if !in_image(q) {
            continue;
        }
        let j = pixel_index(q);
        if geo[j].w == 0.0 {
            continue;
        }
        pen = max(pen, penumbra_pixels(geo[j].xyz, history[j]));
    }
    // Shrunk as samples accumulate: the noise left falls as 1/sqrt(samples), and so does the
    // footprint that still pays for its blur (the whole half width at one sample, a quarter of it
    // at 16).
    let samples = h.z * f32(max(rt.rays, 1u));
    let radius = min(rt.radius, pen * min(1.0, 1.0 / sqrt(samples)));
    if radius < 0.75 {
        denoised[i] = vec4<f32>(h.x, work, 0.0, h.z);
        return;
    }
    let n = rt_normal_of(g.w);
    let plane = SAME_SURFACE * distance(g.xyz, rt.eye);
    // The disk's rotation: interleaved gradient noise (Jimenez 2014), fixed per pixel.
    let turn = 6.2831853 * fract(52.9829189 * fract(dot(vec2<f32>(p), vec2<f32>(0.06711056, 0.00583715))));
    var sum = h.x * h.z;
    var total = h.z;
    for (var k = 0u; k < TAPS; k++) {
        let r = radius * sqrt((f32(k) + 0.5) / f32(TAPS));
        let a = f32(k) * 2.3999632 + turn;
        let q = p + vec2<i32>(round(r * vec2<f32>(cos(a), sin(a))));
        if !in_image(q) || all(q == p) {
            continue;
        }
        let j = pixel_index(q);
        let gq = geo[j];
        if gq.w == 0.0 {
            continue;
        }
        let off_plane = abs(dot(gq.xyz - g.xyz, n));
        let normal_w = max(dot(rt_normal_of(gq.w), n), 0.0);
        let w = max(1.0 - off_plane / plane, 0.0) * normal_w * normal_w * normal_w * normal_w
            * exp(-2.0 * (r * r) / (radius * radius)) * history[j].z;
        sum += w * history[j].x;
        total += w;
    }
    denoised[i] = vec4<f32>(sum / max(total, 1e-6), work, radius, h.z);
}
