// dbuffer-fused's surfaces along the light centre's rays (src/render/passes/fused_layers.rs), drawn
// from c in the light view like the shadow map. Twin: geometry::fused::FusedTwin's
// caster_crossings and receiver_layers.
//   D-buffer grid: the caster surfaces every texel's centre ray crosses (fs_count, additive into
//     R16Float; casters only, both sides) and the largest height of a crossing (fs_far, as the
//     depth, test Greater);
//   list grid: the receivers, surfaces facing c (the pipelines cull the others), along each
//     texel's centre ray: the first (depth Less), the second (fs_peel: the first one's depth
//     read and passed over), the last (depth Greater) and the last on a caster, each as
//     (|p − c|, unit normal), and how many (fs_count).
// #include shared/surface.wgsl
// #include shared/fused.wgsl

@group(0) @binding(0) var<uniform> fused: FusedUniforms;
// The first receivers' depth (fs_peel).
@group(1) @binding(0) var first_depth: texture_2d<f32>;

struct LayerOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

fn surface(v: SurfaceIn) -> LayerOut {
    var out: LayerOut;
    out.clip = fused.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    return out;
}

@vertex
fn vs_surface(v: SurfaceIn) -> LayerOut {
    return surface(v);
}

// Casters only: a receiver-only object's vertices all go to one point outside the view, so its
// triangles have no area and draw nothing.
@vertex
fn vs_caster(v: SurfaceIn) -> LayerOut {
    var out = surface(v);
    if v.albedo != fused.caster_albedo {
        out.clip = vec4<f32>(-2.0, -2.0, 0.5, 1.0);
    }
    return out;
}

@fragment
fn fs_count() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0, 0.0, 0.0, 0.0);
}

// The crossing's height as its depth (the colour target is masked off).
struct FarOut {
    @location(0) unused: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

@fragment
fn fs_far(f: LayerOut) -> FarOut {
    var out: FarOut;
    out.unused = vec4<f32>(0.0);
    out.depth = clamp(fused_height(fused, f.world) * fused.inv_far, 0.0, 1.0);
    return out;
}

// (|p − c|, unit normal turned toward c) of a receiver fragment: the flat normal from the
// derivatives of the (affine on the triangle) position, as the camera pass takes it.
fn receiver(f: LayerOut) -> vec4<f32> {
    let to_c = fused.center - f.world;
    let m = cross(dpdx(f.world), dpdy(f.world));
    var n = select(normalize(to_c), normalize(m), dot(m, m) > 1e-30);
    if dot(n, to_c) < 0.0 {
        n = -n;
    }
    return vec4<f32>(length(to_c), n);
}

@fragment
fn fs_receiver(f: LayerOut) -> @location(0) vec4<f32> {
    return receiver(f);
}

// The first receiver and the count in one render pass: the pipelines' write masks keep the one
// each draws.
struct Both {
    @location(0) receiver: vec4<f32>,
    @location(1) count: vec4<f32>,
};

@fragment
fn fs_receiver_both(f: LayerOut) -> Both {
    var out: Both;
    out.receiver = receiver(f);
    out.count = vec4<f32>(1.0, 0.0, 0.0, 0.0);
    return out;
}

// The second receiver: every receiver behind the first (by the rasteriser's own depth, so the
// first itself, drawn again, is passed over exactly), nearest wins.
@fragment
fn fs_peel(f: LayerOut) -> @location(0) vec4<f32> {
    let out = receiver(f);
    let first = textureLoad(first_depth, vec2<i32>(f.clip.xy), 0).r;
    if f.clip.z <= first {
        discard;
    }
    return out;
}
