// `linear-ssm`: soft shadow maps for linear lights (Heidrich, Brabec & Seidel 2000;
// src/render/methods/linear_ssm.rs). N samples on the segment, ends included, each a point light
// with a distance map and a visibility channel per neighbouring pair (R: with the previous
// sample, G: with the next); a point seen by sample k adds both of k's channels:
//     V(x) = sum over k of [x seen from k] (W_k.r + W_k.g)
// Channels hold half the pair's share where no skin was drawn, so a point seen by every sample
// gets exactly 1, and one seen by none is in umbra.
// #include shared/camera.wgsl
// #include shared/sample_lights.wgsl

@group(1) @binding(0) var<uniform> ssm: SampleLights;
@group(1) @binding(1) var ssm_maps: texture_2d_array<f32>;
@group(1) @binding(2) var ssm_visibility: texture_2d_array<f32>;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    let count = ssm.count;
    let size = ssm.size;
    let weight = 1.0 / f32(max(count, 2u) - 1u);
    var v = 0.0;
    for (var k = 0u; k < count; k++) {
        let light = ssm.lights[k];
        let to_q = light.point - x;
        let dq = length(to_q);
        if !(dot(n, to_q) > 0.0) {
            continue;
        }
        // Outside the sample's frustum nothing casts a shadow: the channels' initial shares.
        let untouched = select(0.0, 0.5 * weight, k > 0u) + select(0.0, 0.5 * weight, k + 1u < count);
        let clip = light.view_proj * vec4<f32>(x, 1.0);
        let ndc = clip.xyz / clip.w;
        if clip.w <= 0.0 || any(abs(ndc.xy) > vec2<f32>(1.0)) {
            v += untouched;
            continue;
        }
        let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
        let texel = vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), vec2<f32>(size - 1.0)));
        let o = textureLoad(ssm_maps, texel, i32(k), 0).x;
        count_work(1.0);
        let cos_i = clamp(dot(n, to_q) / dq, 0.05, 1.0);
        let tan_i = sqrt(1.0 - cos_i * cos_i) / cos_i;
        let bias = dq * (ssm.bias_constant + ssm.bias_slope * ssm.texel_slope * tan_i);
        if dq <= o + bias {
            let w = textureLoad(ssm_visibility, texel, i32(k), 0).xy;
            v += w.x + w.y;
        }
    }
    return plain(clamp(v, 0.0, 1.0));
}
