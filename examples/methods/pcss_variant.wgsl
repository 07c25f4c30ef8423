// A PCSS variant (after Fernando 2005) as a user's method, on the centre's shadow map the
// D-buffer's state binds (`d_o` and `shadow`, read through shared/shadow_lookup.wgsl):
//   dbuffer render fig7-concave --method file:examples/methods/pcss_variant.wgsl --knob softness=1.5
// Where the built-in `pcss` searches blockers in a rotated Poisson disk down to the scene's
// nearest caster, this one searches a regular grid (taps × taps) through a plane at a share of
// the receiver's distance from the light (`search_depth`), and scales the penumbra the blockers'
// mean distance predicts by `softness`.
// knob: taps 2..8 = 4
// knob: search_depth 0.05..0.95 = 0.5
// knob: softness 0.25..4 = 1
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// The grid's side, a whole number of taps.
fn grid_side() -> u32 {
    return u32(round(knob_taps()));
}

// Tap (i, j) of the grid over [-1, 1]², at the cells' centres.
fn grid_point(i: u32, j: u32, side: u32) -> vec2<f32> {
    return (vec2<f32>(f32(i), f32(j)) + 0.5) / f32(side) * 2.0 - 1.0;
}

fn pcss_variant(x: vec3<f32>, n: vec3<f32>, l: LightLookup) -> f32 {
    let r = camera.light_radius;
    let d = l.d;
    let size = shadow.size;
    let centre = l.uv * size;
    let side = grid_side();
    // Blockers: the light's image through the plane at search_depth of the way from c to x.
    let search = clamp(light_width_in_texels(r, d, d * knob_search_depth()), 1.0, size * 0.5);
    var blockers = 0.0;
    var sum = 0.0;
    for (var i = 0u; i < side; i++) {
        for (var j = 0u; j < side; j++) {
            let tap = vec2<i32>(floor(centre + grid_point(i, j, side) * search));
            let q = clamp(tap, vec2<i32>(0), vec2<i32>(i32(size) - 1));
            count_work(1.0);
            let o = textureLoad(d_o, q, 0).x;
            let expected = receiver_distance(q, x, n, d);
            if o + expected * l.rel_bias < expected {
                blockers += 1.0;
                sum += o;
            }
        }
    }
    if blockers == 0.0 {
        took_path(1.0);
        return 1.0;
    }
    took_path(2.0);
    // The penumbra the blockers' mean distance predicts, scaled by softness.
    let width = clamp(knob_softness() * light_width_in_texels(r, d, sum / blockers), 1.0, size * 0.5);
    var lit = 0.0;
    for (var i = 0u; i < side; i++) {
        for (var j = 0u; j < side; j++) {
            let tap = vec2<i32>(floor(centre + grid_point(i, j, side) * width));
            count_work(1.0);
            lit += lit_at(tap, receiver_distance(tap, x, n, d), l.rel_bias);
        }
    }
    return lit / f32(side * side);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(pcss_variant(x, n, l));
}
