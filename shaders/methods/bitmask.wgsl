// `bitmask`: bitmask soft shadows (Schwarz & Stamminger, Computer Graphics Forum 26(3), 2007) on
// the centre's shadow map (src/render/methods/bitmask.rs). Every texel of the map in front of
// the receiver is a micro-patch — a small quad at the distance the map stores, its corners moved
// to the distance the texels on its surface agree on (passes/micro_patches.wgsl: the gap
// filling) — and seen from the shaded point x it covers a quad of the light. The light's samples
// inside that quad are the AND of its four edges' half-plane masks, read from look-up tables
// (shared/light_bits.wgsl); the OR over every micro-patch is what some occluder hides, so
// overlapping occluders combine as they do in the world. V is the share of samples left.
//
// The texels searched are those of a region sized by the light (as pcss's blocker search, down
// to the nearest caster), found through a min-max pyramid of the map: a node with nothing in
// front of the receiver, or too far to reach the light from x at its nearest distance, is
// skipped whole; a node wholly in front and of one surface (its distances bend by less than
// CONTINUITY between neighbours) is back-projected as one patch through its outer corners.
// CPU twin of the arithmetic: geometry::bitmask (back_project, quad_bits, visibility).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl
// #include shared/light_bits.wgsl

// BitmaskParams of src/render/methods/bitmask.rs.
struct BitmaskParams {
    // The lowest caster's height above the light's plane.
    lowest_caster: f32,
    // Light samples, one bit each.
    samples: u32,
    // FLAG_COARSE or 0.
    flags: u32,
    // The level of detail, a share of the samples' spacing (below 1).
    detail: f32,
    // The pyramid's levels.
    levels: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

@group(1) @binding(2) var<uniform> params: BitmaskParams;

// Per texel of the map the distance at its four corners (x: its (0, 0) corner, y: (1, 0), z:
// (1, 1), w: (0, 1)), gap-filled (passes/micro_patches.wgsl).
@group(1) @binding(3) var corners: texture_2d<f32>;
// Level k (a square at x level_offset(k) of the first atlas for even k, of the second for odd
// k): per 2^(k+1) × 2^(k+1) texels of the map, the lowest height above the light's plane and the
// nearest distance (x, y),
// the largest bend of its texels' distances (z: over CONTINUITY, a step from one surface to
// another) and its farthest distance (w).
@group(1) @binding(4) var pyramid_even: texture_2d<f32>;
@group(1) @binding(6) var pyramid_odd: texture_2d<f32>;
// Half-plane masks of the samples, 256 bits (two vec4) a mask (DiskMask::lut_words_wide).
@group(1) @binding(5) var<storage, read> lut: array<vec4<u32>>;

// geometry::bitmask::CONTINUITY: texels whose distances bend less than this share are one
// surface.
const CONTINUITY: f32 = 0.03;
// render::passes::shadow_map::NO_SURFACE, halved: at or beyond it a texel holds no surface.
const NO_SURFACE: f32 = 1.5e38;
// BitmaskFlags of render::methods::bitmask.
const FLAG_COARSE: u32 = 1u;
// Nodes visited at most per pixel. Mesa's llvmpipe ends a shader's loops after 65 535
// iterations in all, so the search is one loop with none inside it, bounded here.
const MAX_VISITS: u32 = 65535u;
const STACK: u32 = 64u;
// The level code of a stack item that is one texel of the map, not a pyramid node.
const TEXEL: u32 = 15u;

struct Bits {
    lo: vec4<u32>,
    hi: vec4<u32>,
};

fn bits_and(a: Bits, b: Bits) -> Bits {
    return Bits(a.lo & b.lo, a.hi & b.hi);
}

fn bits_or(a: Bits, b: Bits) -> Bits {
    return Bits(a.lo | b.lo, a.hi | b.hi);
}

fn bits_count(b: Bits) -> u32 {
    let c = countOneBits(b.lo) + countOneBits(b.hi);
    return c.x + c.y + c.z + c.w;
}

fn bits_none() -> Bits {
    return Bits(vec4<u32>(0u), vec4<u32>(0u));
}

// The first n samples' bits (DiskMask::all).
fn bits_all(n: u32) -> Bits {
    let k = clamp(vec4<i32>(i32(n)) - vec4<i32>(0, 32, 64, 96), vec4<i32>(0), vec4<i32>(32));
    let l = clamp(vec4<i32>(i32(n)) - vec4<i32>(128, 160, 192, 224), vec4<i32>(0), vec4<i32>(32));
    return Bits(word_bits(k), word_bits(l));
}

// Per word, its k lowest bits.
fn word_bits(k: vec4<i32>) -> vec4<u32> {
    let low = (vec4<u32>(1u) << vec4<u32>(min(k, vec4<i32>(31)))) - 1u;
    return select(low, vec4<u32>(0xffffffffu), k >= vec4<i32>(32));
}

// Where pyramid level k starts in its atlas (render::passes::micro_patches::level_offset).
fn level_offset(k: u32) -> u32 {
    let base = 1u << (params.levels - 1u);
    return 2u * base - 2u * (base >> k);
}

fn lut_mask(m: u32) -> Bits {
    return Bits(lut[2u * m], lut[2u * m + 1u]);
}

// The samples p with dot(p, n) <= rho (DiskMask::half_plane): the chord of the angle bin of n
// (of -n where rho < 0) and the distance bin below |rho| / |n|.
fn half_plane(n: vec2<f32>, rho_in: f32, all: Bits) -> Bits {
    let len = length(n);
    if !(len > 0.0) || !(abs(rho_in) < 3.0e38) {
        return bits_none();
    }
    let rho = rho_in / len;
    if rho >= 1.0 {
        return all;
    }
    if rho <= -1.0 {
        return bits_none();
    }
    let j = min(u32(abs(rho) * f32(LUT_OFFSETS)), LUT_OFFSETS - 1u);
    if rho >= 0.0 {
        let beyond = lut_mask(LUT_ANGLES + lut_bin(n) * LUT_OFFSETS + j);
        return Bits(beyond.lo ^ all.lo, beyond.hi ^ all.hi);
    }
    return lut_mask(LUT_ANGLES + lut_bin(-n) * LUT_OFFSETS + j);
}

// The samples inside the convex quad q (either winding; geometry::bitmask::quad_bits).
fn quad_bits(q0: vec2<f32>, q1: vec2<f32>, q2: vec2<f32>, q3: vec2<f32>, all: Bits) -> Bits {
    // Wholly beside the unit disk: no sample.
    let lo = min(min(q0, q1), min(q2, q3));
    let hi = max(max(q0, q1), max(q2, q3));
    if any(lo > vec2<f32>(1.0)) || any(hi < vec2<f32>(-1.0)) {
        return bits_none();
    }
    let twice_area = (q0.x * q1.y - q0.y * q1.x) + (q1.x * q2.y - q1.y * q2.x)
        + (q2.x * q3.y - q2.y * q3.x) + (q3.x * q0.y - q3.y * q0.x);
    if !(abs(twice_area) >= 1e-12) {
        return bits_none();
    }
    // The outward normal of a counter-clockwise edge a b: the inside is dot(n, p) <= dot(n, a).
    // Written out edge by edge: a loop here would run inside the search's loop, and Mesa's
    // llvmpipe stops a shader's loops after 65 535 iterations in all (its loop limiter).
    let o = sign(twice_area);
    let n0 = vec2<f32>(q1.y - q0.y, q0.x - q1.x) * o;
    let n1 = vec2<f32>(q2.y - q1.y, q1.x - q2.x) * o;
    let n2 = vec2<f32>(q3.y - q2.y, q2.x - q3.x) * o;
    let n3 = vec2<f32>(q0.y - q3.y, q3.x - q0.x) * o;
    let a = bits_and(half_plane(n0, dot(n0, q0), all), half_plane(n1, dot(n1, q1), all));
    let b = bits_and(half_plane(n2, dot(n2, q2), all), half_plane(n3, dot(n3, q3), all));
    return bits_and(a, b);
}

// What one pixel's search knows.
struct Search {
    // x about c in the light's frame (light_u, light_w, light_normal): z is its height.
    x: vec3<f32>,
    // The light-frame direction (unnormalized) through texel-space point (s, t) is
    // d0 + s ds + t dt.
    d0: vec3<f32>,
    ds: vec3<f32>,
    dt: vec3<f32>,
    // The receiver's normal in the light frame, and n · (x - c).
    n: vec3<f32>,
    k: f32,
    // Bias of the in-front-of-the-receiver test, relative to the distance.
    bias: f32,
    // x's texel-space point, and the search radius's numerator per axis: texels = reach (hx -
    // h) / h.
    at: vec2<f32>,
    reach: vec2<f32>,
    // A node whose diagonal, seen from x on the light, is at most this long (unit-disk units) is
    // read as one patch at its middle texel's distance (0: never).
    fine: f32,
    all: Bits,
};

fn to_light_frame(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, camera.light_u), dot(v, camera.light_w), dot(v, camera.light_normal));
}

