// The D-buffer's volume channels, drawn from the light centre c (seed 000 §3; design.md §2).
// Its CPU twin is src/geometry/twin.rs; the channel rules must match it:
//   |cx_uv|  per caster the nearest umbra exit (faces whose normal points away from c: the
//            pipeline culls the others), then the farthest over casters (fs_umbra; casters whose
//            volumes overlap in the light's view go through a scratch target merged by fs_merge
//            with the depth test Greater)
//   |cx_pv|  the nearest penumbra entry (faces whose normal points toward c), drawn over the
//            surfaces' depth: an entry behind the nearest surface is never looked up
//   |cx_s|   eq. (2) from the fragment that won, kept per volume (the .y of the volume targets)
// Distances are true Euclidean |p - c| per fragment, not interpolated vertex distances.
// #include shared/light.wgsl

@group(0) @binding(0) var<uniform> light: LightUniforms;

// Kinds, as geometry::VolumeKind::code().
const KIND_SILHOUETTE_FACE_A: u32 = 1u;
const KIND_SILHOUETTE_FACE_B: u32 = 2u;

// As render::VolumeVertex lays it out.
struct VolumeIn {
    @location(0) position: vec3<f32>,
    @location(1) kind: u32,
    // The silhouette edge and the rim point the triangle was extruded from.
    @location(2) edge_a: vec3<f32>,
    @location(3) edge_b: vec3<f32>,
    @location(4) extrusion: vec3<f32>,
};

struct VolumeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) kind: u32,
    @location(2) @interpolate(flat) edge_a: vec3<f32>,
    @location(3) @interpolate(flat) edge_b: vec3<f32>,
    @location(4) @interpolate(flat) extrusion: vec3<f32>,
};

@vertex
fn vs_volume(v: VolumeIn) -> VolumeOut {
    var out: VolumeOut;
    out.clip = light.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.kind = v.kind;
    out.edge_a = v.edge_a;
    out.edge_b = v.edge_b;
    out.extrusion = v.extrusion;
    return out;
}

// The point of the line a-b closest to the line p-q (a when parallel or a = b); the CPU twin is
// geometry::volumes::closest_point_on_line.
fn closest_point_on_line(a: vec3<f32>, b: vec3<f32>, p: vec3<f32>, q: vec3<f32>) -> vec3<f32> {
    let d1 = b - a;
    let d2 = q - p;
    let w0 = a - p;
    let aa = dot(d1, d1);
    let bb = dot(d1, d2);
    let cc = dot(d2, d2);
    let dd = dot(d1, w0);
    let ee = dot(d2, w0);
    let den = aa * cc - bb * bb;
    if !(den > 1e-12 * aa * cc) {
        return a;
    }
    return a + d1 * ((bb * ee - cc * dd) / den);
}

// |cx_s| (eq. 2 as the brief defines it in words): the distance along the ray from c to the plane
// through the silhouette edge parallel to the disk, at the edge point this fragment was extruded
// from. A silhouette face is its own edge. Twin: VolumeVertex::edge_plane_distance.
fn edge_plane_distance(f: VolumeOut, d: f32) -> f32 {
    if f.kind == KIND_SILHOUETTE_FACE_A || f.kind == KIND_SILHOUETTE_FACE_B {
        return d;
    }
    let along = dot(f.world - light.center, light.normal) / d;
    if !(along > 0.0) {
        return 3.0e38;
    }
    let e = closest_point_on_line(f.edge_a, f.edge_b, f.extrusion, f.world);
    return dot(e - light.center, light.normal) / along;
}

// Umbra exits and penumbra entries alike: the pipelines' culling keeps only the faces that count.
@fragment
fn fs_volume(f: VolumeOut) -> @location(0) vec4<f32> {
    let d = distance(f.world, light.center);
    return vec4<f32>(d, edge_plane_distance(f, d), 0.0, 0.0);
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
