// The light centre's view, as render::passes::shadow_map::LightUniforms lays it out: the shadow
// map and the D-buffer's volume channels are drawn with it.
struct LightUniforms {
    view_proj: mat4x4<f32>,
    // The disk centre c.
    center: vec3<f32>,
    // 1 / far: a distance from c as a depth in [0, 1] (the umbra merge writes it).
    inv_far: f32,
    // The unit normal n_c, toward the emitting side.
    normal: vec3<f32>,
    // The frame tag the D-buffer's volume channels are drawn with (shared/frame_tag.wgsl; 0
    // for every other pass).
    tag: u32,
};
