// The moment map's summed-area table (render::passes::moment_sat; the arithmetic's CPU twin is
// geometry::moments): per texel of the centre's shadow map its depth — its height above the
// light's plane — normalized to [0, 1] between the scene's lowest and highest (1 where no
// surface is), the four
// power moments through the optimized quantization (Peters & Klein 2015) in fixed point, and
// their running sums — along each row, then down each column. Sums are u32 and wrap: a box's
// sum, four corners of the table, is exact modulo 2³² and the fixed point leaves room for the
// largest box (JCGT 2017's integer tables).

struct SatUniforms {
    // The light view's clip space back to the world, the light's centre, and its unit normal
    // (zero for a line light): a texel's depth is its height above the light's plane, its
    // distance times the cosine of its ray with the normal (a line light's: the distance).
    inv_light_view_proj: mat4x4<f32>,
    light_center: vec4<f32>,
    light_normal: vec4<f32>,
    size: u32,
    // One moment's fixed-point scale.
    scale: f32,
    _pad0: f32,
    _pad1: f32,
};

@group(0) @binding(0) var<uniform> sat_in: SatUniforms;
@group(0) @binding(1) var distance_map: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> table: array<vec4<u32>>;
// The nearest and farthest surface's |cx_o|, as the bits of positive floats (which order as
// the floats do); reset to (f32 max, 0) before cs_range.
@group(0) @binding(3) var<storage, read_write> range: array<atomic<u32>, 2>;

// Distances at or beyond this are "no surface" (the map's 3e38).
const NO_SURFACE = 1e30;

// One invocation per row: the row's nearest and farthest surface into `range`.
@compute @workgroup_size(64)
fn cs_range(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = id.x;
    let size = sat_in.size;
    if y >= size {
        return;
    }
    var lo = 3.4e38;
    var hi = 0.0;
    for (var x = 0u; x < size; x++) {
        let d = texel_depth(vec2<u32>(x, y));
        if d > 0.0 && d < NO_SURFACE {
            lo = min(lo, d);
            hi = max(hi, d);
        }
    }
    atomicMin(&range[0], bitcast<u32>(lo));
    atomicMax(&range[1], bitcast<u32>(hi));
}

// The normalization of cs_range's bounds: z = (d − min) / (max − min), a little margin each side.
fn depth_range() -> vec2<f32> {
    let lo = bitcast<f32>(atomicLoad(&range[0]));
    let hi = bitcast<f32>(atomicLoad(&range[1]));
    if !(lo <= hi) {
        return vec2<f32>(0.0, 1.0);
    }
    let z_min = lo * 0.999;
    return vec2<f32>(z_min, 1.0 / max(hi * 1.001 - z_min, 1e-4));
}

const ENCODE = mat4x4<f32>(
    -2.07224649, 13.7948857237, 0.105877704, 9.7924062118,
    32.23703778, -59.4683975703, -1.9077466311, -33.7652110555,
    -68.571074599, 82.0359750338, 9.3496555107, 47.9456096605,
    39.3703274134, -35.364903257, -6.6543490743, -23.9728048165,
);

// The texel's depth: its height above the light's plane (a plane parallel to the light is one
// depth over any box, as a receiver-plane bias makes it for a per-tap test), or for a line light
// its distance; NO_SURFACE's own where it holds none.
fn texel_depth(at: vec2<u32>) -> f32 {
    let d = textureLoad(distance_map, vec2<i32>(at), 0).x;
    if !(d < NO_SURFACE) || dot(sat_in.light_normal.xyz, sat_in.light_normal.xyz) == 0.0 {
        return d;
    }
    let uv = (vec2<f32>(at) + 0.5) / f32(sat_in.size);
    let p = sat_in.inv_light_view_proj * vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
    return d * max(dot(normalize(p.xyz / p.w - sat_in.light_center.xyz), sat_in.light_normal.xyz), 0.0);
}

fn texel_moments(at: vec2<u32>, r: vec2<f32>) -> vec4<u32> {
    let d = texel_depth(at);
    let z = clamp((d - r.x) * r.y, 0.0, 1.0);
    let s = z * z;
    let optimized = ENCODE * vec4<f32>(z, s, s * z, s * s) + vec4<f32>(0.035955884801, 0.0, 0.0, 0.0);
    return vec4<u32>(round(clamp(optimized, vec4<f32>(0.0), vec4<f32>(1.0)) * sat_in.scale));
}

// One invocation per row: the running sums of its texels' moments.
@compute @workgroup_size(64)
fn cs_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = id.x;
    let size = sat_in.size;
    if y >= size {
        return;
    }
    let r = depth_range();
    var sum = vec4<u32>(0u);
    for (var x = 0u; x < size; x++) {
        sum += texel_moments(vec2<u32>(x, y), r);
        table[y * size + x] = sum;
    }
}

// One invocation per column: the running sums of the rows' sums.
@compute @workgroup_size(64)
fn cs_columns(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let size = sat_in.size;
    if x >= size {
        return;
    }
    var sum = vec4<u32>(0u);
    for (var y = 0u; y < size; y++) {
        let i = y * size + x;
        sum += table[i];
        table[i] = sum;
    }
}
