// `smrt`: shadow-map ray tracing as Unreal Engine 5 soft-shadows a local light from its virtual
// shadow map (src/render/methods/smrt.rs; UE's `TraceLocalLight` of
// VirtualShadowMapProjectionSpot.ush, `SMRTRayCast` of VirtualShadowMapSMRTTemplate.ush and
// `VirtualShadowMapScreenRayCast` of VirtualShadowMapProjection.usf), here on the centre's shadow
// map. Per pixel: the receiver pushed out along its normal; a short ray through the camera's
// depth (the prepass's positions) toward the light's centre says where the shadow-map rays may
// start; then a few rays toward points of the light, each clipped to a fraction of the way to the
// light (at most an angle seen from the light: the cap on the penumbra) and marched from its far
// end back to its start through the one depth layer the map holds, in steps crowded toward the
// start; a ray is hit where it passes behind the stored surface within one step, and where it
// jumps far behind (a depth gap) it is compared with the last surface it was in front of,
// extrapolated. Depths are compared as 1 / |y − c| (larger nearer the light), an affine stand-in
// for UE's reversed device depth, so the same tolerances hold. V = the rays that miss over the
// rays traced; with the adaptive count a 2×2 quad stops after one ray where all of it missed, and
// after two where all of it was hit (UE votes over a wave).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/hash.wgsl

// SmrtParams of src/render/methods/smrt.rs.
struct SmrtParams {
    // r.Shadow.Virtual.SMRT.ExtrapolateMaxSlopeLocal: the extrapolation's slope at most this
    // share of the ray's own change of depth per unit of time (0: held).
    extrapolate_slope: f32,
    // 1 / tan(r.Shadow.Virtual.SMRT.MaxRayAngleFromLight).
    cot_max_angle: f32,
    // r.Shadow.Virtual.SMRT.TexelDitherScaleLocal times the light's VSM texel dither scale.
    texel_dither: f32,
    // r.Shadow.Virtual.SMRT.MaxSlopeBiasLocal.
    max_slope_bias: f32,
    // r.Shadow.Virtual.ScreenRayLength: the screen ray's length, a share of the view's half
    // height at the receiver's depth.
    screen_ray: f32,
    // r.Shadow.Virtual.NormalBias / 1000: the normal offset, a share of the view's half width at
    // the receiver's distance from the camera.
    normal_bias: f32,
    // tan of half the camera's field of view, across and up.
    tan_half_fov: vec2<f32>,
    // r.Shadow.Virtual.SMRT.RayCountLocal: rays per pixel.
    rays: u32,
    // r.Shadow.Virtual.SMRT.SamplesPerRayLocal: shadow-map samples per ray.
    steps: u32,
    // r.Shadow.Virtual.SMRT.AdaptiveRayCount: 1 for the adaptive ray count.
    adaptive: u32,
    _pad0: u32,
};

@group(1) @binding(2) var<uniform> params: SmrtParams;
@group(1) @binding(3) var screen_position: texture_2d<f32>;

// UE's least normal offset and least shadow resolution scale (0.02 and 0.1 of its centimetres),
// in this project's metres.
const MIN_NORMAL_BIAS: f32 = 0.0002;
const MIN_RESOLUTION: f32 = 0.001;
// The screen ray's samples (SCREEN_RAY_SAMPLES).
const SCREEN_RAY_SAMPLES: u32 = 4u;

// UE's EvolveSobolSeed: the next ray's step offset from this one's bits.
fn evolve(seed: u32) -> u32 {
    var x = seed + 2739110765u;
    x ^= x >> 16u;
    x *= 0x21f0aaadu;
    x ^= x >> 15u;
    return x;
}

fn unit_of(bits: u32) -> f32 {
    return f32(bits >> 8u) * 5.96046448e-8;
}

