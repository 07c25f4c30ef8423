// Shadow rays on the GPU through hardware ray queries (render::passes::trace, Path::RayQuery):
// the scene's triangles in an acceleration structure the driver builds (one bottom level of
// every triangle of the CPU's BVH, world space, under one top-level instance with the identity
// transform) and the two entry points of passes/trace.wgsl with the same meaning. cs_reference
// adds, per pixel, how many of a batch of the light's samples its point sees (the same points,
// the same samples in the same order, the same segment: SELF_EPS from either end); cs_any_hit
// answers one ray each.
//
// Every triangle is opaque and neither side is culled (a shadow is cast by both sides of a
// surface, as on the CPU), and the first hit found ends a query: a shadow ray asks only whether
// something blocks it. The driver's triangle test is its own (watertight or not, no rounding
// allowance), so the two paths differ only for rays that graze an edge or a segment's end.
// The driver does not say how many boxes and triangles it tested: the counts are left at 0.

enable wgpu_ray_query;

// #include shared/trace_io.wgsl

// The scene's triangles.
@group(0) @binding(1) var scene_tlas: acceleration_structure;

// Whether a triangle lies on origin + t·dir for some t in [t_min, t_max] (t in units of dir's
// length, as the CPU's query takes it: dir is not normalized).
fn rq_blocked(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> bool {
    if !(t_min <= t_max) || !(t_min >= 0.0) || all(dir == vec3<f32>(0.0)) {
        return false;
    }
    var rq: ray_query;
    let flags = RAY_FLAG_FORCE_OPAQUE | RAY_FLAG_TERMINATE_ON_FIRST_HIT;
    rayQueryInitialize(&rq, scene_tlas, RayDesc(flags, 0xffu, t_min, t_max, origin, dir));
    // Opaque triangles are committed by the traversal itself: no candidate to confirm.
    while rayQueryProceed(&rq) {}
    let hit = rayQueryGetCommittedIntersection(&rq);
    return hit.kind != RAY_QUERY_INTERSECTION_NONE;
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
    let end = min(trace_in.first + trace_in.samples, arrayLength(&light_samples));
    for (var s = trace_in.first; s < end; s++) {
        let d = light_samples[s].xyz - x.xyz;
        if !rq_blocked(x.xyz, d, SELF_EPS, 1.0 - SELF_EPS) {
            visible += 1u;
        }
    }
    results[3u * i] += visible;
}

@compute @workgroup_size(64)
fn cs_any_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = item_of(id);
    if i >= trace_in.count {
        return;
    }
    let o = items[2u * i];
    let d = items[2u * i + 1u];
    results[3u * i] = select(0u, 1u, rq_blocked(o.xyz, d.xyz, o.w, d.w));
    results[3u * i + 1u] = 0u;
    results[3u * i + 2u] = 0u;
}
