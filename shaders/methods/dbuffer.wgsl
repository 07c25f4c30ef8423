// `dbuffer` and `dbuffer-center`: the D-buffer lookup (Jakobsen et al. 2004, §4, with the corrections in docs/method/dbuffer.md;
// src/render/methods/dbuffer.rs). Per pixel: |cx|, the hidden-from-centre test against |cx_o|,
// the parameter t by the corrected eq. (3) from the umbra or the penumbra channel, then V(t).
// Its CPU twin is DBufferTwin::visibility_on (src/geometry/twin.rs).
// Written without branches: a CPU rasteriser runs both sides of every branch anyway, so one
// formula serves both of eq. (3)'s (they differ only in which channel and in t ↔ 1 − t).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/frame_tag.wgsl

// (|cx_uv|, |cx_s|, lit side) and (|cx_pv|, |cx_s|, lit side): 0 where no umbra exit / penumbra
// entry. The lit side is the chord's direction V exact needs under a polygon light. Both carry
// the frame tag shadow.knobs.z (passes/dbuffer_volumes.wgsl): read through frame_untagged.
@group(1) @binding(2) var d_u: texture_2d<f32>;
@group(1) @binding(3) var d_p: texture_2d<f32>;
// The closing fans' silhouette corners, three texels per fan (apex, the two edges' far ends;
// geometry::FanCorner), CORNERS_PER_ROW fans to a row. A fan's texel holds -(2 + its index) in
// .z (geometry::volume_vertices::corner_marker) instead of a lit side.
@group(1) @binding(4) var corners: texture_2d<f32>;
const CORNERS_PER_ROW: u32 = 512u;

fn corner_point(k: u32, j: u32) -> vec3<f32> {
    count_work(1.0);
    return textureLoad(corners, vec2<u32>(3u * (k % CORNERS_PER_ROW) + j, k / CORNERS_PER_ROW), 0).xyz;
}

// V at x behind one convex silhouette corner: the light less the part behind both planes
// through x and an edge (each on the side of the other edge's far end), the corner's wedge as
// x sees it (a reflex corner: the light less it); -1 where the corner is unclear or degenerate
// from x (twin: DiskFrame::corner_visibility).
fn corner_visibility(x: vec3<f32>, k: u32) -> f32 {
    let size = textureDimensions(corners);
    if 3u * (k % CORNERS_PER_ROW) + 2u >= size.x || k / CORNERS_PER_ROW >= size.y {
        return -1.0;
    }
    // apex.w: 1 convex, -1 reflex, 0 unclear (geometry::FanCorner::convex).
    let apex = textureLoad(corners, vec2<u32>(3u * (k % CORNERS_PER_ROW), k / CORNERS_PER_ROW), 0);
    count_work(1.0);
    let convex = apex.w;
    if convex == 0.0 {
        return -1.0;
    }
    let a = apex.xyz;
    let ends = array<vec3<f32>, 2>(corner_point(k, 1u) - a, corner_point(k, 2u) - a);
    var m: array<vec2<f32>, 3>;
    var h = vec3<f32>(-1.0);
    for (var i = 0u; i < 2u; i++) {
        let edge = ends[i];
        let other = ends[1u - i];
        var n = cross(edge, x - a);
        let side = dot(n, other);
        if !(abs(side) > 1e-6 * length(n) * length(other)) {
            return -1.0;
        }
        n = select(n, -n, side < 0.0);
        // Behind: n . (c + p - a) >= 0, p a corner-plane point about the centre.
        m[i] = vec2<f32>(dot(n, camera.light_u), dot(n, camera.light_w));
        h[i] = dot(n, a - camera.light_center);
    }
    var hidden: f32;
    if polygon_light() {
        hidden = polygon_cut_area(camera.light_corners, camera.light_corner_count, m, h) / max(camera.light_area, 1e-30);
    } else {
        // A disk: the cuts in units of its radius with unit normals (one parallel to the disk
        // keeps all of it or none).
        var mu: array<vec2<f32>, 2>;
        var hu: vec2<f32>;
        for (var i = 0u; i < 2u; i++) {
            let len = length(m[i]) * camera.light_radius;
            let tilted = len > 1e-12 * abs(h[i]);
            mu[i] = select(vec2<f32>(1.0, 0.0), m[i] * camera.light_radius / len, tilted);
            hu[i] = select(select(2.0, -2.0, h[i] <= 0.0), h[i] / len, tilted);
        }
        hidden = disk_cut2_area(mu[0], hu[0], mu[1], hu[1]) / 3.14159265358979;
    }
    // A reflex corner covers the light less the wedge.
    return clamp(select(hidden, 1.0 - hidden, convex > 0.0), 0.0, 1.0);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    let l = light_lookup(x, n);
    let d = l.d;
    let hidden = hidden_from_center(l);
    // Hidden from c: the umbra's exit U; visible: the penumbra's entry P. With X and S its
    // distance and |cx_s|, f = S (D − X) / (2 X (D − S)) is t (hidden) or 1 − t (visible), for
    // D > X; no crossing before the point (X = 0 or D <= X) is umbra (hidden) or lit (visible).
    let xs = frame_untagged(
        select(textureLoad(d_p, l.texel, 0), textureLoad(d_u, l.texel, 0), hidden),
        u32(shadow.knobs.z)
    );
    // The cost view counts texels read: |cx_o| and both channels (a select reads both).
    count_work(3.0);
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
    // V exact where a closing fan won: the corner's wedge, not a chord's strip (which grows
    // with the depth where the wedge grows with its square).
    // (shadow.knobs.y = 1, --dbuffer-corners.)
    if VT_VARIANT == VT_EXACT && crossed && xs.z < -1.5 && shadow.knobs.y > 0.5 {
        let corner = corner_visibility(x, u32(round(-xs.z - 2.0)));
        if corner >= 0.0 {
            out.v = corner;
            took_path(1.0);
        }
    }
    // Outside the fitted frustum no penumbra can reach: lit. Behind the one-sided light, or on
    // a side turned away from the centre: nothing arrives.
    let dark = !in_front_of_light(x) || !faces_light_center(x, n);
    if !l.inside {
        out = plain(1.0);
        took_path(3.0);
    }
    // shadow.knobs.x = 1 (--dbuffer-horizon): at most the part of the light in front of the
    // receiver's own plane. A caster's face whose plane cuts the light sits on its own
    // silhouette, where no volume darkens it; the light behind that plane never reaches it.
    let horizon = horizon_fraction(x, n);
    if shadow.knobs.x > 0.5 && horizon < out.v {
        out = plain(horizon);
        took_path(2.0);
    }
    if dark {
        out = plain(0.0);
        took_path(4.0);
    }
    return out;
}
