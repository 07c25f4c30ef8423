// Shadow rays against the scene's BVH, the GPU port of geometry::bvh's tolerant any-hit query
// (Bvh::find_any_hit_tolerant): the same flattened nodes and triangles (geometry::bvh::FlatBvh),
// the same slab test, the same front-to-back order and the same triangle test with its rounding
// allowance, so the GPU and the CPU block the same rays but for rays that graze an edge or a
// segment's end within a few ulps.
//
// The including shader declares one array, in whatever group it binds it (one storage buffer,
// so the tracer fits an adapter with as few as four per stage):
//   bvh: array<vec4<f32>>  the nodes, two each: (min, bits of first), (max, bits of count);
//                          then the triangles in leaf order, three each: (v0, bits of index),
//                          e1, e2
// and passes the counts (nodes, triangles) to bvh_any_hit, which reads nothing beyond them.

// Entries of the traversal stack: the CPU's, more than the build's depth limit (48) needs.
const BVH_STACK: u32 = 64u;
// The tolerant test's rounding allowance, in units of the summed magnitudes of each dot
// product's terms (geometry::ray's TOLERANCE: 32 ulps of 1).
const BVH_TOLERANCE: f32 = 3.8146973e-6;
// A determinant below this is a ray parallel to the triangle (geometry::ray: 16 × the smallest
// normal f32).
const BVH_MIN_DET: f32 = 1.880791e-37;

// The ray with what the slab test needs: 1/dir with each zero component made a tiny positive
// one, so the slab test never multiplies 0 by infinity (the CPU's min/max skip that NaN; WGSL's
// do not promise to).
struct BvhRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
    inv: vec3<f32>,
};

fn bvh_ray(origin: vec3<f32>, dir: vec3<f32>) -> BvhRay {
    let safe = select(dir, vec3<f32>(1e-30), abs(dir) < vec3<f32>(1e-30));
    return BvhRay(origin, dir, 1.0 / safe);
}

// Whether the ray enters node `i`'s box within [t_min, t_max]; its entry parameter in .y.
fn bvh_enter(ray: BvhRay, i: u32, t_min: f32, t_max: f32) -> vec2<f32> {
    let lo = bvh[2u * i].xyz;
    let hi = bvh[2u * i + 1u].xyz;
    let t1 = (lo - ray.origin) * ray.inv;
    let t2 = (hi - ray.origin) * ray.inv;
    let a = min(t1, t2);
    let b = max(t1, t2);
    let near = max(max(max(a.x, a.y), a.z), t_min);
    let far = min(min(min(b.x, b.y), b.z), t_max);
    return vec2<f32>(select(0.0, 1.0, near <= far), near);
}

// The tolerant Möller–Trumbore test of geometry::ray::intersect_edges_tolerant: the ray
// parameter of the hit, or -1 when the ray misses (a miss never passes t >= t_min >= 0).
// Triangle `k` is at bvh[base + 3k], base = 2 × the node count.
fn bvh_hit_triangle(ray: BvhRay, base: u32, k: u32) -> f32 {
    let v0 = bvh[base + 3u * k].xyz;
    let e1 = bvh[base + 3u * k + 1u].xyz;
    let e2 = bvh[base + 3u * k + 2u].xyz;
    let p = cross(ray.dir, e2);
    let det = dot(e1, p);
    if abs(det) < BVH_MIN_DET {
        return -1.0;
    }
    let sgn = sign(det);
    let big_d = abs(det);
    let s = ray.origin - v0;
    let a = dot(s, p) * sgn;
    let err_a = BVH_TOLERANCE * dot(abs(s), abs(p));
    if a < -err_a {
        return -1.0;
    }
    let q = cross(s, e1);
    let b = dot(ray.dir, q) * sgn;
    let err_b = BVH_TOLERANCE * dot(abs(ray.dir), abs(q));
    let err_d = BVH_TOLERANCE * dot(abs(e1), abs(p));
    if b < -err_b || a + b > big_d + err_a + err_b + err_d {
        return -1.0;
    }
    return dot(e2, q) / det;
}

// What one any-hit query found, and what it cost.
struct BvhAnyHit {
    hit: bool,
    // The triangle hit (leaf order), where one was.
    triangle: u32,
    // Nodes whose box was tested, and triangles tested.
    nodes: u32,
    triangles: u32,
    // Where along the ray the hit is (origin + t·dir), where one was: the first found, not
    // necessarily the nearest.
    t: f32,
};

// Whether triangle `k` (leaf order) is hit at origin + t·dir with t_min <= t <= t_max: the
// shadow cache's test (the oracle's `hits_triangle_tolerant`, on the same numbers).
fn bvh_hits(
    origin: vec3<f32>,
    dir: vec3<f32>,
    t_min: f32,
    t_max: f32,
    node_count: u32,
    triangle_count: u32,
    k: u32,
) -> bool {
    if k >= triangle_count {
        return false;
    }
    let t = bvh_hit_triangle(bvh_ray(origin, dir), 2u * node_count, k);
    return t >= t_min && t <= t_max;
}

// Whether any triangle is hit at origin + t·dir with t_min <= t <= t_max: the traversal of
// Bvh::traverse (the nearer child first, the other pushed; popped nodes tested again). It
// visits each node at most once, so it stops after `node_count` steps whatever the arrays
// hold; a stack overflow (impossible for the CPU's build) drops the far child, as the CPU does.
fn bvh_any_hit(
    origin: vec3<f32>,
    dir: vec3<f32>,
    t_min: f32,
    t_max: f32,
    node_count: u32,
    triangle_count: u32,
) -> BvhAnyHit {
    var out = BvhAnyHit(false, 0u, 0u, 0u, 0.0);
    if triangle_count == 0u || node_count == 0u {
        return out;
    }
    let ray = bvh_ray(origin, dir);
    out.nodes = 1u;
    if bvh_enter(ray, 0u, t_min, t_max).x == 0.0 {
        return out;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var node = 0u;
    for (var step = 0u; step <= node_count; step++) {
        let first = bitcast<u32>(bvh[2u * node].w);
        let count = bitcast<u32>(bvh[2u * node + 1u].w);
        var next = false;
        if count > 0u {
            let end = min(first + count, triangle_count);
            for (var k = first; k < end; k++) {
                out.triangles += 1u;
                let t = bvh_hit_triangle(ray, 2u * node_count, k);
                if t >= t_min && t <= t_max {
                    out.hit = true;
                    out.triangle = k;
                    out.t = t;
                    return out;
                }
            }
        } else if first + 1u < node_count {
            let ea = bvh_enter(ray, first, t_min, t_max);
            let eb = bvh_enter(ray, first + 1u, t_min, t_max);
            out.nodes += 2u;
            if ea.x != 0.0 && eb.x != 0.0 {
                let a_first = ea.y <= eb.y;
                if sp < BVH_STACK {
                    stack[sp] = select(first, first + 1u, a_first);
                    sp += 1u;
                }
                node = select(first + 1u, first, a_first);
                next = true;
            } else if ea.x != 0.0 {
                node = first;
                next = true;
            } else if eb.x != 0.0 {
                node = first + 1u;
                next = true;
            }
        }
        // Pop the next node whose box still overlaps the interval.
        while !next && sp > 0u {
            sp -= 1u;
            let n = stack[sp];
            out.nodes += 1u;
            if bvh_enter(ray, n, t_min, t_max).x != 0.0 {
                node = n;
                next = true;
            }
        }
        if !next {
            return out;
        }
    }
    return out;
}
