// `wedges`: soft shadow volumes with penumbra wedges (Akenine-Möller & Assarsson 2002/2003;
// src/render/methods/wedges.rs): V per pixel made over the camera's pixels before this pass (the
// centre's stencil count H and the wedges' coverage sum S, passes/wedges.wgsl), read at the
// pixel. On a side of a caster turned away from the light's centre, the centre is hidden by that
// very surface (H = 1, what Crow's volume from the centre gives there; the stencil pass closes
// closed casters with their dark faces, which leaves their own points out), so V = -S there.
// A point behind the one-sided light gets nothing. Then (wedge_options.x = 1, --wedges-horizon)
// at most the part of the disk in front of the receiver's own plane: a caster's face whose plane
// cuts the disk is in no wedge when the centre lights it (geometry::wedges, the CPU twin).
// #include shared/camera.wgsl
// #include shared/screen_v.wgsl

@group(1) @binding(1) var wedge_sum: texture_2d<f32>;
// render::methods::wedges::WedgeOptions. x: 1 = clip by the receiver's plane.
@group(1) @binding(2) var<uniform> wedge_options: vec4<f32>;

// The part of the light in front of the plane through x with normal n
// (geometry::wedges::DiskFrame::horizon_fraction): with k = n . (c - x) and m the part of n in
// the light's plane, the far side of the chord at -k / (r |m|), V(t)'s exact disk-half-plane area
// (for a polygon, its share beyond that chord).
fn horizon_fraction(x: vec3<f32>, n: vec3<f32>) -> f32 {
    let nc = camera.light_normal;
    let k = dot(n, camera.light_center - x);
    let s = length(n - dot(n, nc) * nc) * camera.light_radius;
    if !(s > 1e-6 * abs(k)) {
        return select(0.0, 1.0, k > 0.0);
    }
    if camera.light_kind == LIGHT_POLYGON {
        // In front where p . (n . u, n . w) > -k, p a corner-plane point about the centre.
        return light_share_above(vec2<f32>(dot(n, camera.light_u), dot(n, camera.light_w)), -k);
    }
    return disk_segment_fraction(-k / s);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) {
        return plain(0.0);
    }
    var v: f32;
    if !faces_light_center(x, n) {
        let size = vec2<i32>(textureDimensions(wedge_sum));
        let p = clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), size - 1);
        v = clamp(-textureLoad(wedge_sum, p, 0).x, 0.0, 1.0);
    } else {
        v = screen_visibility(pixel);
    }
    if wedge_options.x > 0.5 {
        v = min(v, horizon_fraction(x, n));
    }
    return plain(v);
}
