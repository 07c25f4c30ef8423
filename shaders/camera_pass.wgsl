// The camera pass: per pixel |cx|, the hidden-from-centre test against |cx_o|, the parameter t by
// the corrected eq. (3), V(t), and diffuse shading from the disk times V. Its CPU twin is
// DBufferTwin::sample (src/geometry/twin.rs) with geometry::visibility.
// The comparison methods are resolved here too, from the same inputs: the hard shadow map (the
// |cx_o| test alone), PCF and PCSS of it, the average of N point-light maps (`sampled`), or a V
// computed elsewhere (the ray-cast reference) shaded the same way.
// #include shared/surface.wgsl
// #include shared/sample_lights.wgsl

struct CameraUniforms {
    view_proj: mat4x4<f32>,
    light_view_proj: mat4x4<f32>,
    // xyz: the camera position.
    eye: vec4<f32>,
    // xyz: c; w: radius.
    light_center: vec4<f32>,
    // xyz: n_c; w: intensity.
    light_normal: vec4<f32>,
    // x: constant bias (relative to |cx|); y: slope bias (× texel slope); z: D-buffer size in
    // texels; w: the slope one texel spans in the light view.
    bias: vec4<f32>,
    // x: method (0 dbuffer, 1 hard, 2 pcf, 3 pcss, 4 sampled, 5 external V); y: V(t) variant (0 smoothstep, 1 sqrt, 2 exact, 3 linear);
    // z: ambient term × 1000; w: unused.
    mode: vec4<u32>,
};

@group(0) @binding(0) var<uniform> u: CameraUniforms;
@group(0) @binding(1) var d_o: texture_2d<f32>;
@group(0) @binding(2) var d_u: texture_2d<f32>;
@group(0) @binding(3) var d_p: texture_2d<f32>;

struct MethodUniforms {
    // x: PCF radius in texels; y: PCSS blocker taps; z: PCSS filter taps; w: sampled lights.
    params: vec4<f32>,
    // x: the nearest caster's distance from c (PCSS blocker search).
    pcss: vec4<f32>,
    // Light-view clip space back to world.
    inv_light_view_proj: mat4x4<f32>,
    // 64 points in the unit disk, two per entry; every prefix is spread over the disk.
    poisson: array<vec4<f32>, 32>,
};

@group(1) @binding(0) var<uniform> m: MethodUniforms;
@group(1) @binding(1) var sample_maps: texture_2d_array<f32>;
@group(1) @binding(2) var<uniform> sample_lights: SampleLights;
@group(1) @binding(3) var external_v: texture_2d<f32>;

struct SurfaceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) normal: vec3<f32>,
    @location(2) @interpolate(flat) albedo: f32,
};

@vertex
fn vs_main(v: SurfaceIn) -> SurfaceOut {
    var out: SurfaceOut;
    out.clip = u.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.albedo = v.albedo;
    return out;
}

// Branch codes, as geometry::Branch::code().
const UMBRA: f32 = 0.0;
const PENUMBRA_HIDDEN: f32 = 1.0;
const PENUMBRA_VISIBLE: f32 = 2.0;
const LIT: f32 = 3.0;

// The visible fraction of the unit disk beyond a chord at signed distance h from its centre.
fn disk_segment_fraction(h_in: f32) -> f32 {
    let h = clamp(h_in, -1.0, 1.0);
    return (acos(h) - h * sqrt(max(1.0 - h * h, 0.0))) / 3.14159265358979;
}

fn v_of_t(t_in: f32, variant: u32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    switch variant {
        case 1u: { return sqrt(t); }
        case 2u: { return disk_segment_fraction(1.0 - 2.0 * t); }
        case 3u: { return t; }
        default: { return t * t * (3.0 - 2.0 * t); }
    }
}

struct Visibility {
    v: f32,
    t: f32,
    branch: f32,
};

// V given for a method that is not the D-buffer: t = V, the branch by the class of V.
fn plain(v: f32) -> Visibility {
    var out: Visibility;
    out.v = v;
    out.t = v;
    out.branch = select(select(PENUMBRA_VISIBLE, LIT, v >= 0.996), UMBRA, v <= 0.004);
    return out;
}

// The D-buffer texel under a point of the light view's image, `uv` in [0, 1]².
fn texel_of(uv: vec2<f32>) -> vec2<i32> {
    let size = u.bias.z;
    return vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), vec2<f32>(size - 1.0)));
}

// Where the receiver's plane (through x, normal n) meets the ray from c through the centre of
// `texel`: the |cx| a filter tap there must be compared with (receiver-plane depth bias).
fn receiver_distance(texel: vec2<i32>, x: vec3<f32>, n: vec3<f32>, d: f32) -> f32 {
    let size = u.bias.z;
    let uv = (vec2<f32>(texel) + 0.5) / size;
    let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
    let p = m.inv_light_view_proj * ndc;
    let c = u.light_center.xyz;
    let dir = normalize(p.xyz / p.w - c);
    let denom = dot(n, dir);
    let t = dot(n, x - c) / denom;
    // Grazing or behind: fall back to the point's own distance.
    return select(d, t, abs(denom) > 1e-4 && t > 0.0 && t < 4.0 * d);
}

