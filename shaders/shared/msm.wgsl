// Reading the moment map's summed-area table (render::passes::moment_sat) from the camera pass,
// for `msm` and `msm-soft`; the arithmetic's CPU twin, with its tests: geometry::moments.
// Include after shared/camera.wgsl and shared/shadow_lookup.wgsl; group 1 binds the table at 3
// and the depth range at 4 (the method's params at 2).

@group(1) @binding(3) var<storage, read> table: array<vec4<u32>>;
@group(1) @binding(4) var<storage, read> range: array<u32, 2>;

// geometry::moments::MAX_RADIUS and SAT_SCALE.
const MSM_MAX_RADIUS = 128;
const MSM_SCALE = 65026.0;

const DECODE = mat4x4<f32>(
    0.2227744146, 0.1549679261, 0.1451988946, 0.163127443,
    0.0771972861, 0.1394629426, 0.2120202157, 0.2591432266,
    0.7926986636, 0.7963415838, 0.7258694464, 0.6539092497,
    0.0319417555, -0.1722823173, -0.2758014811, -0.3376131734,
);

// The point's depth (moment_depth) as the table's normalized depth.
fn msm_depth(d: f32) -> f32 {
    let lo = bitcast<f32>(range[0]);
    let hi = bitcast<f32>(range[1]);
    if !(lo <= hi) {
        return clamp(d, 0.0, 1.0);
    }
    let z_min = lo * 0.999;
    return clamp((d - z_min) / max(hi * 1.001 - z_min, 1e-4), 0.0, 1.0);
}

// The normalized depth back to a distance from c.
fn msm_distance(z: f32) -> f32 {
    let lo = bitcast<f32>(range[0]);
    let hi = bitcast<f32>(range[1]);
    if !(lo <= hi) {
        return z;
    }
    let z_min = lo * 0.999;
    return z_min + z * max(hi * 1.001 - z_min, 1e-4);
}

// The inclusive prefix sum up to texel q (0 left of or above the map).
fn table_at(q: vec2<i32>) -> vec4<u32> {
    let size = i32(shadow.size);
    let i = u32(clamp(q.y, 0, size - 1) * size + clamp(q.x, 0, size - 1));
    // Every read of the table is a unit of the cost view (shared/camera.wgsl).
    count_work(1.0);
    return select(vec4<u32>(0u), table[i], q.x >= 0 && q.y >= 0);
}

// The summed moments of the box of texels centre ± half, clipped to the map, and its texel count.
struct BoxSum {
    sum: vec4<f32>,
    count: i32,
};

// The table holds any box up to SAT_SIDE texels a side exactly.
const SAT_SIDE: i32 = 2 * MSM_MAX_RADIUS + 1;

fn box_sum(centre: vec2<i32>, half: vec2<i32>) -> BoxSum {
    let last = vec2<i32>(i32(shadow.size) - 1);
    let lo = clamp(centre - half, vec2<i32>(0), last);
    let hi = clamp(centre + half, vec2<i32>(0), last);
    // Wrapping u32 arithmetic: a box's four corners give its sum exactly as long as its true sum
    // fits (the fixed point's room, geometry::moments::SAT_SCALE: SAT_SIDE² texels), so a wider
    // box is summed in pieces that fit, added as floats (a penumbra wider than the table's room:
    // `no-umbra`'s needs 250 texels).
    let pieces = (hi - lo + SAT_SIDE) / SAT_SIDE;
    var sum = vec4<f32>(0.0);
    for (var py = 0; py < pieces.y; py++) {
        for (var px = 0; px < pieces.x; px++) {
            let a = lo + vec2<i32>(px, py) * SAT_SIDE;
            let b = min(a + SAT_SIDE - 1, hi);
            let s = table_at(b) - table_at(vec2<i32>(a.x - 1, b.y)) - table_at(vec2<i32>(b.x, a.y - 1))
                + table_at(a - vec2<i32>(1));
            sum += vec4<f32>(s);
        }
    }
    return BoxSum(sum, (hi.x - lo.x + 1) * (hi.y - lo.y + 1));
}

// Summed moments back to mean power moments.
fn mean_moments(b: BoxSum) -> vec4<f32> {
    let optimized = b.sum / (f32(max(b.count, 1)) * MSM_SCALE)
        - vec4<f32>(0.035955884801, 0.0, 0.0, 0.0);
    return DECODE * optimized;
}

// The mean power moments of the box centre ± r.
fn box_moments(centre: vec2<i32>, r: vec2<i32>) -> vec4<f32> {
    return mean_moments(box_sum(centre, r));
}