// The light-frame direction from c through texel-space point (s, t) at the map's mid depth.
fn texel_direction(st: vec2<f32>) -> vec3<f32> {
    let uv = st / shadow.size;
    let p = shadow.inv_light_view_proj * vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
    return to_light_frame(p.xyz / p.w - camera.light_center);
}

fn direction(s: Search, st: vec2<f32>) -> vec3<f32> {
    return s.d0 + st.x * s.ds + st.y * s.dt;
}

// The distance from c to the receiver's plane along direction dir (3e38 where the ray stays in
// front of it).
fn receiver_along(s: Search, dir: vec3<f32>) -> f32 {
    let along = dot(s.n, dir);
    let t = s.k * length(dir) / along;
    return select(3.0e38, t, along < 0.0 && t > 0.0);
}

// Where the ray from x through the point at distance `dist` along `dir` meets the light's plane,
// in unit-disk coordinates (geometry::bitmask::back_project); w = 0 where the point is not
// strictly between the plane and x's height.
fn back_project(s: Search, dir: vec3<f32>, dist: f32) -> vec3<f32> {
    let p = dir * (dist / length(dir));
    let hx = s.x.z;
    let ok = p.z > 0.0 && p.z < hx * (1.0 - 1e-5);
    let q = s.x.xy + (p.xy - s.x.xy) * (hx / max(hx - p.z, 1e-30));
    return vec3<f32>(q / max(camera.light_bound, 1e-30), select(0.0, 1.0, ok));
}

