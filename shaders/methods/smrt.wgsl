// `smrt`: shadow-map ray tracing, as Unreal Engine 5 soft-shadows its virtual shadow maps
// (src/render/methods/smrt.rs). Per pixel a few rays from the point toward points on the light,
// each marched through the centre's shadow map — one depth layer — from the light's end to the
// point, with the step times crowded toward the point; a ray is hit where it passes behind the
// stored surface within one step, and where it jumps behind a nearer surface (a depth gap: the
// map cannot say whether the occluder goes on behind) it is compared with the last surface it
// was in front of, extrapolated along the ray. V = the rays that miss over the rays traced.
// knobs: x rays, y steps per ray, z flags (1 extrapolate, 2 adaptive ray count), w the share of
// the way to the light a ray is marched (the cap on the penumbra's width).
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

const FLAG_EXTRAPOLATE: u32 = 1u;
const FLAG_ADAPTIVE: u32 = 2u;
const MAX_SLOPE: f32 = 0.3;

// A per-pixel offset in [0, 1) (interleaved gradient noise), `salt` picking one of
// several independent ones: the rays' Cranley-Patterson rotation, fixed by the pixel alone, so
// two renders of a frame agree.
fn pixel_noise(pixel: vec2<f32>, salt: f32) -> f32 {
    return interleaved_gradient_noise(pixel + salt * vec2<f32>(47.0, 17.0));
}

// A point of the light for u in the unit square, of uniform area density, in polar form about
// the light's centre: u.x goes round (an angle for the disk; for a polygon, its fan of triangles
// from the centre picked by area, and the place along that triangle's edge), sqrt(u.y) out. The
// same u lands within a few per cent of the same place on a disk and on the regular polygon
// inscribed in it (corner 0 on the disk's first axis), so a polygon's shadow meets its disk's.
fn light_point(u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.y);
    var p: vec2<f32>;
    if polygon_light() {
        let n = min(camera.light_corner_count, 16u);
        let target_area = u.x * camera.light_area;
        var before = 0.0;
        var a = light_corner(0u);
        var b = light_corner(min(1u, n - 1u));
        var t = 0.0;
        var found = false;
        var previous = light_corner(0u);
        for (var i = 0u; i < n; i++) {
            let next = light_corner(select(i + 1u, 0u, i + 1u == n));
            // The triangle (centre, previous, next): half their cross product.
            let area = 0.5 * abs(previous.x * next.y - previous.y * next.x);
            let take = !found && (target_area < before + area || i + 1u == n);
            a = select(a, previous, take);
            b = select(b, next, take);
            t = select(t, clamp((target_area - before) / max(area, 1e-30), 0.0, 1.0), take);
            found = found || take;
            before += area;
            previous = next;
        }
        // Uniform in the triangle with its apex at the centre: the point r of the way out to
        // the edge, at t along it (the area element is r dr dt times a constant).
        p = r * mix(a, b, t);
    } else {
        let phi = 6.2831853 * u.x;
        p = r * camera.light_radius * vec2<f32>(cos(phi), sin(phi));
    }
    return camera.light_center + p.x * camera.light_u + p.y * camera.light_w;
}

