// The `sampled` method's shadow maps (light-source sampling, Heckbert & Herf 1997): every surface seen from N stratified points
// on the disk, one array layer each, storing the Euclidean distance to that point (as |cx_o| does
// for the centre). The draw's instance index picks the layer's light; the method's camera pass
// reads the same SampleLights (shaders/methods/sampled.wgsl).
// #include shared/surface.wgsl
// #include shared/sample_lights.wgsl

@group(0) @binding(0) var<uniform> lights: SampleLights;

struct MapOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) layer: u32,
};

@vertex
fn vs_main(v: SurfaceIn, @builtin(instance_index) layer: u32) -> MapOut {
    var out: MapOut;
    out.clip = lights.lights[layer].view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.layer = layer;
    return out;
}

@fragment
fn fs_main(f: MapOut) -> @location(0) vec4<f32> {
    return vec4<f32>(distance(f.world, lights.lights[f.layer].point), 0.0, 0.0, 0.0);
}
