//! Every GPU struct has the layout its WGSL declaration has (naga's reflection), so the two cannot
//! drift apart silently.

#[path = "support/wgsl_layout.rs"]
mod wgsl_layout;

use dbuffer::render::{
    CameraUniforms, LightUniforms, MethodUniforms, SampleLight, SampleLights, SurfaceVertex,
    VolumeVertex,
};
use dbuffer::shader_source;

fn source(name: &str) -> String {
    shader_source::load(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn uniforms_match_their_wgsl() {
    let light = source("light_pass.wgsl");
    assert_wgsl_layout!(
        LightUniforms,
        &light,
        "LightUniforms",
        view_proj,
        center,
        normal,
        depth_scale
    );
    let camera = source("camera_pass.wgsl");
    assert_wgsl_layout!(
        CameraUniforms,
        &camera,
        "CameraUniforms",
        view_proj,
        light_view_proj,
        eye,
        light_center,
        light_normal,
        bias,
        mode
    );
    assert_wgsl_layout!(
        MethodUniforms,
        &camera,
        "MethodUniforms",
        params,
        pcss,
        inv_light_view_proj,
        poisson
    );
    // The sampled method's lights, read by its own pass and by the camera pass.
    for shader in [camera.as_str(), &source("sample_maps.wgsl")] {
        assert_wgsl_layout!(SampleLight, shader, "SampleLight", view_proj, point);
        assert_wgsl_layout!(SampleLights, shader, "SampleLights", lights);
    }
}

/// Vertex inputs are not laid out by WGSL; the attribute offsets in Rust must match the Rust
/// struct, and the shader locations the WGSL inputs.
#[test]
fn vertex_attributes_match_the_structs() {
    use std::mem::offset_of;
    let surface: Vec<(u32, u64)> = SurfaceVertex::ATTRIBUTES
        .iter()
        .map(|a| (a.shader_location, a.offset))
        .collect();
    assert_eq!(
        surface,
        vec![
            (0, offset_of!(SurfaceVertex, position) as u64),
            (1, offset_of!(SurfaceVertex, normal) as u64),
            (2, offset_of!(SurfaceVertex, albedo) as u64),
        ]
    );
    let volume: Vec<(u32, u64)> = VolumeVertex::ATTRIBUTES
        .iter()
        .map(|a| (a.shader_location, a.offset))
        .collect();
    assert_eq!(
        volume,
        vec![
            (0, offset_of!(VolumeVertex, position) as u64),
            (1, offset_of!(VolumeVertex, kind) as u64),
            (2, offset_of!(VolumeVertex, normal) as u64),
            (3, offset_of!(VolumeVertex, edge_a) as u64),
            (4, offset_of!(VolumeVertex, edge_b) as u64),
            (5, offset_of!(VolumeVertex, extrusion) as u64),
        ]
    );
    // The WGSL inputs use those locations with the matching types (SurfaceIn comes from
    // shared/surface.wgsl, which both passes include).
    let light = source("light_pass.wgsl");
    assert!(source("camera_pass.wgsl").contains("@location(2) albedo: f32"));
    for decl in [
        "@location(0) position: vec3<f32>",
        "@location(1) kind: u32",
        "@location(2) normal: vec3<f32>",
        "@location(5) extrusion: vec3<f32>",
        "@location(1) normal: vec3<f32>",
        "@location(2) albedo: f32",
    ] {
        assert!(light.contains(decl), "light_pass.wgsl lacks `{decl}`");
    }
}