// The samples the patch with corners at texel-space points a (s0, t0) to (s1, t1) and corner
// distances c (as the corners texture holds them) hides from x.
fn patch_bits(s: Search, a: vec2<f32>, b: vec2<f32>, c: vec4<f32>) -> Bits {
    let p0 = back_project(s, direction(s, a), c.x);
    let p1 = back_project(s, direction(s, vec2<f32>(b.x, a.y)), c.y);
    let p2 = back_project(s, direction(s, b), c.z);
    let p3 = back_project(s, direction(s, vec2<f32>(a.x, b.y)), c.w);
    if p0.z * p1.z * p2.z * p3.z == 0.0 {
        return bits_none();
    }
    return quad_bits(p0.xy, p1.xy, p2.xy, p3.xy, s.all);
}

// The search radii, in texels along each axis, of occluders at height h above the light's
// plane: a point at height h on the way from x (at height hx) to a point of the light at most
// `light_bound` from c is seen from c at most light_bound (hx - h) / (hx h) from x's ray (its
// distance from c is at least h).
fn radius_at(s: Search, h: f32) -> vec2<f32> {
    return s.reach * max(s.x.z - h, 0.0) / max(h, 1e-30) + 2.0;
}

// Whether the texel-space rectangle [a, b) meets the ellipse of radii r about x's point.
fn within(s: Search, a: vec2<f32>, b: vec2<f32>, r: vec2<f32>) -> bool {
    let off = (clamp(s.at, a, b) - s.at) / r;
    return dot(off, off) <= 1.0;
}

fn push(stack: ptr<function, array<u32, 64>>, sp: ptr<function, u32>, level: u32, at: vec2<u32>) {
    if *sp < STACK {
        (*stack)[*sp] = (level << 28u) | (at.y << 14u) | at.x;
        *sp += 1u;
    }
}

