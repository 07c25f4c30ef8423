// `sampled`: N point lights on the disk, each with its own shadow map, averaged (light-source sampling, Heckbert & Herf 1997;
// src/render/methods/sampled.rs, maps from shaders/passes/sample_maps.wgsl).
// #include shared/camera.wgsl
// #include shared/sample_lights.wgsl

@group(1) @binding(0) var<uniform> sampled: SampleLights;
@group(1) @binding(1) var sample_maps: texture_2d_array<f32>;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) {
        return plain(0.0);
    }
    let count = sampled.count;
    let size = sampled.size;
    var lit = 0.0;
    for (var i = 0u; i < count; i++) {
        let light = sampled.lights[i];
        let to_q = light.point - x;
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
        let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        let texel = vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), vec2<f32>(size - 1.0)));
        let o = textureLoad(sample_maps, texel, i32(i), 0).x;
        count_work(1.0);
        let cos_i = clamp(dot(n, to_q) / dq, 0.05, 1.0);
        let tan_i = sqrt(1.0 - cos_i * cos_i) / cos_i;
        let bias = dq * (sampled.bias_constant + sampled.bias_slope * sampled.texel_slope * tan_i);
        lit += select(0.0, 1.0, dq <= o + bias);
    }
    return plain(lit / f32(max(count, 1u)));
}
