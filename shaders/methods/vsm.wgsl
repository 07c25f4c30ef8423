// `vsm`: variance shadow maps (Donnelly & Lauritzen 2006; src/render/methods/vsm.rs). The
// centre's shadow map's moments (|cx_o|, |cx_o|²), box-filtered over (2R + 1)² texels
// (shaders/passes/moments.wgsl); per pixel the one-sided Chebyshev bound on the share of the
// filter region at least as far as the receiver, the light-bleeding reduction cutting off the
// bound's low tail. A hard shadow from the centre, filtered: its softness is the filter's, not
// the light's.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// VsmParams of src/render/methods/vsm.rs.
struct VsmParams {
    // The light-bleeding reduction (0..1).
    bleed: f32,
    // The least variance, relative to |cx|².
    min_variance: f32,
    _pad0: u32,
    _pad1: u32,
};

@group(1) @binding(2) var<uniform> params: VsmParams;
@group(1) @binding(3) var moments: texture_2d<f32>;

// The Chebyshev upper bound P(o >= d) for mean mu and variance var, with the bleeding cut.
fn chebyshev(m: vec2<f32>, d: f32) -> f32 {
    if d <= m.x {
        return 1.0;
    }
    let variance = max(m.y - m.x * m.x, params.min_variance * d * d);
    let gap = d - m.x;
    let p = variance / (variance + gap * gap);
    let cut = clamp(params.bleed, 0.0, 0.999);
    return clamp((p - cut) / (1.0 - cut), 0.0, 1.0);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    let m = textureLoad(moments, l.texel, 0).xy;
    count_work(1.0);
    // The receiver's distance less the shadow test's slope-scaled bias.
    return plain(chebyshev(m, l.d * (1.0 - l.rel_bias)));
}
