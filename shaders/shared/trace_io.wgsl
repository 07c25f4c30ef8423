// What both shadow-ray tracers bind and share (passes/trace.wgsl, the BVH in WGSL;
// passes/trace_rq.wgsl, hardware ray queries): TraceUniforms of render::passes::trace, the items,
// the light's samples and the results, bindings 0, 2, 3 and 4 of group 0. Each declares its scene
// at binding 1 itself.

struct TraceUniforms {
    // Pixels (cs_reference) or rays (cs_any_hit) to answer.
    count: u32,
    // The batch of samples: samples[first .. first + samples].
    first: u32,
    samples: u32,
    // Invocations per row of the dispatch (its x workgroups × 64): item = x + y · row.
    row: u32,
    node_count: u32,
    triangle_count: u32,
    // cs_reference: the first pixel of this dispatch (it answers pixels offset .. count), so a
    // batch of samples can be traced over the image in slices of pixels.
    offset: u32,
    _pad1: u32,
};

// Hits closer than this fraction of the segment to either end are ignored (geometry::oracle's
// SELF_EPS).
const SELF_EPS: f32 = 1e-4;

@group(0) @binding(0) var<uniform> trace_in: TraceUniforms;
// cs_reference: one point per pixel, w = 1 where the light reaches a surface (0: V = 0).
// cs_any_hit: two per ray, (origin, t_min) and (dir, t_max).
@group(0) @binding(2) var<storage, read> items: array<vec4<f32>>;
// The light's sample points, in the order they are taken.
@group(0) @binding(3) var<storage, read> light_samples: array<vec4<f32>>;
// Three per item: cs_reference's visible samples so far (cs_any_hit's: 1 where the ray is
// blocked), then the box tests and the triangle tests it took, added up (the rays' cost; 0 where
// the driver's ray queries traced them: it does not say).
@group(0) @binding(4) var<storage, read_write> results: array<u32>;

fn item_of(id: vec3<u32>) -> u32 {
    return id.x + id.y * trace_in.row;
}
