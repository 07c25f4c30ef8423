// The camera's depth copied into an R32Float target, bit for bit (render::passes::depth_copy):
// where the device cannot copy a depth texture into a buffer (GL), readback copies this instead.
// #include shared/fullscreen_vs.wgsl

@group(0) @binding(0) var depth: texture_2d<f32>;

@fragment
fn fs_main(in: FullscreenVertex) -> @location(0) vec4<f32> {
    return vec4<f32>(textureLoad(depth, vec2<i32>(in.position.xy), 0).r, 0.0, 0.0, 0.0);
}
