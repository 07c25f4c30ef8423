// The paper's D-buffer (Jakobsen et al. 2004, §4, with the corrections in docs/method/dbuffer.md)
// as a user's method: `dbuffer render fig7-concave --method file:examples/methods/dbuffer_vt.wgsl`.
// It is shaders/methods/dbuffer.wgsl with V(t) written out here (written_v_of_t,
// written_v_of_t_toward and the polygon clip it uses) instead of called from shared/camera.wgsl,
// and renders the built-in `dbuffer`'s image bit for bit (tests/gpu/user_methods.rs).
//
// What it reads is declared for it (docs/guide/user-methods.md): `camera` (group 0), the
// centre's shadow map through light_lookup (shared/shadow_lookup.wgsl), `params` (horizon,
// corners, the frame tag), the channels `d_u` and `d_p`, and the closing fans' `corners`.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/frame_tag.wgsl

// V(t): the share of the light beyond the chord a share t of the way across it, by variant
// (VT_VARIANT, set per pipeline from --vt): smoothstep, sqrt, the exact disk segment, linear.
fn written_v_of_t(t_in: f32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    if VT_VARIANT == VT_SQRT {
        return sqrt(t);
    }
    if VT_VARIANT == VT_EXACT {
        // The disk's segment beyond the chord at height 1 - 2t, over the disk.
        let h = clamp(1.0 - 2.0 * t, -1.0, 1.0);
        return (acos(h) - h * sqrt(max(1.0 - h * h, 0.0))) / 3.14159265358979;
    }
    if VT_VARIANT == VT_LINEAR {
        return t;
    }
    return t * t * (3.0 - 2.0 * t);
}

// Corner i of the polygon light, read from the uniforms in place.
fn written_corner(i: u32) -> vec2<f32> {
    let q = camera.light_corners[i / 2u];
    return select(q.xy, q.zw, (i & 1u) == 1u);
}

// The share of the polygon light where dot(m, p) >= h, in one walk round it: the kept edges, the
// parts of the two it crosses, and the chord from where it leaves the half-plane to where it
// comes back.
fn written_share_above(m: vec2<f32>, h: f32) -> f32 {
    let n = min(camera.light_corner_count, 16u);
    var sum = 0.0;
    var leave = vec2<f32>(0.0);
    var enter = vec2<f32>(0.0);
    var a = written_corner(max(n, 1u) - 1u);
    var da = dot(m, a) - h;
    for (var i = 0u; i < n; i++) {
        let b = written_corner(i);
        let db = dot(m, b) - h;
        let p = a + (b - a) * (da / (da - db));
        let a_in = da >= 0.0;
        let b_in = db >= 0.0;
        let start = select(p, a, a_in);
        let end = select(p, b, b_in);
        sum += select(0.0, start.x * end.y - start.y * end.x, a_in || b_in);
        leave = select(leave, p, a_in && !b_in);
        enter = select(enter, p, !a_in && b_in);
        a = b;
        da = db;
    }
    sum += leave.x * enter.y - leave.y * enter.x;
    return clamp(0.5 * sum / max(camera.light_area, 1e-30), 0.0, 1.0);
}

// V(t) with the chord's lit side m for V exact under a polygon light: the share of the light
// beyond the chord a share t of the way across it toward m. A disk's, no direction, or a fan's
// corner marker (m.x <= -2) is written_v_of_t's.
fn written_v_of_t_toward(t_in: f32, m_in: vec2<f32>) -> f32 {
    if VT_VARIANT != VT_EXACT || !polygon_light() || !(dot(m_in, m_in) > 1e-12) || m_in.x < -1.5 {
        return written_v_of_t(t_in);
    }
    let t = clamp(t_in, 0.0, 1.0);
    let m = normalize(m_in);
    var lo = 3.0e38;
    var hi = -3.0e38;
    for (var i = 0u; i < camera.light_corner_count; i++) {
        let x = dot(m, polygon_corner(camera.light_corners, i));
        lo = min(lo, x);
        hi = max(hi, x);
    }
    return written_share_above(m, hi - t * (hi - lo));
}

