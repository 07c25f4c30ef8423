// Shadow rays on the GPU (render::passes::trace): the scene's BVH (shared/bvh_trace.wgsl) and
// two entry points over it. cs_reference adds, per pixel, how many of a batch of the light's
// samples its point sees: the ray-cast reference of render::reference with the same points, the
// same samples in the same order and the same segment (SELF_EPS from either end), its counts
// accumulated over batches. cs_any_hit answers one ray each, for the tests that hold the GPU's
// traversal to the CPU's.

// #include shared/bvh_trace.wgsl

// #include shared/trace_io.wgsl

// The nodes, then the triangles (shared/bvh_trace.wgsl).
@group(0) @binding(1) var<storage, read> bvh: array<vec4<f32>>;

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
