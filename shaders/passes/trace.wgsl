// Shadow rays on the GPU (render::passes::trace): the scene's BVH (shared/bvh_trace.wgsl) and
// two entry points over it. cs_reference adds, per pixel, how many of a batch of the light's
// samples its point sees: the ray-cast reference of render::reference with the same points, the
// same samples in the same order and the same segment (SELF_EPS from either end), its counts
// accumulated over batches. cs_any_hit answers one ray each, for the tests that hold the GPU's
// traversal to the CPU's.

// #include shared/bvh_trace.wgsl

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
// The nodes, then the triangles (shared/bvh_trace.wgsl).
@group(0) @binding(1) var<storage, read> bvh: array<vec4<f32>>;
// cs_reference: one point per pixel, w = 1 where the light reaches a surface (0: V = 0).
// cs_any_hit: two per ray, (origin, t_min) and (dir, t_max).
@group(0) @binding(2) var<storage, read> items: array<vec4<f32>>;
// The light's sample points, in the order they are taken.
@group(0) @binding(3) var<storage, read> light_samples: array<vec4<f32>>;
// Three per item: cs_reference's visible samples so far (cs_any_hit's: 1 where the ray is
// blocked), then the box tests and the triangle tests it took, added up (the rays' cost).
@group(0) @binding(4) var<storage, read_write> results: array<u32>;

fn item_of(id: vec3<u32>) -> u32 {
    return id.x + id.y * trace_in.row;
}

@compute @workgroup_size(64)
fn cs_reference(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = trace_in.offset + item_of(id);
    if i >= trace_in.count {
        return;
    }
    let x = items[i];
    if x.w == 0.0 {
        return;
    }
    var visible = 0u;
    var nodes = 0u;
    var tests = 0u;
    // The shadow cache of the oracle: neighbouring samples are mostly blocked by the same
    // triangle, so the last occluder is tried before the BVH. Only genuine hits count, so V is
    // what the traversal alone gives.
    var last = 0xffffffffu;
    let n = trace_in.node_count;
    let m = trace_in.triangle_count;
    let end = min(trace_in.first + trace_in.samples, arrayLength(&light_samples));
    for (var s = trace_in.first; s < end; s++) {
        let d = light_samples[s].xyz - x.xyz;
        if last != 0xffffffffu {
            tests += 1u;
            if bvh_hits(x.xyz, d, SELF_EPS, 1.0 - SELF_EPS, n, m, last) {
                continue;
            }
        }
        let r = bvh_any_hit(x.xyz, d, SELF_EPS, 1.0 - SELF_EPS, n, m);
        nodes += r.nodes;
        tests += r.triangles;
        if r.hit {
            last = r.triangle;
        } else {
            visible += 1u;
        }
    }
    results[3u * i] += visible;
    results[3u * i + 1u] += nodes;
    results[3u * i + 2u] += tests;
}

@compute @workgroup_size(64)
fn cs_any_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = item_of(id);
    if i >= trace_in.count {
        return;
    }
    let o = items[2u * i];
    let d = items[2u * i + 1u];
    let r = bvh_any_hit(o.xyz, d.xyz, o.w, d.w, trace_in.node_count, trace_in.triangle_count);
    results[3u * i] = select(0u, 1u, r.hit);
    results[3u * i + 1u] = r.nodes;
    results[3u * i + 2u] = r.triangles;
}