// The mean power moments of a cross, centre ± (r.x, r.y/2) and ± (r.x/2, r.y): three boxes of the
// table that come closer to a disk of radius r than the square does (area 3r², corners at
// 1.12r), so a disk light's penumbra is not drawn as a square's.
fn cross_moments(centre: vec2<i32>, r: vec2<i32>) -> vec4<f32> {
    let h = r / 2;
    let a = box_sum(centre, vec2<i32>(r.x, h.y));
    let b = box_sum(centre, vec2<i32>(h.x, r.y));
    let c = box_sum(centre, h);
    return mean_moments(BoxSum(a.sum + b.sum - c.sum, a.count + b.count - c.count));
}

// What a region's moments say at a receiver depth (geometry::moments::Hamburger): x the share
// strictly in front of z_f (the shadow intensity), y the mean depth of that share.
fn hamburger(moments: vec4<f32>, z_f: f32, moment_bias: f32) -> vec2<f32> {
    let b = mix(moments, vec4<f32>(0.5), moment_bias);
    let l32_d22 = -b.x * b.y + b.z;
    let d22 = max(-b.x * b.x + b.y, 1e-12);
    let squared_variance = -b.y * b.y + b.w;
    let d33_d22 = max(squared_variance * d22 - l32_d22 * l32_d22, 1e-18);
    let l32 = l32_d22 / d22;
    var c = vec3<f32>(1.0, z_f, z_f * z_f);
    c.y -= b.x;
    c.z -= b.y + l32 * c.y;
    c.y /= d22;
    c.z *= d22 / d33_d22;
    c.y -= l32 * c.z;
    c.x -= c.y * b.x + c.z * b.y;
    let p = c.y / c.z;
    let q = c.x / c.z;
    let r = sqrt(max(p * p * 0.25 - q, 0.0));
    let z1 = -p * 0.5 - r;
    let z2 = -p * 0.5 + r;
    let den1 = (z1 - z_f) * (z1 - z2);
    let den2 = (z2 - z_f) * (z2 - z1);
    let w1 = select(0.0, (b.y - (z_f + z2) * b.x + z_f * z2) / den1, abs(den1) >= 1e-12);
    let w2 = select(0.0, (b.y - (z_f + z1) * b.x + z_f * z1) / den2, abs(den2) >= 1e-12);
    let f1 = select(0.0, w1, z1 < z_f);
    let f2 = select(0.0, w2, z2 < z_f);
    let in_front = clamp(f1 + f2, 0.0, 1.0);
    let blocker = select(z_f, clamp((f1 * z1 + f2 * z2) / max(in_front, 1e-6), 0.0, z_f), in_front > 1e-6);
    return vec2<f32>(in_front, blocker);
}

// The relative bias a box of half-width r texels needs on a receiver tilted as `l` says: the
// receiver's own depth changes by one texel's slope-scaled bias a texel. It grows with the box
// up to 4 texels' worth and no further: a wider box on a tilted receiver then shadows itself a
// little at its far side, where a bias grown with it would push the receiver in front of a
// caster just above it and leak (leak-test: twice the lit umbra; penumbra MAE lower or equal on
// 13 of 14 scored scenes, docs/method/README.md).
fn box_bias(l: LightLookup, r: f32) -> f32 {
    return shadow.bias_constant + (l.rel_bias - shadow.bias_constant) * (min(r, 4.0) + 1.0);
}

// The table's depth of the point x (render::passes::moment_sat's texel_depth): its height above
// the light's plane, or for a line light its distance from c.
fn moment_depth(x: vec3<f32>, l: LightLookup) -> f32 {
    if camera.light_kind == LIGHT_LINE {
        return l.d;
    }
    return dot(x - camera.light_center, camera.light_normal);
}

// V of a filter of half-widths r texels along the map's two axes (fractional: between the two
// nearest integers) about the point's texel, at the point's depth `depth` (moment_depth): a box
// (`msm`; `msm-soft` under a rectangle or polygon) or the cross (`msm-soft` under a disk).
fn msm_lit(l: LightLookup, depth: f32, r: vec2<f32>, moment_bias: f32, cross: bool) -> f32 {
    let r0 = floor(r);
    let t = 0.5 * (r.x - r0.x + r.y - r0.y);
    let z_f = msm_depth(depth * (1.0 - box_bias(l, max(r.x, r.y))));
    let r0i = vec2<i32>(r0);
    var m0 = box_moments(l.texel, r0i);
    var m1 = box_moments(l.texel, r0i + 1);
    if cross {
        m0 = cross_moments(l.texel, r0i);
        m1 = cross_moments(l.texel, r0i + 1);
    }
    let a = hamburger(m0, z_f, moment_bias).x;
    let b = hamburger(m1, z_f, moment_bias).x;
    return 1.0 - mix(a, b, t);
}