// Point i of the two-dimensional Sobol sequence, XOR-scrambled by `scramble`: every power-of-two
// prefix is stratified over the unit square, so rays 0 and 1 fall in opposite halves.
fn sobol2(i: u32, scramble: vec2<u32>) -> vec2<f32> {
    var y = 0u;
    var v = 0x80000000u;
    for (var k = 0u; k < 32u; k++) {
        if ((i >> k) & 1u) != 0u {
            y ^= v;
        }
        v ^= v >> 1u;
    }
    let bits = vec2<u32>(reverseBits(i), y) ^ scramble;
    return vec2<f32>(f32(bits.x >> 8u), f32(bits.y >> 8u)) * 5.96046448e-8;
}

// Shirley and Chiu's concentric map of the unit square onto the unit disk (UE's
// UniformSampleDiskConcentric).
fn concentric(u: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * u - 1.0;
    if a.x == 0.0 && a.y == 0.0 {
        return vec2<f32>(0.0);
    }
    var r: f32;
    var phi: f32;
    if abs(a.x) > abs(a.y) {
        r = a.x;
        phi = 0.785398163 * (a.y / a.x);
    } else {
        r = a.y;
        phi = 1.570796327 - 0.785398163 * (a.x / a.y);
    }
    return r * vec2<f32>(cos(phi), sin(phi));
}

// A point of the light for u in the unit square, of uniform area density: the disk by the
// concentric map; a rectangle or polygon by its fan of triangles from the centre, the concentric
// map's angle picking one by area and its radius the way out, so the same u lands within a few
// per cent of the same place on a disk and on the regular polygon inscribed in it (corner 0 on
// the disk's first axis): a polygon's shadow meets its disk's.
fn light_point(u: vec2<f32>) -> vec3<f32> {
    let d = concentric(u);
    var p: vec2<f32>;
    if polygon_light() {
        let n = min(camera.light_corner_count, 16u);
        let target_area = fract(atan2(d.y, d.x) / 6.2831853 + 1.0) * camera.light_area;
        var before = 0.0;
        var a = light_corner(0u);
        var b = light_corner(min(1u, n - 1u));
        var t = 0.0;
        var found = false;
        var previous = light_corner(0u);
        for (var i = 0u; i < n; i++) {
            let next = light_corner(select(i + 1u, 0u, i + 1u == n));
            // The triangle (centre, previous, next): half their cross product.
            let area = 0.5 * abs(previous.x * next.y - previous.y * next.x);
            let take = !found && (target_area < before + area || i + 1u == n);
            a = select(a, previous, take);
            b = select(b, next, take);
            t = select(t, clamp((target_area - before) / max(area, 1e-30), 0.0, 1.0), take);
            found = found || take;
            before += area;
            previous = next;
        }
        p = length(d) * mix(a, b, t);
    } else {
        p = camera.light_radius * d;
    }
    return camera.light_center + p.x * camera.light_u + p.y * camera.light_w;
}

// An orthonormal basis whose third axis is `z` (Frisvad / Duff et al.; UE's GetTangentBasis).
fn tangent_basis(z: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, z.z >= 0.0);
    let a = -1.0 / (s + z.z);
    let b = z.x * z.y * a;
    let t = vec3<f32>(1.0 + s * z.x * z.x * a, s * b, -s * z.x);
    let bt = vec3<f32>(b, s + z.y * z.y * a, -z.y);
    return mat3x3<f32>(t, bt, z);
}

fn pixel_of(ndc: vec2<f32>, size: vec2<f32>) -> vec2<i32> {
    let p = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * size;
    return clamp(vec2<i32>(floor(p)), vec2<i32>(0), vec2<i32>(size) - 1);
}

// The camera's reversed depth of the surface the prepass saw at `pixel` (0 where none).
fn screen_depth(pixel: vec2<i32>) -> f32 {
    let p = textureLoad(screen_position, pixel, 0);
    if p.w < 0.5 {
        return 0.0;
    }
    let clip = camera.view_proj * vec4<f32>(p.xyz, 1.0);
    return clip.z / clip.w;
}

