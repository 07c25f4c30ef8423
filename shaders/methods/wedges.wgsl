// `wedges`: soft shadow volumes with penumbra wedges (Akenine-Möller & Assarsson 2002/2003;
// src/render/methods/wedges.rs): V per pixel made over the camera's pixels before this pass (the
// centre's stencil count H and the wedges' coverage sum S, passes/wedges.wgsl), read at the
// pixel. On a side of a caster turned away from the light's centre, the centre is hidden by that
// very surface (H = 1, what Crow's volume from the centre gives there; the stencil pass closes
// closed casters with their dark faces, which leaves their own points out), so V = -S there.
// A point behind the one-sided light gets nothing. Then (params.horizon = 1, --wedges-horizon)
// at most the part of the disk in front of the receiver's own plane: a caster's face whose plane
// cuts the disk is in no wedge when the centre lights it (geometry::wedges, the CPU twin).
// #include shared/camera.wgsl
// #include shared/screen_v.wgsl

@group(1) @binding(1) var wedge_sum: texture_2d<f32>;

// WedgesParams of src/render/methods/wedges.rs.
struct WedgesParams {
    // 1: clip by the receiver's plane.
    horizon: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(1) @binding(2) var<uniform> params: WedgesParams;

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) {
        return plain(0.0);
    }
    // The cost view: the wedge fragments the coverage pass shaded at this pixel (its sum's y).
    let here = clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), vec2<i32>(textureDimensions(wedge_sum)) - 1);
    count_work(textureLoad(wedge_sum, here, 0).y);
    var v: f32;
    if !faces_light_center(x, n) {
        let size = vec2<i32>(textureDimensions(wedge_sum));
        let p = clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), size - 1);
        v = clamp(-textureLoad(wedge_sum, p, 0).x, 0.0, 1.0);
    } else {
        v = screen_visibility(pixel);
    }
    if params.horizon != 0u {
        v = min(v, horizon_fraction(x, n));
    }
    return plain(v);
}
