// Screen-space stencil shadows (render::passes::stencil_volumes): the camera's depth and world
// position (the prepass), shadow volumes counted in the stencil buffer (z-fail, Carmack's
// reverse with both caps), and the resolve of the count into V per pixel. Every vertex stage
// uses the camera with its far plane at infinity (ScreenUniforms::infinite_view_proj), so a
// volume's back cap (its vertices have w = 0) is never clipped, and `@invariant` positions, so
// the prepass and the volumes agree on every depth they share.
// #include shared/surface.wgsl
// #include shared/fullscreen_vs.wgsl

struct ScreenUniforms {
    // World to clip, far plane at infinity, reversed depth: 1 at the near plane, 2^-20 at
    // infinity (render::passes::camera::ScreenView::infinite_view_proj).
    infinite_view_proj: mat4x4<f32>,
    // The camera position (w unused).
    eye: vec4<f32>,
    // Width and height of the targets in pixels (zw unused).
    size: vec4<f32>,
};

@group(0) @binding(0) var<uniform> screen: ScreenUniforms;

struct PrepassOut {
    @builtin(position) @invariant clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

// The prepass: every surface, nearest by depth; the world position of what each pixel shows
// (w = 1; the target is cleared to w = 0 where nothing is).
@vertex
fn vs_prepass(v: SurfaceIn) -> PrepassOut {
    var out: PrepassOut;
    out.clip = screen.infinite_view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    return out;
}

@fragment
fn fs_prepass(f: PrepassOut) -> @location(0) vec4<f32> {
    return vec4<f32>(f.world, 1.0);
}

struct VolumeOut {
    @builtin(position) @invariant clip: vec4<f32>,
};

// Volume triangles as homogeneous points: w = 1 on the caster, w = 0 for a direction away from
// the light (the sides' far ends and the back cap). No fragment stage: only the stencil changes.
@vertex
fn vs_volume(@location(0) p: vec4<f32>) -> VolumeOut {
    var out: VolumeOut;
    out.clip = screen.infinite_view_proj * p;
    return out;
}

// The resolve: drawn where the stencil test passes (a non-zero count: in shadow), V = 0 there;
// the target was cleared to 1.
@fragment
fn fs_shadowed() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.0, 0.0);
}

// The fill measure: one per volume fragment, added up (no depth or stencil test).
@fragment
fn fs_one() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.0, 0.0, 0.0);
}
