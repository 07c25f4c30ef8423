// The point lights of the `sampled` method, as render::methods::sampled::SampleLights lays them
// out: its maps pass draws with them and its camera pass reads them.
struct SampleLight {
    view_proj: mat4x4<f32>,
    // The point on the disk.
    point: vec3<f32>,
    _pad: f32,
};

struct SampleLights {
    lights: array<SampleLight, 64>,
    // How many of them are used.
    count: u32,
    // The maps are size × size texels.
    size: f32,
    // The slope one texel spans, and the bias of the test (as ShadowUniforms).
    texel_slope: f32,
    bias_constant: f32,
    bias_slope: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
};
