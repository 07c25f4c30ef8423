// `wedges`: soft shadow volumes with penumbra wedges (Akenine-Möller & Assarsson 2002/2003;
// src/render/methods/wedges.rs): V per pixel made over the camera's pixels before this pass (the
// centre's stencil count H and the wedges' coverage sum S, passes/wedges.wgsl), read at the
// pixel. On a side of a caster turned away from the light's centre, the centre is hidden by that
// very surface (H = 1, what Crow's volume from the centre gives there; the stencil pass closes
// closed casters with their dark faces, which leaves their own points out), so V = -S there.
// A point behind the one-sided light gets nothing.
// #include shared/camera.wgsl
// #include shared/screen_v.wgsl

@group(1) @binding(1) var wedge_sum: texture_2d<f32>;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) {
        return plain(0.0);
    }
    if !faces_light_center(x, n) {
        let size = vec2<i32>(textureDimensions(wedge_sum));
        let p = clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), size - 1);
        return plain(clamp(-textureLoad(wedge_sum, p, 0).x, 0.0, 1.0));
    }
    return plain(screen_visibility(pixel));
}
