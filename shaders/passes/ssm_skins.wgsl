// `linear-ssm`'s skins (Heidrich et al. 2000, §3.2; CPU twin geometry::ssm::skins) from one sample's distance
// map, in four dispatches:
//   `find`    every 2x2 cell of texel centres: a cell whose four distances are discontinuous
//             (the largest beyond the smallest times 1 + tau, or surface beside no surface) is
//             appended to the cell list;
//   `size_extract`  the dispatch size of `extract` from the list's length;
//   `extract` each listed cell is split at the largest gap of its sorted distances into near
//             corners (the occluder, value 0) and far ones (the receiver, value 1); each of its two
//             triangles (diagonal from its first to its last corner) with both kinds of corner is
//             a skin, appended to the skin buffer;
//   `finish`  the indirect draw arguments, clamped to the skin buffer's capacity.
// Finding the few discontinuous cells apart from triangulating them keeps the pass cheap on a CPU
// adapter, which runs every lane through all of a shader's code.
// #include shared/ssm_sample.wgsl

@group(0) @binding(0) var<uniform> sample: SsmSample;
// The sample's distance map, copied row by row (`pitch` floats a row): a CPU adapter loads from a
// buffer many times faster than from a texture.
@group(0) @binding(1) var<storage, read> map: array<f32>;
@group(0) @binding(2) var<storage, read_write> skins: array<SkinVertex>;
// [0]: skin triangles appended, [1]: cells listed.
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>, 2>;
// The skins' draw_indirect arguments.
@group(0) @binding(4) var<storage, read_write> args: array<u32, 4>;
@group(0) @binding(5) var<storage, read_write> cells: array<u32>;
// extract's dispatch_workgroups_indirect arguments (a group of their own: `extract` is dispatched
// from this buffer, which its own bindings must not hold).
@group(1) @binding(0) var<storage, read_write> dispatch: array<u32, 3>;

// Threads a workgroup of `extract`.
const EXTRACT_GROUP: u32 = 64u;

fn distance_at(x: u32, y: u32) -> f32 {
    return map[y * sample.pitch + x];
}

fn discontinuous(d: vec4<f32>) -> bool {
    let has = d < vec4<f32>(SSM_NO_SURFACE_AT);
    let lo = min(min(d.x, d.y), min(d.z, d.w));
    let hi = max(max(d.x, d.y), max(d.z, d.w));
    return any(has) && !(all(has) && hi <= lo * (1.0 + sample.tau));
}

fn list(x: u32, y: u32, d: vec4<f32>) {
    if discontinuous(d) {
        let i = atomicAdd(&counts[1], 1u);
        if i < arrayLength(&cells) {
            cells[i] = y * sample.size + x;
        }
    }
}

// One invocation per 2x2 block of cells: its 3x3 texels are loaded once.
@compute @workgroup_size(8, 8)
fn find(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = sample.size;
    let x = id.x * 2u;
    let y = id.y * 2u;
    if x + 1u >= size || y + 1u >= size {
        return;
    }
    let x2 = min(x + 2u, size - 1u);
    let y2 = min(y + 2u, size - 1u);
    let r0 = vec3<f32>(distance_at(x, y), distance_at(x + 1u, y), distance_at(x2, y));
    let r1 = vec3<f32>(distance_at(x, y + 1u), distance_at(x + 1u, y + 1u), distance_at(x2, y + 1u));
    let r2 = vec3<f32>(distance_at(x, y2), distance_at(x + 1u, y2), distance_at(x2, y2));
    list(x, y, vec4<f32>(r0.x, r0.y, r1.x, r1.y));
    if x + 2u < size {
        list(x + 1u, y, vec4<f32>(r0.y, r0.z, r1.y, r1.z));
    }
    if y + 2u < size {
        list(x, y + 1u, vec4<f32>(r1.x, r1.y, r2.x, r2.y));
        if x + 2u < size {
            list(x + 1u, y + 1u, vec4<f32>(r1.y, r1.z, r2.y, r2.z));
        }
    }
}

@compute @workgroup_size(1)
fn size_extract() {
    let n = min(atomicLoad(&counts[1]), arrayLength(&cells));
    dispatch[0] = (n + EXTRACT_GROUP - 1u) / EXTRACT_GROUP;
    dispatch[1] = 1u;
    dispatch[2] = 1u;
}

