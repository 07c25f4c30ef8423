// V per pixel made over the camera's pixels before the camera pass (the stencil methods'
// resolve: render::passes::stencil_volumes): a method's shader includes this after
// shared/camera.wgsl and binds the visibility texture as group 1, binding 0.

@group(1) @binding(0) var screen_v: texture_2d<f32>;

// V at the pixel whose centre is `pixel` (the camera pass's fragment position).
fn screen_visibility(pixel: vec2<f32>) -> f32 {
    let size = vec2<i32>(textureDimensions(screen_v));
    let p = clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), size - 1);
    return textureLoad(screen_v, p, 0).x;
}

// V of a hard method whose count was made over the screen: the camera pass's rules first (a
// point behind the one-sided light, or on a side turned away from the light's centre, gets
// nothing), then the texture.
fn screen_hard_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    count_work(1.0);
    return plain(screen_visibility(pixel));
}
