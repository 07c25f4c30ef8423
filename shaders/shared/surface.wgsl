// The vertex of a scene surface, as render::SurfaceVertex lays it out (tests/render_layout.rs
// checks the offsets): every pass that draws the scene's surfaces reads it.
struct SurfaceIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: f32,
};