// UE's VirtualShadowMapScreenRayCast: four samples of the camera's depth along `length` of the
// ray from `origin` toward `dir`; where one lies behind a surface that is not the start pixel's
// own, the shadow-map rays start a step and a half before it, else at the end.
fn screen_ray_offset(origin: vec3<f32>, dir: vec3<f32>, length: f32, dither: f32) -> f32 {
    let size = vec2<f32>(textureDimensions(screen_position));
    let start_clip = camera.view_proj * vec4<f32>(origin, 1.0);
    let end_clip = camera.view_proj * vec4<f32>(origin + dir * length, 1.0);
    if !(start_clip.w > 0.0) || !(end_clip.w > 0.0) {
        return length;
    }
    let start = start_clip.xyz / start_clip.w;
    let step = end_clip.xyz / end_clip.w - start;
    let start_depth = screen_depth(pixel_of(start.xy, size));
    let dt = 1.0 / f32(SCREEN_RAY_SAMPLES);
    var time = (dither - 0.5) * dt + dt;
    for (var i = 0u; i < SCREEN_RAY_SAMPLES; i++) {
        let p = start + step * time;
        let depth = screen_depth(pixel_of(p.xy, size));
        count_work(1.0);
        // Reversed depth: the sample behind the surface there reads less.
        if depth != start_depth && p.z < depth {
            return length * max(0.0, time - 1.5 * dt);
        }
        time += dt;
    }
    return length;
}

// One shadow-map ray: its ends, their clip positions in the map's view, its depth bias and the
// extrapolation's slope clamp (both in 1 / distance from c).
struct SmrtRay {
    start: vec3<f32>,
    end: vec3<f32>,
    clip_start: vec4<f32>,
    clip_end: vec4<f32>,
    bias: f32,
    slope_clamp: f32,
};

// 1 / |y − c|: larger nearer the light, as UE's reversed depth.
fn inverse_distance(y: vec3<f32>) -> f32 {
    return 1.0 / max(length(y - camera.light_center), 1e-30);
}

// UE's SMRTRayCast over the map: time 1 at the ray's end, 0 at its start, the times squared
// (crowded toward the start) and shifted by `step_offset`; time runs linearly in the map's
// projected space (UE's UVz), which is a point `s` of the way along the ray in the world.
fn ray_hits(ray: SmrtRay, steps: u32, step_offset: f32) -> bool {
    let not_set = -10000.0;
    var history = not_set;
    var history_time = -1.0;
    var slope = 0.0;
    var previous = -1.0;
    let time_scale = -1.0 / f32(steps);
    let time_bias = 1.0 + (1.0 - step_offset) * time_scale;
    let ws = ray.clip_start.w;
    let we = ray.clip_end.w;
    for (var i = 0u; i <= steps; i++) {
        let k = time_scale * f32(i) + time_bias;
        let time = select(k * k, 0.0, i == steps);
        let s = time * ws / max(time * ws + (1.0 - time) * we, 1e-30);
        let clip = mix(ray.clip_start, ray.clip_end, s);
        if !(clip.w > 0.0) {
            continue;
        }
        let ndc = clip.xy / clip.w;
        if any(abs(ndc) > vec2<f32>(1.0)) {
            continue;
        }
        let o = textureLoad(d_o, texel_of(vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5)), 0).x;
        count_work(1.0);
        let reference = inverse_distance(mix(ray.start, ray.end, s)) + ray.bias;
        let sample_depth = 1.0 / max(o, 1e-30);
        if history == not_set {
            // The first sample in the map: a plain depth test.
            history = sample_depth;
            history_time = time;
            if sample_depth > reference {
                return true;
            }
        } else {
            let tolerance = abs(reference - previous) * 1.05;
            // Far behind what the map holds here: a nearer surface jumped in (a gap).
            let behind = sample_depth - reference > tolerance;
            var compared = sample_depth;
            let dt = time - history_time;
            if behind {
                compared = slope * dt + history;
            } else if sample_depth != history {
                slope = clamp((sample_depth - history) / select(dt, -1e-12, dt == 0.0), -ray.slope_clamp, ray.slope_clamp);
                history = sample_depth;
                history_time = time;
            }
            // Crossed behind the compared surface within this step.
            let half = 0.5 * tolerance;
            if abs(reference - compared + half) < half {
                return true;
            }
        }
        previous = reference;
    }
    return false;
}

