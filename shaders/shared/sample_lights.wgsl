// The point lights of the `sampled` method, as render::SampleLights lays them out.
struct SampleLight {
    view_proj: mat4x4<f32>,
    // xyz: the point on the disk.
    point: vec4<f32>,
};

struct SampleLights {
    lights: array<SampleLight, 64>,
};
