// The D-buffer's volume channels, drawn from the light centre c (Jakobsen et al. 2004, §3; docs/method/dbuffer.md).
// Its CPU twin is src/geometry/twin.rs; the channel rules must match it:
//   |cx_uv|  per caster the nearest umbra exit (faces whose normal points away from c: the
//            pipeline culls the others), then the farthest over casters (fs_umbra; casters whose
//            volumes overlap in the light's view go through a scratch target merged by fs_merge
//            with the depth test Greater)
//   |cx_pv|  the nearest penumbra entry (faces whose normal points toward c), drawn over the
//            surfaces' depth: an entry behind the nearest surface is never looked up
// The targets are never cleared (but when new, and every 255 light passes): each texel drawn
// carries the frame's tag in the low bits of its distance (shared/frame_tag.wgsl), and a texel
// of any other frame reads as "no crossing". Only the exits' depth is reset, over the rectangle their
// volumes can cover (vs_reset, fs_reset, colours masked).
//   |cx_s|   eq. (2) from the fragment that won, kept per volume (the .y of the volume targets)
//   side     the winning triangle's lit side in the light's plane (.zw), for V exact under a
//            polygon light (geometry::volume_vertices::lit_side)
// Distances are true Euclidean |p - c| per fragment, not interpolated vertex distances, rounded
// as a tagged texel holds them (a silhouette face's |cx_s| is the same rounded distance).
// #include shared/light.wgsl
// #include shared/frame_tag.wgsl

@group(0) @binding(0) var<uniform> light: LightUniforms;

// Kinds, as geometry::VolumeKind::code().
const KIND_SILHOUETTE_FACE_A: u32 = 1u;
const KIND_SILHOUETTE_FACE_B: u32 = 2u;

// As render::VolumeVertex lays it out.
struct VolumeIn {
    @location(0) position: vec3<f32>,
    @location(1) kind: u32,
    // The edge point's height below the light's plane is base + num / den, num and den affine
    // over the triangle (geometry::volume_vertices::volume_vertices says why).
    @location(2) base: f32,
    @location(3) num: f32,
    @location(4) den: f32,
    // The triangle's lit side in the light's plane (geometry::volume_vertices::lit_side).
    @location(5) side: vec2<f32>,
};

struct VolumeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) kind: u32,
    @location(2) @interpolate(flat) base: f32,
    @location(3) num: f32,
    @location(4) den: f32,
    @location(5) @interpolate(flat) side: vec2<f32>,
};

@vertex
fn vs_volume(v: VolumeIn) -> VolumeOut {
    var out: VolumeOut;
    out.clip = light.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.kind = v.kind;
    out.base = v.base;
    out.num = v.num;
    out.den = v.den;
    out.side = v.side;
    return out;
}

// |cx_s| (eq. 2 as its definition in words has it, docs/method/dbuffer.md): the distance along the ray from c to the plane
// through the silhouette edge parallel to the disk, at the edge point this fragment was extruded
// from. A silhouette face is its own edge. Twin: VolumeVertex::edge_plane_distance.
fn is_silhouette_face(f: VolumeOut) -> bool {
    return f.kind == KIND_SILHOUETTE_FACE_A || f.kind == KIND_SILHOUETTE_FACE_B;
}

fn edge_plane_distance(f: VolumeOut, to_fragment: vec3<f32>, d: f32) -> f32 {
    if is_silhouette_face(f) {
        return d;
    }
    let along = dot(to_fragment, light.normal) / d;
    if !(along > 0.0) {
        return 3.0e38;
    }
    return (f.base + f.num / f.den) / along;
}

// (|p - c| tagged with this frame, |cx_s|, the lit side) of a volume fragment.
fn crossing(f: VolumeOut) -> vec4<f32> {
    let to_fragment = f.world - light.center;
    let d = length(to_fragment);
    let held = frame_quantized(d);
    let s = select(edge_plane_distance(f, to_fragment, d), held, is_silhouette_face(f));
    return vec4<f32>(frame_tagged(held, light.tag), s, f.side);
}

// Umbra exits and penumbra entries alike: the pipelines' culling keeps only the faces that count.
@fragment
fn fs_volume(f: VolumeOut) -> @location(0) vec4<f32> {
    return crossing(f);
}

// Both channels in one render pass: penumbra (0) and umbra (1) targets, the pipeline's write
// masks keep the one it draws.
struct Both {
    @location(0) penumbra: vec4<f32>,
    @location(1) umbra: vec4<f32>,
};

@fragment
fn fs_volume_both(f: VolumeOut) -> Both {
    let v = crossing(f);
    var out: Both;
    out.penumbra = v;
    out.umbra = v;
    return out;
}

// ---- Resetting the exits' depth to 1 over a rectangle (the colours masked) ----

@vertex
fn vs_reset(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 1.0, 1.0);
}

// The pipeline masks both colours: only the depth is written.
@fragment
fn fs_reset() -> Both {
    var out: Both;
    out.penumbra = vec4<f32>(0.0);
    out.umbra = vec4<f32>(0.0);
    return out;
}

// ---- Merge: the farthest of the casters' nearest umbra exits ----

@group(1) @binding(0) var scratch: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

struct MergeOut {
    @location(0) value: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_merge(@builtin(position) p: vec4<f32>) -> MergeOut {
    let s = textureLoad(scratch, vec2<i32>(p.xy), 0);
    if !(s.x > 0.0) {
        discard;
    }
    var out: MergeOut;
    out.value = s;
    out.depth = clamp(s.x * light.inv_far, 0.0, 1.0);
    return out;
}