fn texel_point(x: u32, y: u32, d: f32) -> vec3<f32> {
    let s = f32(sample.size);
    let ndc = vec2<f32>((f32(x) + 0.5) / s * 2.0 - 1.0, 1.0 - (f32(y) + 0.5) / s * 2.0);
    let p = sample.inv_view_proj * vec4<f32>(ndc, 0.5, 1.0);
    let dir = normalize(p.xyz / p.w - sample.point);
    return sample.point + dir * d;
}

fn corner(x: u32, y: u32, i: u32, d: f32, near: bool, cell: u32) -> SkinVertex {
    var v: SkinVertex;
    let dist = select(sample.far, d, d < SSM_NO_SURFACE_AT);
    v.position = texel_point(x + (i & 1u), y + (i >> 1u), dist);
    v.value = select(1.0, 0.0, near);
    v.cell = cell;
    v.corner = i;
    return v;
}

@compute @workgroup_size(64)
fn extract(@builtin(global_invocation_id) id: vec3<u32>) {
    let listed = min(atomicLoad(&counts[1]), arrayLength(&cells));
    if id.x >= listed {
        return;
    }
    let cell = cells[id.x];
    let size = sample.size;
    let x = cell % size;
    let y = cell / size;
    // Corners in the twin's order: (x, y), (x+1, y), (x, y+1), (x+1, y+1).
    let d = vec4<f32>(
        distance_at(x, y),
        distance_at(x + 1u, y),
        distance_at(x, y + 1u),
        distance_at(x + 1u, y + 1u)
    );
    let has = d < vec4<f32>(SSM_NO_SURFACE_AT);
    // Sorted, no surface last (its stand-in is larger than any distance): a sorting network.
    var s = select(vec4<f32>(3.0e38), d, has);
    s = vec4<f32>(min(s.x, s.y), max(s.x, s.y), min(s.z, s.w), max(s.z, s.w));
    s = vec4<f32>(min(s.x, s.z), min(s.y, s.w), max(s.x, s.z), max(s.y, s.w));
    s = vec4<f32>(s.x, min(s.y, s.z), max(s.y, s.z), s.w);
    // The widest step (a step onto no surface is wider than any other, as the twin's infinity).
    var steps = vec3<f32>(s.y - s.x, s.z - s.y, s.w - s.z);
    let onto_nothing = vec3<f32>(s.y, s.z, s.w) >= vec3<f32>(SSM_NO_SURFACE_AT)
        & vec3<f32>(s.x, s.y, s.z) < vec3<f32>(SSM_NO_SURFACE_AT);
    steps = select(steps, vec3<f32>(3.0e38), onto_nothing);
    var limit = s.x;
    var widest = steps.x;
    if steps.y > widest {
        widest = steps.y;
        limit = s.y;
    }
    if steps.z > widest {
        limit = s.z;
    }
    let near = has & (d <= vec4<f32>(limit));
    // geometry::ssm::CELL_TRIANGLES: (0, 3, 1) and (0, 2, 3).
    let k0 = u32(near.x) + u32(near.w) + u32(near.y);
    let k1 = u32(near.x) + u32(near.z) + u32(near.w);
    let emit0 = k0 == 1u || k0 == 2u;
    let emit1 = k1 == 1u || k1 == 2u;
    let n = u32(emit0) + u32(emit1);
    if n == 0u {
        return;
    }
    let base = atomicAdd(&counts[0], n);
    if base + n > sample.capacity {
        return;
    }
    let c0 = corner(x, y, 0u, d.x, near.x, cell);
    let c1 = corner(x, y, 1u, d.y, near.y, cell);
    let c2 = corner(x, y, 2u, d.z, near.z, cell);
    let c3 = corner(x, y, 3u, d.w, near.w, cell);
    var slot = base * 3u;
    if emit0 {
        skins[slot] = c0;
        skins[slot + 1u] = c3;
        skins[slot + 2u] = c1;
        slot += 3u;
    }
    if emit1 {
        skins[slot] = c0;
        skins[slot + 1u] = c2;
        skins[slot + 2u] = c3;
    }
}

@compute @workgroup_size(1)
fn finish() {
    let n = min(atomicLoad(&counts[0]), sample.capacity);
    args[0] = n * 3u;
    args[1] = 1u;
    args[2] = 0u;
    args[3] = 0u;
}
