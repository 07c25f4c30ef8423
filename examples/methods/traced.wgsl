// Shadow rays as a user's method: V is the share of a grid of points over the light that the
// scene's BVH leaves in view of the shaded point, traced in the camera pass with
// `scene_occluded` (a file that calls it gets the BVH bound: docs/guide/user-methods.md).
//   dbuffer compare fig7-concave --methods pcss,file:examples/methods/traced.wgsl --knob grid=6
// A disk is sampled by the concentric map (Shirley and Chiu), a rectangle or a polygon on the
// grid over its corners' box, points outside it left out. No denoiser: a grid of g × g points
// has g² levels, banded where the built-in `raytraced` is noisy.
// knob: grid 1..12 = 4
// #include shared/camera.wgsl

// The grid point (i, j) of g × g over [-1, 1]², at its cells' centres.
fn cell(i: u32, j: u32, g: u32) -> vec2<f32> {
    return (vec2<f32>(f32(i), f32(j)) + 0.5) / f32(g) * 2.0 - 1.0;
}

// A point of [-1, 1]² on the light, in its plane's (u, w) coordinates, or a miss (z = 0).
fn on_light(a: vec2<f32>) -> vec3<f32> {
    if polygon_light() {
        var lo = vec2<f32>(3.0e38);
        var hi = vec2<f32>(-3.0e38);
        for (var k = 0u; k < camera.light_corner_count; k++) {
            lo = min(lo, light_corner(k));
            hi = max(hi, light_corner(k));
        }
        let p = mix(lo, hi, a * 0.5 + 0.5);
        // Inside the convex polygon: on the left of every edge (counter-clockwise corners).
        for (var k = 0u; k < camera.light_corner_count; k++) {
            let e0 = light_corner(k);
            let e1 = light_corner((k + 1u) % camera.light_corner_count);
            let e = e1 - e0;
            let q = p - e0;
            if e.x * q.y - e.y * q.x < 0.0 {
                return vec3<f32>(0.0);
            }
        }
        return vec3<f32>(p, 1.0);
    }
    // The concentric map of the square onto the unit disk, scaled by the radius.
    var r = a.y;
    var phi = 1.5707963 - 0.7853982 * a.x / max(abs(a.y), 1e-30);
    if abs(a.x) > abs(a.y) {
        r = a.x;
        phi = 0.7853982 * a.y / a.x;
    }
    return vec3<f32>(camera.light_radius * r * vec2<f32>(cos(phi), sin(phi)), 1.0);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let g = u32(round(knob_grid()));
    var seen = 0.0;
    var total = 0.0;
    for (var i = 0u; i < g; i++) {
        for (var j = 0u; j < g; j++) {
            let q = on_light(cell(i, j, g));
            if q.z == 0.0 {
                continue;
            }
            let s = camera.light_center + q.x * camera.light_u + q.y * camera.light_w;
            // Points of the light behind x's own plane send it nothing.
            if dot(s - x, n) <= 0.0 {
                total += 1.0;
                continue;
            }
            count_work(1.0);
            total += 1.0;
            seen += select(1.0, 0.0, scene_occluded(x, s));
        }
    }
    return plain(seen / max(total, 1.0));
}