// What every ray of a pixel shares (UE's TraceLocalLight before its loop).
struct SmrtPixel {
    // The receiver pushed out along its normal, and its normal.
    x: vec3<f32>,
    n: vec3<f32>,
    // Toward the light's centre, the distance there, and the cone's frame about it.
    axis: vec3<f32>,
    distance: f32,
    frame: mat3x3<f32>,
    // The receiver's plane's slope in that frame (UE's DepthSlopeTangent).
    depth_slope: vec2<f32>,
    // How far along each ray the march starts.
    start_offset: f32,
    // The texel dither's size and the dither's and the depth bias's caps.
    dither: f32,
    max_dither_slope: f32,
    max_depth_bias: f32,
    // The sample scramble and the first ray's step offset.
    scramble: vec2<u32>,
    seed: u32,
};

fn smrt_pixel(x_in: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>, d: f32) -> SmrtPixel {
    var p: SmrtPixel;
    let u = params;
    let view_depth = (camera.view_proj * vec4<f32>(x_in, 1.0)).w;
    let normal_bias = max(MIN_NORMAL_BIAS, u.normal_bias * length(x_in - camera.eye) * u.tan_half_fov.x);
    p.x = x_in + n * normal_bias;
    p.n = n;
    let to_light = camera.light_center - p.x;
    p.distance = length(to_light);
    p.axis = to_light / max(p.distance, 1e-30);
    p.frame = tangent_basis(p.axis);
    let n_local = transpose(p.frame) * n;
    p.depth_slope = -n_local.xy / select(n_local.z, 1e-6, abs(n_local.z) < 1e-6);
    let noise = interleaved_gradient_noise(pixel);
    let screen_length = u.screen_ray * u.tan_half_fov.y * view_depth;
    p.start_offset = screen_ray_offset(p.x, p.axis, screen_length, noise);
    // UE sizes these by its shadow resolution scale, half a screen pixel's world size, which its
    // virtual map's resolution follows; this map is fixed, so half a texel's here.
    let resolution = max(MIN_RESOLUTION, 0.5 * shadow.texel_slope * d);
    p.dither = u.texel_dither * resolution;
    p.max_dither_slope = u.max_slope_bias * p.dither;
    // In 1 / distance: the world's `resolution` at distance d is resolution / d².
    p.max_depth_bias = u.max_slope_bias * resolution / max(p.distance * p.distance, 1e-30);
    let px = vec2<u32>(max(pixel, vec2<f32>(0.0)));
    p.scramble = vec2<u32>(hash2(px.x, px.y), hash2(px.y + 0x51ed27u, px.x));
    p.seed = bitcast<u32>(noise);
    return p;
}

// Where the receiver's plane (through p.x) meets the ray from c toward `y`, in 1 / distance.
fn plane_inverse_distance(p: SmrtPixel, y: vec3<f32>) -> f32 {
    let c = camera.light_center;
    let dir = normalize(y - c);
    let denom = dot(p.n, dir);
    let t = dot(p.n, p.x - c) / select(denom, 1e-12, abs(denom) < 1e-12);
    return select(inverse_distance(y), 1.0 / t, t > 0.0);
}

// UE's ComputeOptimalSlopeBiasLocal in 1 / distance: twice the receiver plane's rise toward the
// light between the ray's start and the centre of its texel.
fn optimal_bias(p: SmrtPixel, start: vec3<f32>, clip: vec4<f32>) -> f32 {
    let uv = vec2<f32>(clip.x / clip.w * 0.5 + 0.5, 0.5 - clip.y / clip.w * 0.5);
    let centre_uv = (vec2<f32>(texel_of(uv)) + 0.5) / shadow.size;
    let ndc = vec4<f32>(centre_uv.x * 2.0 - 1.0, 1.0 - centre_uv.y * 2.0, 0.5, 1.0);
    let q = shadow.inv_light_view_proj * ndc;
    let centre = q.xyz / q.w;
    return 2.0 * max(0.0, plane_inverse_distance(p, centre) - plane_inverse_distance(p, start));
}

