// `extended-light-map`: light and shadow from one lookup in the extended light map (Brabec,
// Heidrich and Seidel 2000; src/render/methods/extended_light_map.rs): the map's A is the
// nearest surface's distance from the light (quantised), its RGB the light that surface gets.
// The point is lit when it is no farther than A plus the bias; the light it gets is the texel's
// RGB (so the image shows the map's resolution and its colours).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// ExtendedLightMapParams of src/render/methods/extended_light_map.rs.
struct ExtendedLightMapParams {
    // 1 / the light view's far distance: A's scale.
    inv_far: f32,
    // A's depth levels, 2^bits - 1.
    levels: u32,
    _pad0: u32,
    _pad1: u32,
};

@group(1) @binding(2) var<uniform> params: ExtendedLightMapParams;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        // Outside the map the light does not reach.
        var outside = plain(1.0);
        outside.light = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return outside;
    }
    let texel = textureLoad(d_o, l.texel, 0);
    count_work(1.0);
    let d = l.d * params.inv_far;
    // A depth level (the rounding is half of one), and the slope bias of the hard test.
    let bias = 1.0 / f32(params.levels) + d * l.rel_bias;
    var out = plain(select(0.0, 1.0, d <= texel.a + bias));
    out.light = vec4<f32>(texel.rgb, 1.0);
    return out;
}
