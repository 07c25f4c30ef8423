// dbuffer-fused, what its light passes (passes/fused_layers.wgsl, passes/fused_lists.wgsl) and its
// camera pass (methods/dbuffer_fused.wgsl) share: the uniforms, the candidate edge's record and
// the geometry of an edge seen from a point. The CPU twin is src/geometry/fused/ (docs/method/dbuffer-fused.md
// describes the method); every function here names the twin's it follows, line for line, in f32.

// As render::passes::fused_layers::FusedUniforms lays it out.
struct FusedUniforms {
    // World to the light view's clip space, and back (the D-buffer's view; the list grid is the
    // same view at list_size texels).
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // The disk: centre c, radius r, unit normal n toward the emitting side, basis e1, e2.
    center: vec3<f32>,
    radius: f32,
    normal: vec3<f32>,
    // 1 / the light view's far distance: a height as a depth in [0, 1].
    inv_far: f32,
    e1: vec3<f32>,
    // Texels per side of the list grid.
    list_size: f32,
    e2: vec3<f32>,
    // Half the diagonal of a list texel, as a slope (FusedTwin::texel_ray_of's half_slope).
    half_slope: f32,
    // Texels per side of the D-buffer (where the caster crossings are counted).
    map_size: f32,
    // Edge ids one list stores.
    cap: u32,
    // Disk samples in the mask (at most 128).
    samples: u32,
    // Candidate edges.
    edge_count: u32,
    // The largest receiver height (the proxies' extent).
    h_max: f32,
    // SurfaceVertex.albedo of casters (render::gpu_scene::CASTER_ALBEDO).
    caster_albedo: f32,
    // 1: every list counts as overflowing (too many candidate edges for the budget).
    all_overflow: u32,
    _pad: u32,
};

// A candidate edge (geometry::fused::FusedEdge::gpu_record): a.xyz, layers · b.xyz, max |a_i| ·
// n0.xyz, offset0 · n1.xyz, offset1 · fold.xyz, 1 where a silhouette from the light centre c ·
// m_c.xyz, m_c·fold with m_c = (a − c) × (b − c) · its caster, 1 where that caster is convex.
// Face planes n·p − offset, positive in front.
struct FusedEdge {
    a: vec4<f32>,
    b: vec4<f32>,
    n0: vec4<f32>,
    n1: vec4<f32>,
    fold: vec4<f32>,
    mc: vec4<f32>,
    caster: vec4<f32>,
};

// One list texel's ray and where its receivers can be (geometry::fused::TexelRay), as the merge
// makes it: patches k = 0 .. count − 1 (point xyz, radius) and (normal xyz, bulge); dir.w = 1
// where the texel has a ray (receivers around it), 0 where it has none; span = (lo, hi) of the
// deeper stretch (distances along dir; lo > hi: none), far (a distance along dir), patch count.
struct TexelRay {
    point: array<vec4<f32>, 3>,
    normal: array<vec4<f32>, 3>,
    dir: vec4<f32>,
    span: vec4<f32>,
};

// geometry::fused::CLIP and FACING_TOL.
const FUSED_CLIP: f32 = 1e-4;
const FUSED_FACING_TOL: f32 = 1.9073486e-6; // 16 f32::EPSILON

fn fused_height(u: FusedUniforms, p: vec3<f32>) -> f32 {
    return dot(u.normal, p - u.center);
}

// Unit direction from c through the centre of texel t of a size-texel grid over the light view
// (FusedTwin::texel_ray).
fn fused_texel_dir(u: FusedUniforms, t: vec2<f32>, size: f32) -> vec3<f32> {
    let uv = (t + 0.5) / size;
    let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
    let p = u.inv_view_proj * ndc;
    return normalize(p.xyz / p.w - u.center);
}

fn fused_max_abs(v: vec3<f32>) -> f32 {
    let a = abs(v);
    return max(a.x, max(a.y, a.z));
}

// FusedEdge::is_silhouette_from.
fn fused_is_silhouette_from(e: FusedEdge, x: vec3<f32>) -> bool {
    let tol = FUSED_FACING_TOL * (1.0 + fused_max_abs(x) + e.b.w);
    let front0 = dot(e.n0.xyz, x) - e.n0.w > -tol;
    let front1 = dot(e.n1.xyz, x) - e.n1.w > -tol;
    return front0 != front1;
}
