// `planar`: planar projected shadows (Blinn 1988), drawn over the camera's pixels by
// render::passes::planar before this pass (src/render/methods/planar.rs). Only the pixels of
// planar receivers can be in shadow: nothing else is darkened, which is the method's limit.
// #include shared/camera.wgsl
// #include shared/screen_v.wgsl

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    return screen_hard_visibility(x, n, pixel);
}
