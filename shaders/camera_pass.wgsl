// The camera pass: per pixel |cx|, the hidden-from-centre test against |cx_o|, the parameter t by
// the corrected eq. (3), V(t), and diffuse shading from the disk times V. Its CPU twin is
// DBufferTwin::sample (src/geometry/twin.rs) with geometry::visibility.
// #include shared/surface.wgsl

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
    // x: method (0 dbuffer, 1 hard); y: V(t) variant (0 smoothstep, 1 sqrt, 2 exact, 3 linear);
    // z: ambient term × 1000; w: unused.
    mode: vec4<u32>,
};

@group(0) @binding(0) var<uniform> u: CameraUniforms;
@group(0) @binding(1) var d_o: texture_2d<f32>;
@group(0) @binding(2) var d_u: texture_2d<f32>;
@group(0) @binding(3) var d_p: texture_2d<f32>;

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

fn visibility(x: vec3<f32>, n: vec3<f32>) -> Visibility {
    var out: Visibility;
    let c = u.light_center.xyz;
    let to_x = x - c;
    let d = length(to_x);
    // Behind the one-sided light, or on a side turned away from the light centre (self-shadowed:
    // the point lies on its own caster's umbra exit, where D ≈ |cx_uv| is decided by rounding):
    // nothing arrives. The oracle agrees: rays from such a point run into the object.
    if !(dot(to_x, u.light_normal.xyz) > 0.0) || !(dot(n, -to_x) > 0.0) {
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
    let size = u.bias.z;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let texel = vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), vec2<f32>(size - 1.0)));
    let o = textureLoad(d_o, texel, 0).x;
    let um = textureLoad(d_u, texel, 0).xy;
    let pm = textureLoad(d_p, texel, 0).xy;

    // Slope-scaled bias: a texel spans a slope of bias.w in the light view; on a surface tilted
    // away from the light its footprint grows with tan(incidence).
    let l = -to_x / d;
    let cos_i = clamp(abs(dot(n, l)), 0.05, 1.0);
    let tan_i = sqrt(1.0 - cos_i * cos_i) / cos_i;
    let bias = d * (u.bias.x + u.bias.y * u.bias.w * tan_i);
    let hidden = d > o + bias;

    if u.mode.x == 1u {
        // Hard shadow map: the |cx_o| test alone.
        out.v = select(1.0, 0.0, hidden);
        out.t = out.v;
        out.branch = select(LIT, UMBRA, hidden);
        return out;
    }
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
    let vis = visibility(f.world, n);
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
