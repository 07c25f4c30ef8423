// `hard`: the shadow map from the light centre (Williams 1978), the |cx_o| test alone with
// slope-scaled bias (src/render/methods/hard.rs).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    count_work(1.0);
    return plain(select(1.0, 0.0, hidden_from_center(l)));
}
