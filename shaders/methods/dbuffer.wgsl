// `dbuffer` and `dbuffer-center`: the D-buffer lookup (seed 000 §4, with design.md's corrections;
// src/render/methods/dbuffer.rs). Per pixel: |cx|, the hidden-from-centre test against |cx_o|,
// the parameter t by the corrected eq. (3) from the umbra or the penumbra channel, then V(t).
// Its CPU twin is DBufferTwin::sample (src/geometry/twin.rs) with geometry::visibility.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// (|cx_uv|, |cx_s|) and (|cx_pv|, |cx_s|): 0 where no umbra exit / penumbra entry.
@group(1) @binding(2) var d_u: texture_2d<f32>;
@group(1) @binding(3) var d_p: texture_2d<f32>;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    // Outside the fitted frustum no penumbra can reach: lit.
    if !l.inside {
        return plain(1.0);
    }
    let d = l.d;
    var out: Visibility;
    if hidden_from_center(l) {
        // Corrected eq. (3), hidden branch; no exit along the ray (U = 0) or D <= U: umbra.
        let um = textureLoad(d_u, l.texel, 0).xy;
        let u = um.x;
        let s = um.y;
        if u > 0.0 && d > u {
            out.t = clamp(s * (d - u) / (2.0 * u * (d - s)), 0.0, 0.5);
            out.branch = BRANCH_PENUMBRA_HIDDEN;
        } else {
            out.t = 0.0;
            out.branch = BRANCH_UMBRA;
        }
    } else {
        let pm = textureLoad(d_p, l.texel, 0).xy;
        let p = pm.x;
        let s = pm.y;
        if p > 0.0 && d > p {
            out.t = clamp(1.0 - s * (d - p) / (2.0 * p * (d - s)), 0.5, 1.0);
            out.branch = BRANCH_PENUMBRA_VISIBLE;
        } else {
            out.t = 1.0;
            out.branch = BRANCH_LIT;
        }
    }
    out.v = v_of_t(out.t);
    return out;
}
