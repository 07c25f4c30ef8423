// `msm`: moment shadow maps (Peters & Klein, I3D 2015; src/render/methods/msm.rs), filtered: the
// centre's shadow map's four moments over a (2R + 1)² box from the summed-area table, and
// Hamburger 4MSM at the receiver's depth. A hard shadow from the centre, filtered: its softness
// is the filter's, not the light's.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/msm.wgsl

// MsmParams of src/render/methods/msm.rs.
struct MsmParams {
    // The box's half-width R in texels.
    radius: u32,
    // The moment bias.
    bias: f32,
    _pad0: u32,
    _pad1: u32,
};

@group(1) @binding(2) var<uniform> params: MsmParams;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(msm_lit(l, moment_depth(x, l), vec2<f32>(f32(params.radius)), params.bias, false));
}
