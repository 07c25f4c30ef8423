// `msm-soft`: moment soft shadow mapping (Peters, Münstermann, Wetzstein & Klein, I3D 2016;
// src/render/methods/msm_soft.rs), sized by the disk as `pcss` is: the blocker search is one
// box of the summed-area table over the cone from the point to the disk down to the nearest
// caster, whose moments give the share in front of the receiver and its mean depth (Hamburger
// 4MSM's three-point distribution); the penumbra that mean depth predicts sizes the filter,
// a second box, whose moments give V. No per-tap loop: six table reads of four corners.
// knobs: x the nearest caster's distance from c, y the moment bias, z the least blocker share.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/msm.wgsl

fn msm_soft(l: LightLookup) -> f32 {
    let r = camera.light_radius;
    let d = l.d;
    let near = max(shadow.knobs.x, 1e-4);
    if d <= near {
        return 1.0;
    }
    let max_r = f32(MSM_MAX_RADIUS - 1);
    let search = clamp(light_width_in_texels(r, d, near), 1.0, max_r);
    let z_search = msm_depth(d * (1.0 - box_bias(l, search)));
    let found = hamburger(box_moments(l.texel, i32(ceil(search))), z_search, shadow.knobs.y);
    if found.x < shadow.knobs.z {
        return 1.0;
    }
    let blocker = max(msm_distance(found.y), near);
    let width = clamp(light_width_in_texels(r, d, blocker), 0.0, max_r);
    return msm_lit(l, width, shadow.knobs.y, true);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(msm_soft(l));
}
