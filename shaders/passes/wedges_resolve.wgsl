// The resolve of penumbra wedges (render::passes::wedges): V = clamp(1 - H - sum, 0, 1) per
// pixel, H = 1 where the centre's stencil count is not zero (two pipelines over the same
// fullscreen triangle, one per stencil test), sum the wedges' coverage (passes/wedges.wgsl).
// #include shared/fullscreen_vs.wgsl

@group(0) @binding(0) var wedge_sum: texture_2d<f32>;

fn sum_at(p: vec4<f32>) -> f32 {
    return textureLoad(wedge_sum, vec2<i32>(p.xy), 0).x;
}

// Where the stencil count is zero: outside the centre's hard shadow.
@fragment
fn fs_outside(in: FullscreenVertex) -> @location(0) vec4<f32> {
    return vec4<f32>(clamp(1.0 - sum_at(in.position), 0.0, 1.0), 0.0, 0.0, 0.0);
}

// Where the stencil count is not zero: inside it.
@fragment
fn fs_inside(in: FullscreenVertex) -> @location(0) vec4<f32> {
    return vec4<f32>(clamp(-sum_at(in.position), 0.0, 1.0), 0.0, 0.0, 0.0);
}