// Declared for this file by the loader (as in the lines commented out below), with `params`
// (DBufferParams: horizon, corners, tag) at @group(1) @binding(2):
// (|cx_uv|, |cx_s|, lit side) and (|cx_pv|, |cx_s|, lit side): 0 where no umbra exit / penumbra
// entry. The lit side is the chord's direction V exact needs under a polygon light. Both carry
// the frame tag params.tag (passes/dbuffer_volumes.wgsl): read through frame_untagged.
// @group(1) @binding(3) var d_u: texture_2d<f32>;
// @group(1) @binding(4) var d_p: texture_2d<f32>;
// The closing fans' silhouette corners, TEXELS_PER_CORNER texels per fan (apex, the two edges'
// far ends, each edge's two faces' normals, the two extrusion points; geometry::FanCorner),
// CORNERS_PER_ROW fans to a row.
// A fan's texel holds -(2 + its index) in .z (geometry::volume_vertices::corner_marker) instead of
// a lit side, where V exact may be taken from its corner.
// @group(1) @binding(5) var corners: texture_2d<f32>;
const TEXELS_PER_CORNER: u32 = 9u;
const CORNERS_PER_ROW: u32 = 224u;
// geometry::wedges::SILHOUETTE_MARGIN, REACH_MARGIN and SEAM_MARGIN.
const SILHOUETTE_MARGIN: f32 = 0.1;
const REACH_MARGIN: f32 = 0.25;
const SEAM_MARGIN: f32 = 0.15;

fn corner_point(k: u32, j: u32) -> vec3<f32> {
    count_work(1.0);
    return textureLoad(corners, vec2<u32>(TEXELS_PER_CORNER * (k % CORNERS_PER_ROW) + j, k / CORNERS_PER_ROW), 0).xyz;
}

// How far outside the light `end` lies seen from x (projected from x onto the light's plane), in
// light radii (light_bound: a polygon's enclosing disk); an end no nearer the light's plane than
// x is far outside (its edge runs away from the light).
fn corner_reach(x: vec3<f32>, end: vec3<f32>) -> f32 {
    let hx = dot(camera.light_normal, x - camera.light_center);
    let he = dot(camera.light_normal, end - camera.light_center);
    if !(he < hx) {
        return 1e30;
    }
    let g = x + (end - x) * (hx / (hx - he)) - camera.light_center;
    let q = vec2<f32>(dot(g, camera.light_u), dot(g, camera.light_w));
    var out = length(q) - camera.light_bound;
    if polygon_light() {
        out = -1e30;
        for (var i = 0u; i < camera.light_corner_count; i++) {
            let a = polygon_corner(camera.light_corners, i);
            let d = polygon_corner(camera.light_corners, (i + 1u) % camera.light_corner_count) - a;
            out = max(out, dot(vec2<f32>(d.y, -d.x), q - a) / max(length(d), 1e-30));
        }
    }
    return out / max(camera.light_bound, 1e-30);
}

// Where x lies across the fan at `apex` between the extrusion points s0 and s1: the distance to
// the nearer of the planes through the light's centre, the apex and each (the fan's texels lie
// between them) over the sum of both; 0 on a side, 1/2 on the middle (twin: DiskFrame::fan_share).
fn fan_share(x: vec3<f32>, apex: vec3<f32>, s0: vec3<f32>, s1: vec3<f32>) -> f32 {
    let c = camera.light_center;
    let p = array<vec3<f32>, 2>(s0 - c, s1 - c);
    var d = vec2<f32>(0.0);
    for (var k = 0u; k < 2u; k++) {
        let n = cross(apex - c, p[k]);
        let away = select(n, -n, dot(n, p[1u - k]) > 0.0);
        d[k] = max(dot(away, x - c), 0.0) / max(length(away), 1e-30);
    }
    let sum = d.x + d.y;
    return select(0.0, min(d.x, d.y) / sum, sum > 0.0);
}