// 1 where the shadow map at `texel` does not hide a receiver at `expected`.
fn lit_at(texel: vec2<i32>, expected: f32, rel_bias: f32) -> f32 {
    let size = i32(u.bias.z);
    let q = clamp(texel, vec2<i32>(0), vec2<i32>(size - 1));
    let o = textureLoad(d_o, q, 0).x;
    return select(0.0, 1.0, expected <= o + expected * rel_bias);
}

fn poisson(i: u32) -> vec2<f32> {
    let e = m.poisson[i / 2u];
    return select(e.zw, e.xy, i % 2u == 0u);
}

// A per-pixel rotation (interleaved gradient noise, Jimenez 2014).
fn rotation(pixel: vec2<f32>) -> mat2x2<f32> {
    let a = 6.2831853 * fract(52.9829189 * fract(dot(pixel, vec2<f32>(0.06711056, 0.00583715))));
    let cs = cos(a);
    let sn = sin(a);
    return mat2x2<f32>(cs, sn, -sn, cs);
}

// Percentage-closer soft shadows (Fernando 2005) for a disk of radius r seen from c: blockers
// are searched in the cone from x to the disk down to the nearest caster, and the filter spans
// the penumbra width their mean distance predicts. Sizes are slopes from c, over the slope one
// texel spans.
fn pcss(x: vec3<f32>, n: vec3<f32>, d: f32, uv: vec2<f32>, rel_bias: f32, pixel: vec2<f32>) -> f32 {
    let r = u.light_center.w;
    let near = max(m.pcss.x, 1e-4);
    if d <= near {
        return 1.0;
    }
    let texel_slope = max(u.bias.w, 1e-9);
    let size = u.bias.z;
    let centre = uv * size;
    let rot = rotation(pixel);
    let search = clamp(r * (d - near) / (d * near) / texel_slope, 1.0, size * 0.5);
    var blockers = 0.0;
    var sum = 0.0;
    let blocker_taps = u32(m.params.y);
    for (var i = 0u; i < blocker_taps; i++) {
        let tap = vec2<i32>(floor(centre + rot * poisson(i) * search));
        let q = clamp(tap, vec2<i32>(0), vec2<i32>(i32(size) - 1));
        let o = textureLoad(d_o, q, 0).x;
        let expected = receiver_distance(q, x, n, d);
        if o + expected * rel_bias < expected {
            blockers += 1.0;
            sum += o;
        }
    }
    if blockers == 0.0 {
        return 1.0;
    }
    let blocker = sum / blockers;
    let width = clamp(r * (d - blocker) / (blocker * d) / texel_slope, 1.0, size * 0.5);
    var lit = 0.0;
    let filter_taps = u32(m.params.z);
    for (var i = 0u; i < filter_taps; i++) {
        let tap = vec2<i32>(floor(centre + rot * poisson(i) * width));
        lit += lit_at(tap, receiver_distance(tap, x, n, d), rel_bias);
    }
    return lit / f32(filter_taps);
}

// N point lights on the disk, each with its own map, averaged (seed 002 §3.1).
fn sampled(x: vec3<f32>, n: vec3<f32>) -> f32 {
    let count = u32(m.params.w);
    var lit = 0.0;
    for (var i = 0u; i < count; i++) {
        let light = sample_lights.lights[i];
        let to_q = light.point.xyz - x;
        let dq = length(to_q);
        if !(dot(n, to_q) > 0.0) {
            continue;
        }
        let clip = light.view_proj * vec4<f32>(x, 1.0);
        let ndc = clip.xyz / clip.w;
        if clip.w <= 0.0 || any(abs(ndc.xy) > vec2<f32>(1.0)) {
            lit += 1.0;
            continue;
        }
        let texel = texel_of(vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5));
        let o = textureLoad(sample_maps, texel, i32(i), 0).x;
        let cos_i = clamp(dot(n, to_q) / dq, 0.05, 1.0);
        let tan_i = sqrt(1.0 - cos_i * cos_i) / cos_i;
        let bias = dq * (u.bias.x + u.bias.y * u.bias.w * tan_i);
        lit += select(0.0, 1.0, dq <= o + bias);
    }
    return lit / f32(max(count, 1u));
}

