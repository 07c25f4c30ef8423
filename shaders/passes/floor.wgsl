// The floor (src/render/passes/floor.rs): the scene drawn with a flat colour into Rgba8 and a
// depth buffer, the cheapest image of it. `dbuffer bench` gives every frame as a ratio to it.
// #include shared/surface.wgsl

struct FloorUniforms {
    view_proj: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> floor_camera: FloorUniforms;

@vertex
fn vs_main(v: SurfaceIn) -> @builtin(position) vec4<f32> {
    return floor_camera.view_proj * vec4<f32>(v.position, 1.0);
}

@fragment
fn fs_main() -> @location(0) vec4<f32> {
    return vec4<f32>(0.8, 0.8, 0.8, 1.0);
}
