// What the view pass and the probe read of a frame (src/render/passes/view.rs, probe.rs): the
// camera pass's targets, the reference V, and the shown method's light-space maps, with the
// uniforms that say how to show them. Both passes bind this same layout as group 0.
// #include shared/frame_tag.wgsl

struct ViewUniforms {
    // VIEW_* below.
    kind: u32,
    // Bit c set: light-map channel c is shown (the D-buffer view).
    channel_mask: u32,
    // COLORMAP_* below.
    colormap: u32,
    // 1 when the reference texture holds V of this frame's size.
    has_reference: u32,
    // The display range: black and white points.
    black: f32,
    white: f32,
    // The light maps are map_size × map_size texels.
    map_size: f32,
    // How many light-map channels there are (0 to 4).
    channel_count: u32,
    // Per channel: texture, component, EMPTY_*, fallback (NO_FALLBACK, or texture × 4 + component
    // of the value used where this one has none).
    channels: array<vec4<u32>, 4>,
    // Per light-map texture, the frame tag its live texels carry (0: read as stored;
    // shared/frame_tag.wgsl).
    tags: vec4<u32>,
    // World to clip of the camera, inverted (positions from the reversed depth).
    inv_view_proj: mat4x4<f32>,
    // World to clip of the light maps' view.
    map_view_proj: mat4x4<f32>,
    // The probe: the pixel (or texel, in the D-buffer view) it reads, PROBE_* mode, and for
    // FIT how many samples over a grid of grid × grid.
    probe: vec4<u32>,
};

const VIEW_FINAL: u32 = 0u;
const VIEW_VISIBILITY: u32 = 1u;
const VIEW_T: u32 = 2u;
const VIEW_CLASSES: u32 = 3u;
const VIEW_ERROR: u32 = 4u;
const VIEW_LIGHT_MAPS: u32 = 5u;
const VIEW_COST: u32 = 6u;
const VIEW_FLIP: u32 = 7u;
const VIEW_RANGE: u32 = 8u;

const COLORMAP_GRAY: u32 = 0u;
const COLORMAP_HEAT: u32 = 1u;
const COLORMAP_TURBO: u32 = 2u;

const EMPTY_FAR: u32 = 0u;
const EMPTY_NON_POSITIVE: u32 = 1u;
const NO_FALLBACK: u32 = 255u;

@group(0) @binding(0) var<uniform> view: ViewUniforms;
// The camera pass's targets: shaded colour (its sRGB bytes as they are), V and t + 2·branch, and
// the reversed depth (0 where no surface).
@group(0) @binding(1) var color_bytes: texture_2d<f32>;
@group(0) @binding(2) var data: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_2d<f32>;
@group(0) @binding(4) var reference_v: texture_2d<f32>;
@group(0) @binding(5) var map0: texture_2d<f32>;
@group(0) @binding(6) var map1: texture_2d<f32>;
@group(0) @binding(7) var map2: texture_2d<f32>;
// The camera pass's cost target: the method's work per pixel and the path it took.
@group(0) @binding(8) var cost: texture_2d<f32>;

fn is_hit(p: vec2<i32>) -> bool {
    return textureLoad(depth, p, 0).r > 0.0;
}

fn branch_of(td: f32) -> f32 {
    return clamp(round((td - 0.5) / 2.0), 0.0, 3.0);
}

// Whether v is NaN, infinite, below 0 or above 1 (every comparison with a NaN is false).
fn out_of_range(v: f32) -> bool {
    return !(v >= 0.0 && v <= 1.0);
}

// Whether the surface at pixel p has a V or a t (decoded from t + 2·branch, which the camera
// pass writes so that a t out of range reads back out of range) that is out of range: the range
// view's mark, and what the probe's count counts (twin: render::frame_data::Frame::out_of_range).
fn range_flag(p: vec2<i32>) -> bool {
    if !is_hit(p) {
        return false;
    }
    let d = textureLoad(data, p, 0).xy;
    return out_of_range(d.x) || out_of_range(d.y - 2.0 * branch_of(d.y));
}

fn map_texel(t: u32, q: vec2<i32>) -> vec4<f32> {
    switch t {
        case 1u: { return frame_untagged(textureLoad(map1, q, 0), view.tags.y); }
        case 2u: { return frame_untagged(textureLoad(map2, q, 0), view.tags.z); }
        default: { return frame_untagged(textureLoad(map0, q, 0), view.tags.x); }
    }
}

fn has_value(v: f32, empty: u32) -> bool {
    if empty == EMPTY_FAR {
        return v < 1.5e38;
    }
    return v > 0.0 && v < 1.5e38;
}

struct ChannelValue {
    value: f32,
    valid: bool,
};

// Channel c of the light maps at texel q.
fn channel_at(c: u32, q: vec2<i32>) -> ChannelValue {
    let spec = view.channels[c];
    var out: ChannelValue;
    out.value = map_texel(spec.x, q)[spec.y];
    out.valid = has_value(out.value, spec.z);
    if !out.valid && spec.w != NO_FALLBACK {
        out.value = map_texel(spec.w / 4u, q)[spec.w % 4u];
        out.valid = has_value(out.value, spec.z);
    }
    return out;
}
