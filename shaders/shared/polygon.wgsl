// A convex polygon light's corners in its own plane, as the uniforms hold them: up to 16 points
// counter-clockwise, two per vec4 (xy, zw). Its cut areas, for the D-buffer's corners
// (methods/dbuffer.wgsl; one cut is shared/camera.wgsl's light_share_above), the wedges'
// coverage (passes/wedges.wgsl) and dbuffer-fused's exact regions (methods/dbuffer_fused.wgsl).
// The CPU twins are in src/geometry/outline.rs.

fn polygon_corner(corners: array<vec4<f32>, 8>, i: u32) -> vec2<f32> {
    let q = corners[i / 2u];
    return select(q.xy, q.zw, (i & 1u) == 1u);
}

// The area of the polygon cut down to the half-planes dot(m[k], p) >= h[k], k < 3 (a cut with
// m = 0 and h < 0 keeps everything): Sutherland-Hodgman into fixed arrays, then the shoelace
// formula (geometry::outline::convex_cut_area).
fn polygon_cut_area(
    corners: array<vec4<f32>, 8>,
    count: u32,
    m: array<vec2<f32>, 3>,
    h: vec3<f32>
) -> f32 {
    var poly: array<vec2<f32>, 20>;
    var next: array<vec2<f32>, 20>;
    var n = min(count, 16u);
    for (var i = 0u; i < n; i++) {
        poly[i] = polygon_corner(corners, i);
    }
    for (var k = 0u; k < 3u; k++) {
        var out = 0u;
        for (var i = 0u; i < n; i++) {
            let a = poly[i];
            let b = poly[(i + 1u) % n];
            let da = dot(m[k], a) - h[k];
            let db = dot(m[k], b) - h[k];
            if da >= 0.0 && out < 20u {
                next[out] = a;
                out++;
            }
            if (da >= 0.0) != (db >= 0.0) && out < 20u {
                next[out] = a + (b - a) * (da / (da - db));
                out++;
            }
        }
        n = out;
        if n < 3u {
            return 0.0;
        }
        poly = next;
    }
    var sum = 0.0;
    for (var i = 0u; i < n; i++) {
        let a = poly[i];
        let b = poly[(i + 1u) % n];
        sum += a.x * b.y - a.y * b.x;
    }
    return max(0.5 * sum, 0.0);
}

// Minus the part of the polygon beyond the segment a -> b's line inside the angle its ends
// subtend at the centre, over the polygon's area, for a segment turning counter-clockwise about
// the centre (plus it, clockwise): the penumbra wedges' coverage and, unsigned, dbuffer-fused's
// region of an edge (geometry::outline::polygon_edge_coverage).
fn polygon_edge_coverage(
    corners: array<vec4<f32>, 8>,
    count: u32,
    area: f32,
    a_in: vec2<f32>,
    b_in: vec2<f32>
) -> f32 {
    let turn = a_in.x * b_in.y - a_in.y * b_in.x;
    if !(abs(turn) > 0.0) || !(area > 0.0) {
        return 0.0;
    }
    let ccw = turn > 0.0;
    let a = select(b_in, a_in, ccw);
    let b = select(a_in, b_in, ccw);
    let d = b - a;
    var m: array<vec2<f32>, 3>;
    m[0] = vec2<f32>(-a.y, a.x);
    m[1] = vec2<f32>(b.y, -b.x);
    m[2] = vec2<f32>(d.y, -d.x);
    let h = vec3<f32>(0.0, 0.0, dot(m[2], a));
    return select(1.0, -1.0, ccw) * polygon_cut_area(corners, count, m, h) / area;
}
