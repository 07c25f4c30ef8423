// The shadow map from the light centre c (Williams 1978): every surface, nearest by depth,
// storing its true Euclidean distance |cx_o| = |x - c| per fragment (not an interpolated vertex
// distance). It is the hard shadow's map and the D-buffer's first channel; PCF and PCSS filter it.
// #include shared/surface.wgsl
// #include shared/light.wgsl

@group(0) @binding(0) var<uniform> light: LightUniforms;

struct MapOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_main(v: SurfaceIn) -> MapOut {
    var out: MapOut;
    out.clip = light.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    return out;
}

@fragment
fn fs_main(f: MapOut) -> @location(0) vec4<f32> {
    return vec4<f32>(distance(f.world, light.center), 0.0, 0.0, 0.0);
}
