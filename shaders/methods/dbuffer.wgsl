// `dbuffer` and `dbuffer-center`: the D-buffer lookup (Jakobsen et al. 2004, §4, with the corrections in docs/method/dbuffer.md;
// src/render/methods/dbuffer.rs). Per pixel: |cx|, the hidden-from-centre test against |cx_o|,
// the parameter t by the corrected eq. (3) from the umbra or the penumbra channel, then V(t).
// Its CPU twin is DBufferTwin::sample (src/geometry/twin.rs) with geometry::visibility.
// Written without branches: a CPU rasteriser runs both sides of every branch anyway, so one
// formula serves both of eq. (3)'s (they differ only in which channel and in t ↔ 1 − t).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// (|cx_uv|, |cx_s|, lit side) and (|cx_pv|, |cx_s|, lit side): 0 where no umbra exit / penumbra
// entry. The lit side is the chord's direction V exact needs under a polygon light.
@group(1) @binding(2) var d_u: texture_2d<f32>;
@group(1) @binding(3) var d_p: texture_2d<f32>;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    let l = light_lookup(x, n);
    let d = l.d;
    let hidden = hidden_from_center(l);
    // Hidden from c: the umbra's exit U; visible: the penumbra's entry P. With X and S its
    // distance and |cx_s|, f = S (D − X) / (2 X (D − S)) is t (hidden) or 1 − t (visible), for
    // D > X; no crossing before the point (X = 0 or D <= X) is umbra (hidden) or lit (visible).
    let xs = select(textureLoad(d_p, l.texel, 0), textureLoad(d_u, l.texel, 0), hidden);
    let crossed = xs.x > 0.0 && d > xs.x;
    let f = clamp(xs.y * (d - xs.x) / (2.0 * xs.x * (d - xs.y)), 0.0, 0.5);
    var out: Visibility;
    out.t = select(select(1.0, 1.0 - f, crossed), select(0.0, f, crossed), hidden);
    out.branch = select(
        select(BRANCH_LIT, BRANCH_PENUMBRA_VISIBLE, crossed),
        select(BRANCH_UMBRA, BRANCH_PENUMBRA_HIDDEN, crossed),
        hidden
    );
    out.v = v_of_t_toward(out.t, xs.zw);
    // Outside the fitted frustum no penumbra can reach: lit. Behind the one-sided light, or on
    // a side turned away from the centre: nothing arrives.
    let dark = !in_front_of_light(x) || !faces_light_center(x, n);
    if !l.inside {
        out = plain(1.0);
    }
    if dark {
        out = plain(0.0);
    }
    return out;
}