fn bitmask(x: vec3<f32>, n: vec3<f32>, l: LightLookup) -> f32 {
    let size = shadow.size;
    let samples = params.samples;
    var s: Search;
    s.all = bits_all(samples);
    s.x = to_light_frame(x - camera.light_center);
    if !(s.x.z > 0.0) {
        return 0.0;
    }
    let d00 = texel_direction(vec2<f32>(0.0));
    s.ds = (texel_direction(vec2<f32>(size, 0.0)) - d00) / size;
    s.dt = (texel_direction(vec2<f32>(0.0, size)) - d00) / size;
    s.d0 = d00;
    s.n = to_light_frame(n);
    s.k = dot(n, x - camera.light_center);
    s.bias = l.rel_bias;
    s.at = l.uv * size;
    // The light's bounding radius in texels per unit of angle, each axis of the map on its own
    // (a map of a wide frustum is square: its texels span less angle across than along), grown
    // by 1 / cos² of the ray's angle from the view's axis (off the axis an angle spans more of
    // the image plane; the axis is the image plane's normal — the frustum is off-centre) and by
    // a quarter for the light's tilt seen from x.
    let axis = normalize(cross(s.ds, s.dt));
    let plane = abs(dot(s.d0, axis));
    let ray = direction(s, s.at);
    let cos2 = dot(ray, axis) * dot(ray, axis) / max(dot(ray, ray), 1e-30);
    let per_texel = vec2<f32>(length(s.ds), length(s.dt)) / max(plane, 1e-30);
    s.reach = 1.25 * camera.light_bound / (s.x.z * max(per_texel, vec2<f32>(1e-9)) * max(cos2, 1e-3));
    // The receiver's horizon: the samples behind the plane through x with normal n, which the
    // receiver hides itself (a point whose plane faces away from c still sees the light in front
    // of it).
    let m = vec2<f32>(dot(n, camera.light_u), dot(n, camera.light_w)) * camera.light_bound;
    let facing = dot(n, camera.light_center - x);
    var horizon = half_plane(m, -facing, s.all);
    if !(dot(m, m) > 0.0) && facing <= 0.0 {
        horizon = s.all;
    }
    let everything = bits_count(s.all);
    let near = max(params.lowest_caster, 1e-4);
    if s.x.z <= near || bits_count(horizon) >= everything {
        return 1.0 - f32(bits_count(horizon)) / f32(max(samples, 1u));
    }
    let coarse = (params.flags & FLAG_COARSE) != 0u;
    // The level of detail: a share of the samples' spacing (the side of a sample's share of the
    // unit disk, √(π / N)).
    s.fine = sqrt(3.14159265 / f32(max(samples, 1u))) * params.detail;
    let levels = params.levels;
    let map = vec2<f32>(size);
    // The top level: nodes at least as wide as the search, so at most 3 × 3 of them.
    let r0 = min(radius_at(s, near), vec2<f32>(size));
    var top = 0u;
    while top + 1u < levels && f32(2u << top) < max(r0.x, r0.y) {
        top += 1u;
    }
    var stack: array<u32, 64>;
    var sp = 0u;
    let width = f32(2u << top);
    let first = vec2<u32>(max(floor((s.at - r0) / width), vec2<f32>(0.0)));
    let last = vec2<u32>(clamp(floor((s.at + r0) / width), vec2<f32>(0.0), vec2<f32>(f32((u32(size) - 1u) / (2u << top)))));
    for (var ny = first.y; ny <= last.y; ny++) {
        for (var nx = first.x; nx <= last.x; nx++) {
            push(&stack, &sp, top, vec2<u32>(nx, ny));
        }
    }
    var hidden = horizon;
    var visits = 0u;
    // One patch at most an iteration: a CPU rasteriser runs every branch of a loop's body for
    // all its lanes, so the body holds one back-projection, not one per path.
    while sp > 0u && visits < MAX_VISITS {
        visits += 1u;
        sp -= 1u;
        let code = stack[sp];
        let level = code >> 28u;
        let node = vec2<u32>(code & 0x3fffu, (code >> 14u) & 0x3fffu);
        // The patch this item makes, if any: its corners a and b, its corner distances.
        var emit = false;
        var a = vec2<f32>(node);
        var b = a + 1.0;
        var c = vec4<f32>(0.0);
        if level == TEXEL {
            let o = textureLoad(d_o, vec2<i32>(node), 0).x;
            let ray = direction(s, a + 0.5);
            emit = all(a < map) && o < NO_SURFACE && within(s, a, b, radius_at(s, o * ray.z / length(ray)))
                && o < receiver_along(s, ray) * (1.0 - s.bias);
            c = textureLoad(corners, vec2<i32>(node), 0);
        } else {
            // The node's lowest height, its nearest distance, the largest bend inside it, its
            // farthest distance.
            let at = vec2<i32>(node) + vec2<i32>(i32(level_offset(level)), 0);
            let range = select(textureLoad(pyramid_odd, at, 0), textureLoad(pyramid_even, at, 0), level % 2u == 0u);
            let low = range.x;
            let w = f32(2u << level);
            a = vec2<f32>(node) * w;
            b = a + w;
            let da = direction(s, a);
            let db = direction(s, b);
            let dab = direction(s, vec2<f32>(b.x, a.y));
            let dba = direction(s, vec2<f32>(a.x, b.y));
            let ra = receiver_along(s, da);
            let rb = receiver_along(s, db);
            let rab = receiver_along(s, dab);
            let rba = receiver_along(s, dba);
            // Something of it above x's level (x's own plane, parallel to the light, is not) and
            // in front of the receiver's plane, within reach of the light.
            if low < s.x.z * (1.0 - s.bias) && range.y < max(max(ra, rb), max(rab, rba)) * (1.0 - s.bias)
                && within(s, a, b, radius_at(s, low)) {
                // Wholly above x's level (each distance below x's height), in front of the
                // receiver's plane at each of its corners and one surface: one patch through the
                // node's outer corners.
                let one_patch = coarse && all(b <= map) && range.w < s.x.z * (1.0 - 1e-5) && range.z <= CONTINUITY
                    && range.w < min(min(ra, rb), min(rab, rba)) * (1.0 - s.bias);
                // Seen from x, a node no wider on the light than a share of the samples' spacing
                // is one patch at the distance of its middle texel, if that is in front of the
                // receiver: the map read at the coarser level the search needs (its shadow's edge
                // moves by at most half a node, a fraction of the spacing of the samples).
                let qa = back_project(s, da, low * length(da) / max(da.z, 1e-30));
                let qb = back_project(s, db, low * length(db) / max(db.z, 1e-30));
                let fine_enough = s.fine > 0.0 && qa.z * qb.z > 0.0 && distance(qa.xy, qb.xy) <= s.fine;
                if one_patch {
                    let last_texel = vec2<i32>(b) - 1;
                    let ai = vec2<i32>(a);
                    c = vec4<f32>(
                        textureLoad(corners, ai, 0).x,
                        textureLoad(corners, vec2<i32>(last_texel.x, ai.y), 0).y,
                        textureLoad(corners, last_texel, 0).z,
                        textureLoad(corners, vec2<i32>(ai.x, last_texel.y), 0).w,
                    );
                    emit = true;
                } else if fine_enough {
                    let mid = min(vec2<u32>(0.5 * (a + b)), vec2<u32>(u32(size) - 1u));
                    let o = textureLoad(d_o, vec2<i32>(mid), 0).x;
                    emit = o < NO_SURFACE && o < receiver_along(s, direction(s, vec2<f32>(mid) + 0.5)) * (1.0 - s.bias);
                    b = min(b, map);
                    c = vec4<f32>(o);
                } else {
                    // Its four children, or at the first level its four texels.
                    let below = select(level - 1u, TEXEL, level == 0u);
                    let c0 = 2u * node;
                    push(&stack, &sp, below, c0);
                    push(&stack, &sp, below, c0 + vec2<u32>(1u, 0u));
                    push(&stack, &sp, below, c0 + vec2<u32>(0u, 1u));
                    push(&stack, &sp, below, c0 + vec2<u32>(1u, 1u));
                }
            }
        }
        if emit {
            hidden = bits_or(hidden, patch_bits(s, a, b, c));
            if bits_count(hidden) >= everything {
                break;
            }
        }
    }
    count_work(f32(visits));
    return 1.0 - f32(bits_count(bits_and(hidden, s.all))) / f32(max(samples, 1u));
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(bitmask(x, n, l));
}