fn visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    var out: Visibility;
    let method = u.mode.x;
    if method == 5u {
        return plain(textureLoad(external_v, vec2<i32>(floor(pixel)), 0).x);
    }
    let c = u.light_center.xyz;
    let to_x = x - c;
    let d = length(to_x);
    if !(dot(to_x, u.light_normal.xyz) > 0.0) {
        // Behind the one-sided light.
        return plain(0.0);
    }
    if method == 4u {
        return plain(sampled(x, n));
    }
    // On a side turned away from the light centre (self-shadowed: the point lies on its own
    // caster's umbra exit, where D ≈ |cx_uv| is decided by rounding): nothing arrives. The oracle
    // agrees: rays from such a point run into the object.
    if !(dot(n, -to_x) > 0.0) {
        out.v = 0.0;
        out.t = 0.0;
        out.branch = UMBRA;
        return out;
    }
    let clip = u.light_view_proj * vec4<f32>(x, 1.0);
    let ndc = clip.xyz / clip.w;
    // Outside the fitted frustum no penumbra can reach: lit.
    if clip.w <= 0.0 || any(abs(ndc.xy) > vec2<f32>(1.0)) {
        out.v = 1.0;
        out.t = 1.0;
        out.branch = LIT;
        return out;
    }
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let texel = texel_of(uv);

    // Slope-scaled bias: a texel spans a slope of bias.w in the light view; on a surface tilted
    // away from the light its footprint grows with tan(incidence).
    let l = -to_x / d;
    let cos_i = clamp(abs(dot(n, l)), 0.05, 1.0);
    let tan_i = sqrt(1.0 - cos_i * cos_i) / cos_i;
    let rel_bias = u.bias.x + u.bias.y * u.bias.w * tan_i;
    let o = textureLoad(d_o, texel, 0).x;
    let hidden = d > o + d * rel_bias;

    if method == 1u {
        // Hard shadow map: the |cx_o| test alone.
        out.v = select(1.0, 0.0, hidden);
        out.t = out.v;
        out.branch = select(LIT, UMBRA, hidden);
        return out;
    }
    if method == 2u {
        // PCF: the same test over a (2R + 1)² block of texels, each against the receiver plane.
        let radius = i32(m.params.x);
        var lit = 0.0;
        for (var dy = -radius; dy <= radius; dy++) {
            for (var dx = -radius; dx <= radius; dx++) {
                let tap = texel + vec2<i32>(dx, dy);
                lit += lit_at(tap, receiver_distance(tap, x, n, d), rel_bias);
            }
        }
        let side = f32(2 * radius + 1);
        return plain(lit / (side * side));
    }
    if method == 3u {
        return plain(pcss(x, n, d, uv, rel_bias, pixel));
    }
    let um = textureLoad(d_u, texel, 0).xy;
    let pm = textureLoad(d_p, texel, 0).xy;
    if hidden {
        // Corrected eq. (3), hidden branch; no exit along the ray (U = 0) or D <= U: umbra.
        let uu = um.x;
        let s = um.y;
        if uu > 0.0 && d > uu {
            out.t = clamp(s * (d - uu) / (2.0 * uu * (d - s)), 0.0, 0.5);
            out.branch = PENUMBRA_HIDDEN;
        } else {
            out.t = 0.0;
            out.branch = UMBRA;
        }
    } else {
        let p = pm.x;
        let s = pm.y;
        if p > 0.0 && d > p {
            out.t = clamp(1.0 - s * (d - p) / (2.0 * p * (d - s)), 0.5, 1.0);
            out.branch = PENUMBRA_VISIBLE;
        } else {
            out.t = 1.0;
            out.branch = LIT;
        }
    }
    out.v = v_of_t(out.t, u.mode.y);
    return out;
}

struct Targets {
    // Linear RGB (the sRGB target encodes it); a = 1.
    @location(0) color: vec4<f32>,
    // V, and t + 2 × branch code: t is in [0, 1], so both are exact in one f32.
    @location(1) data: vec4<f32>,
    // World position, 1.
    @location(2) position: vec4<f32>,
};

@fragment
fn fs_main(f: SurfaceOut) -> Targets {
    // Two-sided surfaces: the normal of the side the camera sees (as view::receivers on the CPU).
    var n = normalize(f.normal);
    if dot(n, u.eye.xyz - f.world) < 0.0 {
        n = -n;
    }
    let vis = visibility(f.world, n, f.clip.xy);
    let l = normalize(u.light_center.xyz - f.world);
    let ambient = f32(u.mode.z) / 1000.0;
    let cos_receiver = max(dot(n, l), 0.0);
    let cos_emitter = max(dot(-l, u.light_normal.xyz), 0.0);
    let direct = u.light_normal.w * vis.v * cos_receiver * cos_emitter;
    let shade = f.albedo * (ambient + (1.0 - ambient) * min(direct, 1.0));
    var out: Targets;
    out.color = vec4<f32>(vec3<f32>(shade), 1.0);
    out.data = vec4<f32>(vis.v, vis.t + 2.0 * vis.branch, 0.0, 0.0);
    out.position = vec4<f32>(f.world, 1.0);
    return out;
}
