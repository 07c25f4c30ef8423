// Fullscreen-triangle vertex stage: draw 3 vertices with no vertex buffers and one triangle,
// counter-clockwise, covers the whole target (clip space (-1,1), (-1,-3), (3,1)).
//
// `uv` is (0, 0) at the top-left corner of the target and (1, 1) at the bottom-right, matching
// wgpu texture coordinates, so a fragment stage can sample a same-sized texture at `in.uv` or
// load texel `vec2<i32>(in.position.xy)`.

struct FullscreenVertex {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> FullscreenVertex {
    // index 0, 1, 2 -> uv (0, 0), (0, 2), (2, 0)
    let uv = vec2<f32>(f32(index & 2u), f32((index << 1u) & 2u));
    var out: FullscreenVertex;
    out.position = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    out.uv = uv;
    return out;
}