// Whether the ray from x toward the light point q is stopped in the map: UE5's SMRTRayCast, in
// distances from the light's centre (smaller is nearer the light). `offset` in [0, 1) shifts the
// step times of this pixel so neighbours sample between each other's steps.
fn ray_hits(x: vec3<f32>, q: vec3<f32>, rel_bias: f32, offset: f32) -> bool {
    let steps = max(u32(shadow.knobs.y), 1u);
    let extrapolate = (u32(shadow.knobs.z) & FLAG_EXTRAPOLATE) != 0u;
    let far = x + (q - x) * clamp(shadow.knobs.w, 0.0, 1.0);
    let c = camera.light_center;
    // Homogeneous coordinates are linear along the ray: one product per end.
    let clip_x = shadow.light_view_proj * vec4<f32>(x, 1.0);
    let clip_far = shadow.light_view_proj * vec4<f32>(far, 1.0);
    let length_along = length(far - x);
    var history = -1.0;
    var history_time = 0.0;
    var slope = 0.0;
    var previous = -1.0;
    var hit = false;
    for (var i = 0u; i <= steps; i++) {
        // Time 1 at the far end, 0 at x, crowded toward x (the square of a linear ramp).
        let k = f32(steps - i) - 1.0 + offset;
        let time = select(clamp(k / f32(steps), 0.0, 1.0), 0.0, i == steps);
        let time2 = time * time;
        let clip = mix(clip_x, clip_far, time2);
        let y = mix(x, far, time2);
        if !(clip.w > 0.0) {
            continue;
        }
        let ndc = clip.xy / clip.w;
        if any(abs(ndc) > vec2<f32>(1.0)) {
            continue;
        }
        let texel = texel_of(vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5));
        let o = textureLoad(d_o, texel, 0).x;
        count_work(1.0);
        // The ray point's distance, less the shadow test's bias.
        let r = length(y - c) * (1.0 - rel_bias);
        if history < 0.0 {
            // The first sample in the map: behind the surface there is a hit.
            history = o;
            history_time = time2;
            if r > o {
                hit = true;
                break;
            }
        } else {
            let tolerance = abs(r - previous) * 1.05;
            // Far behind what the map holds here: a nearer surface jumped in (a gap).
            let behind = r - o > tolerance;
            var compared = o;
            if behind {
                compared = select(history, history + slope * (time2 - history_time), extrapolate);
            } else if o != history {
                let dt = time2 - history_time;
                // The extrapolation's slope at most MAX_SLOPE of the ray's length a unit of time
                // (UE5's ExtrapolateMaxSlopeLocal is 0.3, in its own depth units).
                let max_slope = MAX_SLOPE * length_along;
                slope = clamp((o - history) / select(dt, -1e-6, abs(dt) < 1e-6), -max_slope, max_slope);
                history = o;
                history_time = time2;
            }
            // Crossed behind the compared surface within this step.
            let behind_by = r - compared;
            if behind_by > 0.0 && behind_by < tolerance {
                hit = true;
                break;
            }
        }
        previous = r;
    }
    return hit;
}

// 1 where the ray from x to the light point of u arrives, 0 where the map stops it or the
// point is behind the receiver's own plane.
fn ray_lit(x: vec3<f32>, n: vec3<f32>, u: vec2<f32>, rel_bias: f32, offset: f32) -> u32 {
    let q = light_point(u);
    if !(dot(n, q - x) > 0.0) {
        return 0u;
    }
    return select(1u, 0u, ray_hits(x, q, rel_bias, offset));
}

fn smrt(x: vec3<f32>, n: vec3<f32>, l: LightLookup, pixel: vec2<f32>) -> f32 {
    let rays = max(u32(shadow.knobs.x), 1u);
    let adaptive = (u32(shadow.knobs.z) & FLAG_ADAPTIVE) != 0u;
    let rotation = vec2<f32>(pixel_noise(pixel, 0.0), pixel_noise(pixel, 1.0));
    let offset = pixel_noise(pixel, 2.0);
    // Adaptive ray count: two rays toward opposite halves of the light first; if they agree,
    // the pixel is taken as fully lit or fully shadowed, else every ray is traced.
    if adaptive && rays > 2u {
        let first = ray_lit(x, n, rotation, l.rel_bias, offset);
        let second = ray_lit(x, n, fract(rotation + vec2<f32>(0.5)), l.rel_bias, offset);
        if first == second {
            took_path(1.0);
            return f32(first);
        }
    }
    took_path(2.0);
    var lit = 0u;
    for (var i = 0u; i < rays; i++) {
        // A Fibonacci lattice over the unit square, rotated per pixel: stratified in both
        // coordinates for any count.
        let u = fract(vec2<f32>((f32(i) + 0.5) / f32(rays), f32(i) * 0.618033989) + rotation);
        lit += ray_lit(x, n, u, l.rel_bias, offset);
    }
    return f32(lit) / f32(rays);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(smrt(x, n, l, pixel));
}
