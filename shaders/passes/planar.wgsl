// Planar projected shadows (render::passes::planar; Blinn 1988): per receiver plane k, its
// pixels are marked in the stencil (reference k), then every other caster is drawn flattened
// onto the plane from the light (geometry::planar::projection) where the stencil holds k, and
// each such pixel is darkened once: the stencil is zeroed as it is drawn (the trick that stops
// double blending where projected triangles overlap). Drawn after the screen prepass
// (passes/stencil_volumes.wgsl), whose depth-stencil and world positions it uses.

const MAX_RECEIVERS: u32 = 8u;

struct Receiver {
    // World to world: onto the plane from the light, homogeneous (w < 0 beyond the light).
    projection: mat4x4<f32>,
    // (n, d): n·x + d = 0, the light on the positive side.
    plane: vec4<f32>,
};

struct PlanarUniforms {
    // World to clip with the far plane at infinity and reversed depth (ScreenUniforms').
    infinite_view_proj: mat4x4<f32>,
    // x: V written where a shadow lands (1 - opacity); y: the plane tolerance relative to the
    // distance from the eye; zw unused.
    shade: vec4<f32>,
    eye: vec4<f32>,
    receivers: array<Receiver, MAX_RECEIVERS>,
};

@group(0) @binding(0) var<uniform> planar: PlanarUniforms;
@group(0) @binding(1) var position: texture_2d<f32>;

struct MarkOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) receiver: u32,
};

// The receiver's own triangles (instance k = its index), no depth test: a fragment marks its
// pixel only where the surface the prepass saw there lies on the receiver's plane.
@vertex
fn vs_mark(@location(0) p: vec4<f32>, @builtin(instance_index) k: u32) -> MarkOut {
    var out: MarkOut;
    out.clip = planar.infinite_view_proj * p;
    out.receiver = k;
    return out;
}

@fragment
fn fs_mark(f: MarkOut) -> @location(0) vec4<f32> {
    let seen = textureLoad(position, vec2<i32>(floor(f.clip.xy)), 0);
    let plane = planar.receivers[min(f.receiver, MAX_RECEIVERS - 1u)].plane;
    let tolerance = planar.shade.y * distance(seen.xyz, planar.eye.xyz);
    if seen.w < 0.5 || abs(dot(plane.xyz, seen.xyz) + plane.w) > tolerance {
        discard;
    }
    return vec4<f32>(1.0);
}

// The casters flattened onto receiver k's plane; the stencil test keeps the fragments on its
// marked pixels, and zeroes each pixel as it is darkened.
@vertex
fn vs_shadow(@location(0) p: vec4<f32>, @builtin(instance_index) k: u32) -> @builtin(position) vec4<f32> {
    let m = planar.receivers[min(k, MAX_RECEIVERS - 1u)].projection;
    return planar.infinite_view_proj * (m * p);
}

@fragment
fn fs_shadow() -> @location(0) vec4<f32> {
    return vec4<f32>(planar.shade.x, 0.0, 0.0, 1.0);
}
