// `pcf`: percentage-closer filtering (Reeves et al. 1987) of the centre's shadow map: the hard
// test over a (2R + 1)² block of texels, each against the receiver's plane
// (src/render/methods/pcf.rs).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// PcfParams of src/render/methods/pcf.rs.
struct PcfParams {
    // The kernel radius R in texels.
    radius: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(1) @binding(2) var<uniform> params: PcfParams;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    let radius = i32(params.radius);
    var lit = 0.0;
    for (var dy = -radius; dy <= radius; dy++) {
        for (var dx = -radius; dx <= radius; dx++) {
            let tap = l.texel + vec2<i32>(dx, dy);
            count_work(1.0);
            lit += lit_at(tap, receiver_distance(tap, x, n, l.d), l.rel_bias);
        }
    }
    let side = f32(2 * radius + 1);
    return plain(lit / (side * side));
}
