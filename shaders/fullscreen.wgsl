// #include shared/fullscreen_vs.wgsl

// Fullscreen blit: copies `source` over the whole target, e.g. to show a pass's output or to
// convert it to the target's format. Draw 3 vertices, no vertex buffers (see fullscreen_vs.wgsl).

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var source_sampler: sampler;

@fragment
fn fs_main(in: FullscreenVertex) -> @location(0) vec4<f32> {
    return textureSample(source, source_sampler, in.uv);
}
