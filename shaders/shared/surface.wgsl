// The vertex of a scene surface, as render::SurfaceVertex lays it out (tests/gpu/render_layout.rs
// checks the offsets): every pass that draws the scene's surfaces reads it. Surfaces are indexed
// and carry no normal: a pass that shades takes the flat normal from the derivatives of the
// world position (shared/camera.wgsl).
struct SurfaceIn {
    @location(0) position: vec3<f32>,
    @location(1) albedo: f32,
};
