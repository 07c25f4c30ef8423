// One light sample of `linear-ssm`, as render::passes::ssm::SsmSample lays it out: the skin
// extraction reads its map with it, and the skins of its neighbours are drawn into its
// visibility channel with it.
struct SsmSample {
    // The sample's moved light view, and its inverse (texel centre -> world direction).
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // The sample point on the segment.
    point: vec3<f32>,
    // Its layer in the maps' array texture.
    layer: u32,
    // Maps are size × size texels.
    size: u32,
    // Skin triangles the buffer holds.
    capacity: u32,
    // The distance of a texel with no surface (the view's far plane).
    far: f32,
    // A cell is a discontinuity when its largest distance exceeds its smallest by this factor.
    tau: f32,
    // The share of the light each pair of neighbouring samples stands for, 1/(N - 1).
    weight: f32,
    // A skin fragment farther than the sample's own map by this fraction is hidden.
    skin_bias: f32,
    // Floats per row of the map's copy in the skin extraction's buffer (rows padded to 256 bytes).
    pitch: u32,
    _pad1: f32,
};

// A skin corner: world position, value (0 on the occluder, 1 on the receiver); the cell it came
// from and its corner, for tests.
struct SkinVertex {
    position: vec3<f32>,
    value: f32,
    cell: u32,
    corner: u32,
    _pad0: u32,
    _pad1: u32,
};

// Distances at or above this are "no surface" (geometry::ssm::NO_SURFACE_AT).
const SSM_NO_SURFACE_AT: f32 = 1.5e38;
