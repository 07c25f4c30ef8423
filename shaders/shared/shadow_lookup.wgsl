// Looking up the centre's shadow map (|cx_o|, render::passes::shadow_map) from the camera pass:
// the methods built on it (hard, pcf, pcss, the D-buffer family) include this file after
// shared/camera.wgsl and bind their ShadowUniforms and the map as group 1, bindings 0 and 1.
// ShadowUniforms holds the map's own numbers only: a method's parameters are its own struct
// (`NameParams`, declared in its shader and as a #[repr(C)] struct in its Rust module, u32 for
// switches, bits and counts, f32 for real numbers), bound as `params` at binding 2
// (render::passes::shadow_map::PARAMS_BINDING); the method's other bindings follow from 3 on.

struct ShadowUniforms {
    // World to the light view's clip space, and back.
    light_view_proj: mat4x4<f32>,
    inv_light_view_proj: mat4x4<f32>,
    // The map is size × size texels.
    size: f32,
    // The slope (tangent) one texel spans in the light view.
    texel_slope: f32,
    // Bias of the hidden-from-centre test, relative to |cx|: constant, and the factor of the
    // slope one texel spans times the tangent of the incidence angle.
    bias_constant: f32,
    bias_slope: f32,
};

@group(1) @binding(0) var<uniform> shadow: ShadowUniforms;
@group(1) @binding(1) var d_o: texture_2d<f32>;

// Where a shaded point falls in the light view.
struct LightLookup {
    // |cx|.
    d: f32,
    // In [0, 1]² over the map; inside: the point is in the map's frustum.
    uv: vec2<f32>,
    texel: vec2<i32>,
    inside: bool,
    // The bias of the |cx_o| test here, relative to |cx|.
    rel_bias: f32,
};

// The texel under a point of the light view's image, `uv` in [0, 1]².
fn texel_of(uv: vec2<f32>) -> vec2<i32> {
    let size = shadow.size;
    return vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), vec2<f32>(size - 1.0)));
}

fn light_lookup(x: vec3<f32>, n: vec3<f32>) -> LightLookup {
    var out: LightLookup;
    let to_x = x - camera.light_center;
    out.d = length(to_x);
    let clip = shadow.light_view_proj * vec4<f32>(x, 1.0);
    let ndc = clip.xyz / clip.w;
    out.inside = clip.w > 0.0 && all(abs(ndc.xy) <= vec2<f32>(1.0));
    out.uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    out.texel = texel_of(out.uv);
    // Slope-scaled bias: a texel spans a slope of texel_slope in the light view; on a surface
    // tilted away from the light its footprint grows with tan(incidence).
    let cos_i = clamp(abs(dot(n, -to_x / out.d)), 0.05, 1.0);
    let tan_i = sqrt(1.0 - cos_i * cos_i) / cos_i;
    out.rel_bias = shadow.bias_constant + shadow.bias_slope * shadow.texel_slope * tan_i;
    return out;
}

// Whether the nearest surface at the point's texel hides it from c.
fn hidden_from_center(l: LightLookup) -> bool {
    let o = textureLoad(d_o, l.texel, 0).x;
    return l.d > o + l.d * l.rel_bias;
}

// Where the receiver's plane (through x, normal n) meets the ray from c through the centre of
// `texel`: the |cx| a filter tap there must be compared with (receiver-plane depth bias).
fn receiver_distance(texel: vec2<i32>, x: vec3<f32>, n: vec3<f32>, d: f32) -> f32 {
    let uv = (vec2<f32>(texel) + 0.5) / shadow.size;
    let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
    let p = shadow.inv_light_view_proj * ndc;
    let c = camera.light_center;
    let dir = normalize(p.xyz / p.w - c);
    let denom = dot(n, dir);
    let t = dot(n, x - c) / denom;
    // Grazing or behind: fall back to the point's own distance.
    return select(d, t, abs(denom) > 1e-4 && t > 0.0 && t < 4.0 * d);
}

// How wide, in shadow-map texels, a light of radius r at c looks from a receiver at distance d
// through a plane at distance z (similar triangles over the larger of the map's two texel
// slopes): the blocker search of `pcss` with z the nearest caster, its penumbra with z the
// blockers' mean.
fn light_width_in_texels(r: f32, d: f32, z: f32) -> f32 {
    return r * (d - z) / (z * d) / max(shadow.texel_slope, 1e-9);
}

// Where a world point falls in the map, in texels.
fn map_point(p: vec3<f32>) -> vec2<f32> {
    let clip = shadow.light_view_proj * vec4<f32>(p, 1.0);
    let ndc = clip.xy / clip.w;
    return vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * shadow.size;
}

// The light seen from x through the plane at height h above the light's plane (parallel to it),
// projected into the map: the half-widths, in texels along the map's two axes, of the light's
// image there — the points q + (x − q) h / h_x for q on the light, about the one for its centre
// (which lies on x's ray, so on x's texel). `msm-soft` sizes its blocker search (h: the lowest
// caster) and its penumbra filter (h: the blockers') by it (`pcss` keeps its classic sizing,
// light_width_in_texels, which on the scored scenes does better for it). By similar triangles in
// the light's own frame and the map's own projection, so the map's view tilted from the light,
// a frustum wider one way than the other (a square map's texels then span less angle across than
// along) and a point off the view's axis are all counted. A disk's image is an ellipse, whose box
// this is; a rectangle's or polygon's, the box of its corners.
fn light_footprint(x: vec3<f32>, h: f32) -> vec2<f32> {
    let c = camera.light_center;
    let hx = dot(x - c, camera.light_normal);
    let f = clamp(h / max(hx, 1e-30), 0.0, 1.0);
    let centre = map_point(c + (x - c) * f);
    if polygon_light() {
        var e = vec2<f32>(0.0);
        for (var i = 0u; i < camera.light_corner_count; i++) {
            let k = light_corner(i);
            let q = c + k.x * camera.light_u + k.y * camera.light_w;
            e = max(e, abs(map_point(q + (x - q) * f) - centre));
        }
        return e;
    }
    let r = camera.light_radius;
    let qa = c + r * camera.light_u;
    let qb = c + r * camera.light_w;
    let a = map_point(qa + (x - qa) * f) - centre;
    let b = map_point(qb + (x - qb) * f) - centre;
    return sqrt(a * a + b * b);
}

// 1 where the shadow map at `texel` does not hide a receiver at `expected`.
fn lit_at(texel: vec2<i32>, expected: f32, rel_bias: f32) -> f32 {
    let size = i32(shadow.size);
    let q = clamp(texel, vec2<i32>(0), vec2<i32>(size - 1));
    let o = textureLoad(d_o, q, 0).x;
    return select(0.0, 1.0, expected <= o + expected * rel_bias);
}