// V at x behind one convex silhouette corner, and how far it may be trusted there: (v, weight),
// V exact being the chord's moved `weight` of the way to v; weight 0 where the corner does not
// apply (twin: DiskFrame::corner_visibility, with why). v is the light less the part behind both
// planes through x and an edge (each on the side of the other edge's far end). It applies where
// both edges are silhouettes seen from x, the corner is convex seen from x and both edges reach
// past the light seen from x; the weight fades in over SILHOUETTE_MARGIN and REACH_MARGIN, and
// out toward the fan's sides (SEAM_MARGIN), where its texels meet the quads' chord.
fn corner_visibility(x: vec3<f32>, k: u32) -> vec2<f32> {
    let size = textureDimensions(corners);
    if TEXELS_PER_CORNER * (k % CORNERS_PER_ROW) + TEXELS_PER_CORNER > size.x || k / CORNERS_PER_ROW >= size.y {
        return vec2<f32>(0.0);
    }
    let a = corner_point(k, 0u);
    let far = array<vec3<f32>, 2>(corner_point(k, 1u), corner_point(k, 2u));
    let ends = array<vec3<f32>, 2>(far[0] - a, far[1] - a);
    let to_x = x - a;
    let dist = length(to_x);
    var weight = 1.0;
    var m: array<vec2<f32>, 3>;
    var h = vec3<f32>(-1.0);
    for (var i = 0u; i < 2u; i++) {
        let na = corner_point(k, 3u + 2u * i);
        let nb = corner_point(k, 4u + 2u * i);
        // A silhouette from x: its faces on two sides of x (an open edge: its one face's two sides).
        let da = dot(na, to_x);
        let db = select(dot(nb, to_x), -da, all(nb == vec3<f32>(0.0)));
        if !(da * db < 0.0) {
            return vec2<f32>(0.0);
        }
        weight = min(weight, min(abs(da), abs(db)) / (dist * SILHOUETTE_MARGIN));
        let edge = ends[i];
        let other = ends[1u - i];
        var n = cross(edge, to_x);
        let side = dot(n, other);
        if !(abs(side) > 1e-6 * length(n) * length(other)) {
            return vec2<f32>(0.0);
        }
        n = select(n, -n, side < 0.0);
        // Convex from x: the caster (against its outward direction) on the other end's side.
        if !(dot(n, na + nb) < 0.0) {
            return vec2<f32>(0.0);
        }
        // Behind: n . (c + p - a) >= 0, p a corner-plane point about the centre.
        m[i] = vec2<f32>(dot(n, camera.light_u), dot(n, camera.light_w));
        h[i] = dot(n, a - camera.light_center);
    }
    weight = min(weight, min(corner_reach(x, far[0]), corner_reach(x, far[1])) / REACH_MARGIN);
    weight = min(weight, fan_share(x, a, corner_point(k, 7u), corner_point(k, 8u)) / SEAM_MARGIN);
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
    let v = clamp(1.0 - hidden, 0.0, 1.0);
    return select(vec2<f32>(0.0), vec2<f32>(v, clamp(weight, 0.0, 1.0)), v == v && weight == weight);
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
        params.tag
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
    out.v = written_v_of_t_toward(out.t, xs.zw);
    // V exact where a closing fan won: toward the corner's wedge, not a chord's strip (which
    // grows with the depth where the wedge grows with its square), as far as the corner is the
    // caster there. (params.corners = 1, --dbuffer-corners.)
    if VT_VARIANT == VT_EXACT && crossed && xs.z < -1.5 && params.corners != 0u {
        let corner = corner_visibility(x, u32(round(-xs.z - 2.0)));
        if corner.y > 0.0 {
            out.v = mix(out.v, corner.x, corner.y);
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
    // params.horizon = 1 (--dbuffer-horizon): at most the part of the light in front of the
    // receiver's own plane. A caster's face whose plane cuts the light sits on its own
    // silhouette, where no volume darkens it; the light behind that plane never reaches it.
    let horizon = horizon_fraction(x, n);
    if params.horizon != 0u && horizon < out.v {
        out = plain(horizon);
        took_path(2.0);
    }
    if dark {
        out = plain(0.0);
        took_path(4.0);
    }
    return out;
}
