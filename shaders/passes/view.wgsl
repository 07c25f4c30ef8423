// The view pass: what the lab's viewport shows of a frame, drawn on the GPU into the texture the
// viewport samples (src/render/passes/view.rs). Views: the final image, V, t, the classes, |ΔV|
// against the reference, the pixels whose V or t is NaN, infinite or outside [0, 1], and the
// shown method's light-space maps with channel isolation, each scalar through a black/white range
// and a colour map. Its CPU twin is
// src/render/passes/view_twin.rs; a test holds the two to agree on every view.
// #include shared/fullscreen_vs.wgsl
// #include shared/view_inputs.wgsl

// Which view and which colour map: fixed per pipeline (VIEW_* and COLORMAP_* of
// shared/view_inputs.wgsl). A CPU rasteriser runs every path of a branch on every pixel, so a
// switch on a uniform would cost every view's fetches and every map's arithmetic.
override VIEW_KIND: u32 = 0u;
override COLORMAP: u32 = 0u;

// Background of pixels that hit no surface, and of map texels with no data (views::NO_DATA).
const NO_DATA: vec3<f32> = vec3<f32>(20.0, 24.0, 48.0) / 255.0;

// The classes view's colours by branch code (view_twin::BRANCH_COLORS).
const BRANCH_UMBRA_COLOR: vec3<f32> = vec3<f32>(40.0, 60.0, 160.0) / 255.0;
const BRANCH_HIDDEN_COLOR: vec3<f32> = vec3<f32>(230.0, 120.0, 40.0) / 255.0;
const BRANCH_VISIBLE_COLOR: vec3<f32> = vec3<f32>(250.0, 200.0, 90.0) / 255.0;
const BRANCH_LIT_COLOR: vec3<f32> = vec3<f32>(200.0, 196.0, 186.0) / 255.0;

fn normalise(v: f32) -> f32 {
    let span = view.white - view.black;
    if abs(span) < 1.1920929e-7 {
        return select(0.0, 1.0, v >= view.white);
    }
    return (v - view.black) / span;
}

fn poly(c: array<f32, 6>, x: f32) -> f32 {
    var k = c;
    var acc = 0.0;
    for (var i = 5; i >= 0; i--) {
        acc = acc * x + k[i];
    }
    return acc;
}

// The colour map of x in [0, 1] (clamped; NaN as 0), as view_twin::ColorMap::color.
fn colormap(x_in: f32) -> vec3<f32> {
    var x = clamp(x_in, 0.0, 1.0);
    if x_in != x_in {
        x = 0.0;
    }
    switch COLORMAP {
        case COLORMAP_HEAT: {
            return clamp(vec3<f32>(x * 3.0, x * 3.0 - 1.0, x * 3.0 - 2.0), vec3<f32>(0.0), vec3<f32>(1.0));
        }
        case COLORMAP_TURBO: {
            // Polynomial fit of Google's Turbo (Mikhailov 2019).
            let r = poly(array<f32, 6>(0.13572138, 4.6153926, -42.66032258, 132.13108234, -152.94239396, 59.28637943), x);
            let g = poly(array<f32, 6>(0.09140261, 2.19418839, 4.84296658, -14.18503333, 4.27729857, 2.82956604), x);
            let b = poly(array<f32, 6>(0.1066733, 12.64194608, -60.58204836, 110.36276771, -89.90310912, 27.34824973), x);
            return clamp(vec3<f32>(r, g, b), vec3<f32>(0.0), vec3<f32>(1.0));
        }
        default: {
            return vec3<f32>(x);
        }
    }
}

fn mapped(v: f32) -> vec3<f32> {
    return colormap(normalise(v));
}

// The range view's marks, and its dimmed grey of the image under them (view_twin::RANGE_MARK,
// view_twin::range_grey).
const RANGE_MARK: vec3<f32> = vec3<f32>(1.0, 0.0, 1.0);

fn range_view(p: vec2<i32>) -> vec3<f32> {
    if range_flag(p) {
        return RANGE_MARK;
    }
    let c = textureLoad(color_bytes, p, 0).rgb;
    return vec3<f32>((c.r + c.g + c.b) * (0.4 / 3.0));
}

fn camera_view(p: vec2<i32>) -> vec3<f32> {
    if VIEW_KIND == VIEW_FINAL {
        return textureLoad(color_bytes, p, 0).rgb;
    }
    if VIEW_KIND == VIEW_RANGE {
        return range_view(p);
    }
    if !is_hit(p) {
        return NO_DATA;
    }
    let d = textureLoad(data, p, 0).xy;
    let branch = branch_of(d.y);
    switch VIEW_KIND {
        case VIEW_VISIBILITY: { return mapped(d.x); }
        case VIEW_T: { return mapped(d.y - 2.0 * branch); }
        case VIEW_ERROR: {
            if view.has_reference == 0u {
                return textureLoad(color_bytes, p, 0).rgb;
            }
            return mapped(abs(d.x - textureLoad(reference_v, p, 0).x));
        }
        case VIEW_COST: { return mapped(textureLoad(cost, p, 0).x); }
        // The FLIP map handed in, bound where the reference V is for the error view.
        case VIEW_FLIP: {
            if view.has_reference == 0u {
                return textureLoad(color_bytes, p, 0).rgb;
            }
            return mapped(textureLoad(reference_v, p, 0).x);
        }
        default: {
            switch u32(branch) {
                case 0u: { return BRANCH_UMBRA_COLOR; }
                case 1u: { return BRANCH_HIDDEN_COLOR; }
                case 2u: { return BRANCH_VISIBLE_COLOR; }
                default: { return BRANCH_LIT_COLOR; }
            }
        }
    }
}

fn maps_view(q: vec2<i32>) -> vec3<f32> {
    let mask = view.channel_mask & ((1u << view.channel_count) - 1u);
    let shown = countOneBits(mask);
    if shown == 0u {
        return NO_DATA;
    }
    if shown == 1u {
        let c = channel_at(firstTrailingBit(mask), q);
        return select(NO_DATA, mapped(c.value), c.valid);
    }
    // Several: an RGB composite of the first three, each through the range in gray.
    var rgb = vec3<f32>(0.0);
    var any = false;
    for (var c = 0u; c < 3u; c++) {
        if (mask & (1u << c)) != 0u {
            let v = channel_at(c, q);
            if v.valid {
                rgb[c] = clamp(normalise(v.value), 0.0, 1.0);
                any = true;
            }
        }
    }
    return select(NO_DATA, rgb, any);
}

@fragment
fn fs_main(in: FullscreenVertex) -> @location(0) vec4<f32> {
    let p = vec2<i32>(floor(in.position.xy));
    var rgb: vec3<f32>;
    if VIEW_KIND == VIEW_LIGHT_MAPS {
        rgb = maps_view(p);
    } else {
        rgb = camera_view(p);
    }
    return vec4<f32>(rgb, 1.0);
}
