// `msm-soft`: moment soft shadow mapping (Peters, Münstermann, Wetzstein & Klein, I3D 2016;
// src/render/methods/msm_soft.rs), sized by the disk as `pcss` is: the blocker search is one
// box of the summed-area table over the cone from the point to the disk down to the nearest
// caster, whose moments give the share in front of the receiver and its mean depth (Hamburger
// 4MSM's three-point distribution); the penumbra that mean depth predicts sizes the filter,
// a second box, whose moments give V. No per-tap loop: six table reads of four corners. Depths
// are heights above the light's plane (moment_depth), as the table holds them.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/msm.wgsl

// MsmSoftParams of src/render/methods/msm_soft.rs.
struct MsmSoftParams {
    // The lowest caster's height above the light's plane.
    lowest_caster: f32,
    // The moment bias.
    bias: f32,
    // The least blocker share of the search box.
    least_blocker: f32,
    _pad0: u32,
};

@group(1) @binding(2) var<uniform> params: MsmSoftParams;

// Under a rectangle or polygon light, how much to shrink the box of the light's image so that
// it has the light's own area (the box of a light turned against the map's axes is larger than
// the light): a summed-area table filters boxes, and under a rectangle light a box is the exact
// kernel, where pcss takes the disk of the same area. 1 for a disk.
fn box_shrink() -> f32 {
    if !polygon_light() {
        return 1.0;
    }
    // The map's axes in the light's plane (texel s grows with NDC x, t against NDC y).
    let o = shadow.inv_light_view_proj * vec4<f32>(0.0, 0.0, 0.5, 1.0);
    let sx = shadow.inv_light_view_proj * vec4<f32>(1.0, 0.0, 0.5, 1.0);
    let ty = shadow.inv_light_view_proj * vec4<f32>(0.0, -1.0, 0.5, 1.0);
    let s_dir = sx.xyz / sx.w - o.xyz / o.w;
    let t_dir = ty.xyz / ty.w - o.xyz / o.w;
    let s_axis = normalize(vec2<f32>(dot(s_dir, camera.light_u), dot(s_dir, camera.light_w)));
    let t_axis = normalize(vec2<f32>(dot(t_dir, camera.light_u), dot(t_dir, camera.light_w)));
    var e = vec2<f32>(0.0);
    for (var i = 0u; i < camera.light_corner_count; i++) {
        let q = light_corner(i);
        e = max(e, abs(vec2<f32>(dot(q, s_axis), dot(q, t_axis))));
    }
    return min(sqrt(camera.light_area / max(4.0 * e.x * e.y, 1e-30)), 1.0);
}

fn msm_soft(x: vec3<f32>, l: LightLookup) -> f32 {
    // Heights above the light's plane: the table's depths, and the similar triangles' own.
    let d = moment_depth(x, l);
    let near = max(params.lowest_caster, 1e-4);
    if d <= near {
        return 1.0;
    }
    // Filters wider than the table's room are summed in pieces (shared/msm.wgsl box_sum); the
    // map's width bounds them.
    let max_r = vec2<f32>(shadow.size);
    let search = clamp(light_footprint(x, near), vec2<f32>(1.0), max_r);
    let z_search = msm_depth(d * (1.0 - box_bias(l, max(search.x, search.y))));
    let found = hamburger(box_moments(l.texel, vec2<i32>(ceil(search))), z_search, params.bias);
    if found.x < params.least_blocker {
        return 1.0;
    }
    let blocker = max(msm_distance(found.y), near);
    let width = clamp(light_footprint(x, blocker) * box_shrink(), vec2<f32>(0.0), max_r);
    return msm_lit(l, d, width, params.bias, !polygon_light());
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(msm_soft(x, l));
}
