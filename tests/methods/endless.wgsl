// A user's method whose loop never takes its exit (tests/cli/user_methods.rs,
// tests/gpu/user_methods.rs): on lavapipe the driver ends it after about 65,535 steps, so a
// frame takes seconds; on a GPU the driver loses the device.
// #include shared/camera.wgsl

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    var acc = bitcast<u32>(x.y);
    loop {
        acc = acc * 1664525u + 1013904223u;
        if pixel.x < -1.0 {
            break;
        }
    }
    return plain(f32(acc & 255u) / 255.0);
}
