// What `bitmask` reads of the centre's shadow map besides |cx_o| (render::passes::micro_patches),
// in Rgba32Float draws of one full-screen triangle:
// - mode 0, the patch corners: per texel the distance at each of its corners (x: the texel's
//   (0, 0) corner, y: (1, 0), z: (1, 1), w: (0, 1), in texel coordinates), the mean of the texels
//   meeting there within CONTINUITY of the texel's own (geometry::bitmask::corner_distance; the
//   gap filling), or the texel's own everywhere where gap filling is off;
// - mode 1, the pyramid's first level: per 2×2 texels of the map the lowest height above the
//   light's plane and the nearest distance from c (x, y), the largest bend of the texels' distances across them and
//   the texels right of and below them (z: over CONTINUITY, the node holds a step from one
//   surface to another), and the farthest distance (w);
// - mode 2, a further level: per 2×2 texels of the level below, the same.
// The levels are squares side by side in two atlases (even levels in one, odd in the other; each
// drawn from the other), drawn with a viewport on their square.
// Texels beyond the map (the pyramid's first level is a power of two) count as no surface.
// #include shared/fullscreen_vs.wgsl

struct PatchUniforms {
    // The light view's clip space back to the world.
    inv_light_view_proj: mat4x4<f32>,
    // The light's centre c, and its unit normal (toward the side it emits to): a texel's height
    // is its distance times the cosine of its ray with the normal.
    light_center: vec4<f32>,
    light_normal: vec4<f32>,
    mode: u32,
    // 1: the corners are gap-filled.
    gap_fill: u32,
    // The map's (or the level below's) texels per side.
    size: u32,
    // Where the level below (mode 2) and the level drawn (modes 1, 2) start in their atlases
    // (x, in texels; render::passes::micro_patches::level_offset).
    source_offset: u32,
    target_offset: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
};

// geometry::bitmask::CONTINUITY.
const CONTINUITY: f32 = 0.03;
// render::passes::shadow_map::NO_SURFACE.
const NO_SURFACE: f32 = 3.0e38;

@group(0) @binding(0) var<uniform> patches: PatchUniforms;
@group(0) @binding(1) var source: texture_2d<f32>;

fn distance_at(q: vec2<i32>) -> f32 {
    let size = i32(patches.size);
    if any(q < vec2<i32>(0)) || any(q >= vec2<i32>(size)) {
        return NO_SURFACE;
    }
    return textureLoad(source, q, 0).x;
}

// The distance at the corner `corner` (0 or 1 each way) of texel `at` whose own is `own`.
fn corner(at: vec2<i32>, own: f32, corner: vec2<i32>) -> f32 {
    var sum = 0.0;
    var n = 0.0;
    for (var dy = -1; dy <= 0; dy++) {
        for (var dx = -1; dx <= 0; dx++) {
            let o = distance_at(at + corner + vec2<i32>(dx, dy));
            if abs(o - own) <= CONTINUITY * own {
                sum += o;
                n += 1.0;
            }
        }
    }
    return select(own, sum / n, n > 0.0);
}

@fragment
fn fs_main(in: FullscreenVertex) -> @location(0) vec4<f32> {
    let at = vec2<i32>(in.position.xy) - vec2<i32>(i32(patches.target_offset), 0);
    if patches.mode == 0u {
        let own = distance_at(at);
        if patches.gap_fill == 0u || own >= NO_SURFACE {
            return vec4<f32>(own);
        }
        return vec4<f32>(
            corner(at, own, vec2<i32>(0, 0)),
            corner(at, own, vec2<i32>(1, 0)),
            corner(at, own, vec2<i32>(1, 1)),
            corner(at, own, vec2<i32>(0, 1)),
        );
    }
    var low = NO_SURFACE;
    var nearest = NO_SURFACE;
    var jump = 0.0;
    var farthest = 0.0;
    var any_texel = false;
    if patches.mode == 1u {
        // The node's 2×2 texels and those right of and below them (so that a level above sees
        // every pair of neighbours inside it).
        var d: array<f32, 9>;
        for (var k = 0; k < 9; k++) {
            d[k] = distance_at(2 * at + vec2<i32>(k % 3, k / 3));
        }
        for (var k = 0; k < 4; k++) {
            let q = vec2<i32>(k % 2, k / 2);
            let own = d[q.y * 3 + q.x];
            if any(2 * at + q >= vec2<i32>(i32(patches.size))) || own >= NO_SURFACE {
                continue;
            }
            low = min(low, own * cosine_to_normal(2 * at + q));
            nearest = min(nearest, own);
            farthest = max(farthest, own);
            any_texel = true;
        }
        // The bend of the surface across the middle row and column of the block: a step
        // between any two neighbours of the node (or to those right of and below it) shows there.
        for (var k = 0; k < 3; k++) {
            jump = max(jump, bend(d[k * 3], d[k * 3 + 1], d[k * 3 + 2]));
            jump = max(jump, bend(d[k], d[3 + k], d[6 + k]));
        }
    } else {
        for (var k = 0; k < 4; k++) {
            let q = 2 * at + vec2<i32>(k % 2, k / 2);
            if any(q >= vec2<i32>(i32(patches.size))) {
                continue;
            }
            let texel = textureLoad(source, q + vec2<i32>(i32(patches.source_offset), 0), 0);
            if texel.x >= NO_SURFACE {
                continue;
            }
            low = min(low, texel.x);
            nearest = min(nearest, texel.y);
            jump = max(jump, texel.z);
            farthest = max(farthest, texel.w);
            any_texel = true;
        }
    }
    return select(vec4<f32>(NO_SURFACE, NO_SURFACE, 0.0, 0.0), vec4<f32>(low, nearest, jump, farthest), any_texel);
}

// The cosine between the ray from c through the centre of map texel t and the light's normal.
fn cosine_to_normal(t: vec2<i32>) -> f32 {
    let uv = (vec2<f32>(t) + 0.5) / f32(patches.size);
    let p = patches.inv_light_view_proj * vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
    return dot(normalize(p.xyz / p.w - patches.light_center.xyz), patches.light_normal.xyz);
}

// How far the middle of three neighbouring texels' distances lies off the line through the
// outer two, relative to the middle one: small on any smooth surface, however steep, and large
// across a step from one surface to another (or to no surface: larger than any).
fn bend(a: f32, b: f32, c: f32) -> f32 {
    let none = vec3<bool>(a >= NO_SURFACE, b >= NO_SURFACE, c >= NO_SURFACE);
    if any(none) {
        return select(1.0e30, 0.0, all(none));
    }
    return abs(a - 2.0 * b + c) / max(b, 1e-30);
}
