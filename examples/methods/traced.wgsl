// Shadow rays as a user's method: V is the share of a stratified grid of points over the light
// that the scene leaves in view of the shaded point, traced in the camera pass with
// `scene_occluded` (a file that calls it gets the scene's BVH bound) to the points
// `light_sample` spreads uniformly over the light (docs/guide/user-methods.md):
//   dbuffer compare fig7-concave --methods pcss,file:examples/methods/traced.wgsl --knob grid=8
// No jitter and no denoiser: a grid of g × g points has g² levels, banded where the built-in
// `raytraced` is noisy.
// knob: grid 1..12 = 4
// #include shared/camera.wgsl

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let g = u32(round(knob_grid()));
    var seen = 0.0;
    for (var i = 0u; i < g; i++) {
        for (var j = 0u; j < g; j++) {
            let s = light_sample((vec2<f32>(f32(i), f32(j)) + 0.5) / f32(g));
            // A point of the light behind x's own plane sends it nothing.
            if dot(s - x, n) > 0.0 {
                count_work(1.0);
                seen += select(1.0, 0.0, scene_occluded(x, s));
            }
        }
    }
    return plain(seen / f32(g * g));
}
