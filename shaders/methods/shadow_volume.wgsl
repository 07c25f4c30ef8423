// `shadow-volume`: stencil shadow volumes from the light centre (Crow 1977; counted by z-fail
// with both caps, so the camera may stand inside a volume), counted over the camera's pixels by
// render::passes::stencil_volumes before this pass (src/render/methods/shadow_volume.rs).
// #include shared/camera.wgsl
// #include shared/screen_v.wgsl

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    return screen_hard_visibility(x, n, pixel);
}
