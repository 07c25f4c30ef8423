// The variance shadow map's moments (render::passes::moments): (|cx_o|, |cx_o|²) of the centre's
// shadow map box-filtered over (2R + 1)² texels, in two separable draws — across from the
// distance map, then down from the first draw's moments. Where no surface is, the distance is
// the light view's far plane (the map's own 3e38 would square to infinity).
// #include shared/fullscreen_vs.wgsl

struct MomentUniforms {
    // The step between taps: (1, 0) across, (0, 1) down.
    step: vec2<i32>,
    // R, the taps each side.
    radius: i32,
    // 1: the input is the distance map (take its distance and square it); 0: moments already.
    from_distance: u32,
    // The light view's far plane.
    far: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
};

@group(0) @binding(0) var<uniform> moments: MomentUniforms;
@group(0) @binding(1) var source: texture_2d<f32>;

@fragment
fn fs_main(in: FullscreenVertex) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(source));
    let at = vec2<i32>(in.position.xy);
    var sum = vec2<f32>(0.0);
    for (var k = -moments.radius; k <= moments.radius; k++) {
        let q = clamp(at + k * moments.step, vec2<i32>(0), size - 1);
        let texel = textureLoad(source, q, 0);
        if moments.from_distance == 1u {
            let d = min(texel.x, moments.far);
            sum += vec2<f32>(d, d * d);
        } else {
            sum += texel.xy;
        }
    }
    return vec4<f32>(sum / f32(2 * moments.radius + 1), 0.0, 0.0);
}
