// The probe (src/render/passes/probe.rs): what the lab reads back of a frame instead of the
// frame. PROBE_PIXEL: every value under the cursor — colour, V, t + 2·branch, depth, the world
// position, the reference V, the method's cost (work, path), and the three light-map texels
// under that position (or under the cursor in the light-maps view) — PIXEL_FLOATS floats. PROBE_FIT: the shown scalar at samples on
// a grid, for the display range's auto-fit (NaN where there is none). PROBE_MOTION: V at the
// same grid's pixels whatever the view (NaN where no surface), for the lab's motion meter.
// PROBE_COUNT: the pixels whose V or t is out of range (range_flag), counted by each of the
// dispatch's workgroups over every COUNT_GROUPS·64-th pixel, one count a workgroup.
// #include shared/view_inputs.wgsl

const PROBE_PIXEL: u32 = 0u;
const PROBE_FIT: u32 = 1u;
const PROBE_MOTION: u32 = 2u;
const PROBE_COUNT: u32 = 3u;
const PIXEL_FLOATS: u32 = 28u;
const NAN_BITS: u32 = 0x7fc00000u;

@group(1) @binding(0) var<storage, read_write> out: array<f32>;

fn nan() -> f32 {
    return bitcast<f32>(NAN_BITS);
}

fn put_texels(base: u32, q: vec2<i32>) {
    for (var t = 0u; t < 3u; t++) {
        let v = map_texel(t, q);
        for (var c = 0u; c < 4u; c++) {
            out[base + 4u * t + c] = v[c];
        }
    }
}

fn map_size_i() -> i32 {
    return i32(view.map_size);
}

// The light-map texel under world point x, or (-1, -1) outside the maps.
fn texel_under(x: vec3<f32>) -> vec2<i32> {
    let clip = view.map_view_proj * vec4<f32>(x, 1.0);
    if !(clip.w > 0.0) || view.map_size < 1.0 {
        return vec2<i32>(-1);
    }
    let ndc = clip.xy / clip.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let n = view.map_size;
    let t = clamp(floor(uv * n), vec2<f32>(0.0), vec2<f32>(n - 1.0));
    return vec2<i32>(t);
}

fn probe_pixel() {
    let p = vec2<i32>(view.probe.xy);
    for (var i = 0u; i < PIXEL_FLOATS; i++) {
        out[i] = nan();
    }
    if view.kind == VIEW_LIGHT_MAPS {
        out[14] = f32(p.x);
        out[15] = f32(p.y);
        if p.x < map_size_i() && p.y < map_size_i() {
            put_texels(16u, p);
        }
        return;
    }
    let size = vec2<i32>(textureDimensions(data));
    if any(p >= size) {
        return;
    }
    let c = textureLoad(color_bytes, p, 0);
    out[0] = c.r;
    out[1] = c.g;
    out[2] = c.b;
    out[3] = c.a;
    let d = textureLoad(data, p, 0);
    out[4] = d.x;
    out[5] = d.y;
    let z = textureLoad(depth, p, 0).r;
    out[6] = z;
    out[7] = select(0.0, 1.0, z > 0.0);
    if view.has_reference != 0u {
        out[8] = textureLoad(reference_v, p, 0).x;
    }
    let work = textureLoad(cost, p, 0).xy;
    out[12] = work.x;
    out[13] = work.y;
    if z > 0.0 {
        let dims = vec2<f32>(size);
        let ndc = vec2<f32>((f32(p.x) + 0.5) / dims.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) / dims.y * 2.0);
        let w = view.inv_view_proj * vec4<f32>(ndc, z, 1.0);
        let x = w.xyz / w.w;
        out[9] = x.x;
        out[10] = x.y;
        out[11] = x.z;
        let q = texel_under(x);
        if q.x >= 0 {
            out[14] = f32(q.x);
            out[15] = f32(q.y);
            put_texels(16u, q);
        }
    }
}

// V at the pixel of grid sample i (probe.rs's grid_pixel), NaN where no surface.
fn motion_value(i: u32, grid: u32) -> f32 {
    let dims = vec2<f32>(textureDimensions(data));
    let p = vec2<i32>(vec2<f32>((f32(i % grid) + 0.5) / f32(grid) * dims.x, (f32(i / grid) + 0.5) / f32(grid) * dims.y));
    if !is_hit(p) {
        return nan();
    }
    return textureLoad(data, p, 0).x;
}

// The value the fit sees at grid sample i.
fn fit_value(i: u32, grid: u32) -> f32 {
    let gx = i % grid;
    let gy = i / grid;
    if view.kind == VIEW_LIGHT_MAPS {
        let n = view.map_size;
        let q = vec2<i32>(vec2<f32>((f32(gx) + 0.5) / f32(grid) * n, (f32(gy) + 0.5) / f32(grid) * n));
        let mask = view.channel_mask & ((1u << view.channel_count) - 1u);
        let shown = countOneBits(mask);
        if shown == 0u {
            return nan();
        }
        // Sample i looks at the (i mod shown)-th shown channel.
        var k = i % shown;
        var c = 0u;
        for (var j = 0u; j < 4u; j++) {
            if (mask & (1u << j)) != 0u {
                if k == 0u {
                    c = j;
                    break;
                }
                k -= 1u;
            }
        }
        let v = channel_at(c, q);
        return select(nan(), v.value, v.valid);
    }
    let dims = vec2<f32>(textureDimensions(data));
    let p = vec2<i32>(vec2<f32>((f32(gx) + 0.5) / f32(grid) * dims.x, (f32(gy) + 0.5) / f32(grid) * dims.y));
    if !is_hit(p) {
        return nan();
    }
    let d = textureLoad(data, p, 0).xy;
    switch view.kind {
        case VIEW_VISIBILITY: { return d.x; }
        case VIEW_T: { return d.y - 2.0 * branch_of(d.y); }
        case VIEW_ERROR: {
            if view.has_reference == 0u {
                return nan();
            }
            return abs(d.x - textureLoad(reference_v, p, 0).x);
        }
        case VIEW_COST: { return textureLoad(cost, p, 0).x; }
        default: { return nan(); }
    }
}

// The workgroup's count of out-of-range pixels (PROBE_COUNT).
var<workgroup> range_count: atomic<u32>;

// Workgroup `group` of `groups` counts the out-of-range pixels among every (groups · 64)-th,
// starting at its own, and writes its count to out[group].
fn count_out_of_range(local: u32, group: u32, groups: u32) {
    if local == 0u {
        atomicStore(&range_count, 0u);
    }
    workgroupBarrier();
    let size = textureDimensions(data);
    let n = size.x * size.y;
    var mine = 0u;
    for (var i = group * 64u + local; i < n; i += groups * 64u) {
        if range_flag(vec2<i32>(vec2<u32>(i % size.x, i / size.x))) {
            mine += 1u;
        }
    }
    atomicAdd(&range_count, mine);
    workgroupBarrier();
    if local == 0u {
        out[group] = f32(atomicLoad(&range_count));
    }
}

@compute @workgroup_size(64)
fn cs_main(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if view.probe.z == PROBE_COUNT {
        count_out_of_range(local, group.x, groups.x);
        return;
    }
    if view.probe.z == PROBE_PIXEL {
        if id.x == 0u {
            probe_pixel();
        }
        return;
    }
    let grid = max(view.probe.w, 1u);
    if id.x < grid * grid {
        if view.probe.z == PROBE_MOTION {
            out[id.x] = motion_value(id.x, grid);
        } else {
            out[id.x] = fit_value(id.x, grid);
        }
    }
}