// Ray i of the pixel: whether the map stops it (light behind the receiver's own plane counts as
// stopped: UE traces such a ray into the receiver, whose own surface in the map stops it).
fn ray_blocked(p: SmrtPixel, i: u32, step_offset: f32) -> bool {
    let u = sobol2(i, p.scramble);
    let q = light_point(u);
    if !(dot(p.n, q - p.x) > 0.0) {
        return true;
    }
    let dir = normalize(q - p.x);
    let cos_theta = clamp(dot(dir, p.axis), 0.0, 1.0);
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    // Texel dither: the start moved within the receiver's plane (toward the light only).
    let r = vec2<f32>(unit_of(hash2(p.scramble.x ^ i, 0xa511e9b3u)), unit_of(hash2(p.scramble.y ^ i, 0x63d83595u)));
    let offset = (r - 0.5) * p.dither;
    let rise = min(p.max_dither_slope, 2.0 * max(0.0, dot(p.depth_slope, offset)));
    let origin = p.x + p.frame * vec3<f32>(offset, rise);
    // The ray clipped to the angle the light may see it span (UE's MaxRayAngleFromLight), and at
    // most three quarters of the way to the light.
    let clamped_end = p.distance * 0.75 * clamp(1.5 / (cos_theta + params.cot_max_angle * sin_theta), 0.0, 1.0);
    let start_length = min(p.start_offset, clamped_end - 1e-6);
    var ray: SmrtRay;
    ray.start = origin + dir * start_length;
    ray.end = origin + dir * clamped_end;
    ray.clip_start = shadow.light_view_proj * vec4<f32>(ray.start, 1.0);
    ray.clip_end = shadow.light_view_proj * vec4<f32>(ray.end, 1.0);
    ray.bias = min(p.max_depth_bias, optimal_bias(p, ray.start, ray.clip_start));
    ray.slope_clamp = params.extrapolate_slope * abs(inverse_distance(ray.end) - inverse_distance(ray.start));
    let steps = max(params.steps, 1u);
    return ray_hits(ray, steps, step_offset);
}

// All four pixels of this one's 2×2 quad hold `b` (fine derivatives: in uniform control flow).
fn quad_all(b: bool) -> bool {
    let v = select(0.0, 1.0, b);
    let row = select(0.0, v, dpdxFine(v) == 0.0);
    return row > 0.5 && dpdyFine(row) == 0.0;
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    // No early return before the quad's votes: they read the neighbours' values by derivatives,
    // which need every pixel of the quad here.
    let l = light_lookup(x, n);
    let traced = in_front_of_light(x) && faces_light_center(x, n) && l.inside;
    let rays = max(params.rays, 1u);
    let adaptive = params.adaptive != 0u;
    var p: SmrtPixel;
    var offset = 0.0;
    var misses = 0u;
    var count = 0u;
    if traced {
        p = smrt_pixel(x, n, pixel, l.d);
        offset = unit_of(p.seed);
        misses = select(1u, 0u, ray_blocked(p, 0u, offset));
        count = 1u;
    }
    // UE's adaptive count: after the first ray, stop where every lane missed (lit) ...
    let all_missed = quad_all(!traced || misses == 1u);
    let lit_quad = adaptive && all_missed;
    if traced && !lit_quad && rays > 1u {
        p.seed = evolve(p.seed);
        offset = unit_of(p.seed);
        misses += select(1u, 0u, ray_blocked(p, 1u, offset));
        count = 2u;
    }
    // ... after the second, where every lane was hit by both (umbra).
    let all_hit = quad_all(!traced || misses == 0u);
    let dark_quad = adaptive && !lit_quad && all_hit;
    if traced && !lit_quad && !dark_quad {
        for (var i = 2u; i < rays; i++) {
            p.seed = evolve(p.seed);
            offset = unit_of(p.seed);
            misses += select(1u, 0u, ray_blocked(p, i, offset));
        }
        count = rays;
    }
    if !traced {
        // Not marched: behind the light, turned from its centre (dark), or off the map (lit).
        took_path(0.0);
        let lit = in_front_of_light(x) && faces_light_center(x, n);
        return plain(select(0.0, 1.0, lit));
    }
    took_path(select(select(3.0, 2.0, dark_quad), 1.0, lit_quad));
    return plain(f32(misses) / f32(max(count, 1u)));
}
