// `hybrid`: shadow volumes reconstructed from the light's depth map (McCool 2000), counted in one
// stencil bit over the camera's pixels by render::passes::hybrid before this pass
// (src/render/methods/hybrid.rs).
// #include shared/camera.wgsl
// #include shared/screen_v.wgsl

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    return screen_hard_visibility(x, n, pixel);
}
