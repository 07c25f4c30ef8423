// `pcss`: percentage-closer soft shadows (Fernando 2005) for a disk of radius r seen from c, on
// the centre's shadow map (src/render/methods/pcss.rs): blockers are searched in the cone from x
// to the disk down to the nearest caster, and the filter spans the penumbra width their mean
// distance predicts. Sizes are slopes from c, over the slope one texel spans.
// #include shared/camera.wgsl
// #include shared/shadow_lookup.wgsl

// PcssParams of src/render/methods/pcss.rs.
struct PcssParams {
    blocker_taps: u32,
    filter_taps: u32,
    // The nearest caster's distance from c.
    nearest_caster: f32,
    _pad0: u32,
};

struct PoissonDisk {
    // 64 points in the unit disk, two per entry (xy, zw); every prefix is spread over the disk.
    points: array<vec4<f32>, 32>,
};

@group(1) @binding(2) var<uniform> params: PcssParams;
@group(1) @binding(3) var<uniform> disk: PoissonDisk;

fn poisson(i: u32) -> vec2<f32> {
    let e = disk.points[i / 2u];
    return select(e.zw, e.xy, i % 2u == 0u);
}

// A per-pixel rotation (interleaved gradient noise).
fn rotation(pixel: vec2<f32>) -> mat2x2<f32> {
    let a = 6.2831853 * interleaved_gradient_noise(pixel);
    let cs = cos(a);
    let sn = sin(a);
    return mat2x2<f32>(cs, sn, -sn, cs);
}

fn pcss(x: vec3<f32>, n: vec3<f32>, l: LightLookup, pixel: vec2<f32>) -> f32 {
    let r = camera.light_radius;
    let d = l.d;
    let near = max(params.nearest_caster, 1e-4);
    if d <= near {
        return 1.0;
    }
    let size = shadow.size;
    let centre = l.uv * size;
    let rot = rotation(pixel);
    let search = clamp(light_width_in_texels(r, d, near), 1.0, size * 0.5);
    var blockers = 0.0;
    var sum = 0.0;
    let blocker_taps = params.blocker_taps;
    for (var i = 0u; i < blocker_taps; i++) {
        let tap = vec2<i32>(floor(centre + rot * poisson(i) * search));
        let q = clamp(tap, vec2<i32>(0), vec2<i32>(i32(size) - 1));
        count_work(1.0);
        let o = textureLoad(d_o, q, 0).x;
        let expected = receiver_distance(q, x, n, d);
        if o + expected * l.rel_bias < expected {
            blockers += 1.0;
            sum += o;
        }
    }
    if blockers == 0.0 {
        took_path(1.0);
        return 1.0;
    }
    took_path(2.0);
    let blocker = sum / blockers;
    let width = clamp(light_width_in_texels(r, d, blocker), 1.0, size * 0.5);
    var lit = 0.0;
    let filter_taps = params.filter_taps;
    for (var i = 0u; i < filter_taps; i++) {
        let tap = vec2<i32>(floor(centre + rot * poisson(i) * width));
        count_work(1.0);
        lit += lit_at(tap, receiver_distance(tap, x, n, d), l.rel_bias);
    }
    return lit / f32(filter_taps);
}

fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility {
    if !in_front_of_light(x) || !faces_light_center(x, n) {
        return plain(0.0);
    }
    let l = light_lookup(x, n);
    if !l.inside {
        return plain(1.0);
    }
    return plain(pcss(x, n, l, pixel));
}
