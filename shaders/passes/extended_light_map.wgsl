// The extended light map (render::passes::extended_light_map; Brabec, Heidrich and Seidel 2000):
// one pass from the light's centre writes, per texel, the light that reaches the nearest surface
// in RGB — a spotlight's falloff, a projected texture (a gobo), the cosines — and its distance
// from the light in A, quantised to the map's depth bits (8 in the 2000 hardware's alpha
// channel). The camera pass then takes light and shadow from one lookup
// (shaders/methods/extended_light_map.wgsl). CPU twin of the RGB:
// render::methods::extended_light_map::light_rgb.
// #include shared/surface.wgsl

struct ElmUniforms {
    // The light view: world to clip.
    view_proj: mat4x4<f32>,
    // xyz: the light point; w: 1 / far (distances to [0, 1]).
    light: vec4<f32>,
    // xyz: the spot's axis; w: the light's intensity.
    axis: vec4<f32>,
    // x: cos of the spot's outer angle; y: of its inner one; z: depth levels (2^bits - 1);
    // w: unused (the pattern is the pipeline constant PATTERN).
    spot: vec4<f32>,
    // xyz: the emitter's normal (one-sided disk: its cosine); w: 1 to apply it; .. size below.
    emitter: vec4<f32>,
    // x: the map's side in texels.
    size: vec4<f32>,
};

// The pattern (0 spotlight, 1 projected texture, 2 uniform), fixed per pipeline: a CPU
// rasteriser would run every pattern's arithmetic on every texel if it were a uniform.
override PATTERN: u32 = 0u;

@group(0) @binding(0) var<uniform> elm: ElmUniforms;
@group(0) @binding(1) var pattern: texture_2d<f32>;
@group(0) @binding(2) var pattern_sampler: sampler;

struct ElmOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_main(v: SurfaceIn) -> ElmOut {
    var out: ElmOut;
    out.clip = elm.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    return out;
}

// The light's colour at world point y with unit normal n (either side), seen from the light at
// image point uv of the map.
fn light_rgb(y: vec3<f32>, n: vec3<f32>, uv: vec2<f32>) -> vec3<f32> {
    let dir = normalize(y - elm.light.xyz);
    let cos_axis = dot(dir, elm.axis.xyz);
    var spot = smoothstep(elm.spot.x, elm.spot.y, cos_axis);
    var gobo = vec3<f32>(1.0);
    if PATTERN == 2u {
        spot = 1.0;
    }
    if PATTERN == 1u {
        gobo = textureSampleLevel(pattern, pattern_sampler, uv, 0.0).rgb;
    }
    let cos_receiver = abs(dot(n, dir));
    let cos_emitter = select(1.0, max(dot(dir, elm.emitter.xyz), 0.0), elm.emitter.w > 0.5);
    return elm.axis.w * spot * gobo * cos_receiver * cos_emitter;
}

// A distance in [0, 1] on the map's depth levels.
fn quantise(d: f32) -> f32 {
    let levels = elm.spot.z;
    return floor(clamp(d, 0.0, 1.0) * levels + 0.5) / levels;
}

@fragment
fn fs_main(f: ElmOut) -> @location(0) vec4<f32> {
    let m = cross(dpdx(f.world), dpdy(f.world));
    let n = select(vec3<f32>(0.0, 1.0, 0.0), normalize(m), dot(m, m) > 1e-30);
    let uv = f.clip.xy / elm.size.x;
    let rgb = light_rgb(f.world, n, uv);
    return vec4<f32>(rgb, quantise(distance(f.world, elm.light.xyz) * elm.light.w));
}
