// The camera pass every method shares (src/render/passes/camera.rs): every surface from the
// camera, V per pixel from the method, diffuse shading from the light's centre (a disk's, a line
// light's midpoint) times V. A method's shader
// (shaders/methods/NAME.wgsl) includes this file and defines
//     fn method_visibility(x: vec3<f32>, n: vec3<f32>, pixel: vec2<f32>) -> Visibility
// for the shaded point x, its normal n (turned toward the camera) and the pixel's centre, with
// its own bindings in group 1. Depth is reversed (1 at the near plane, 0 at the far one) for
// precision: the world position is read back from it.
// #include shared/surface.wgsl
// #include shared/polygon.wgsl

struct CameraUniforms {
    view_proj: mat4x4<f32>,
    // The camera position.
    eye: vec3<f32>,
    // The ambient share of the shading, so shadowed surfaces keep their shape.
    ambient: f32,
    // The disk centre c.
    light_center: vec3<f32>,
    light_radius: f32,
    // The unit normal n_c, toward the emitting side (zero for a line light).
    light_normal: vec3<f32>,
    light_intensity: f32,
    // LIGHT_DISK, LIGHT_LINE or LIGHT_POLYGON. A line light emits all around its segment: no
    // one-sided test, no emitter cosine; light_center is its midpoint, light_radius 0. A
    // rectangle or polygon: light_radius is the radius of the disk of its area.
    light_kind: u32,
    // A rectangle's or polygon's corners (0 for a disk or a line), and its area.
    light_corner_count: u32,
    light_area: f32,
    // The radius of the disk about light_center that holds the whole light (0 for a line).
    light_bound: f32,
    // The light's plane basis the corners are given in.
    light_u: vec3<f32>,
    _pad1: u32,
    light_w: vec3<f32>,
    _pad2: u32,
    // The corners about the centre in (light_u, light_w), counter-clockwise, two per vector.
    light_corners: array<vec4<f32>, 8>,
};

const LIGHT_DISK: u32 = 0u;
const LIGHT_LINE: u32 = 1u;
const LIGHT_POLYGON: u32 = 2u;

@group(0) @binding(0) var<uniform> camera: CameraUniforms;

// V(t) variants, as geometry::VtVariant::code(). Which one a pipeline applies is fixed when it
// is made (a pipeline per variant): a CPU rasteriser runs every path of a branch, so a switch on
// a uniform would cost every variant's arithmetic on every pixel.
override VT_VARIANT: u32 = 0u;
// 1 in the pipelines for a rectangle or polygon light (render::methods::MethodPipeline): a
// constant, so a disk's pipeline has no polygon path — a CPU rasteriser runs every branch, and
// the polygon's clips under a disk cost several times the pass.
override POLYGON_LIGHT: u32 = 0u;

// Whether the light is a rectangle or polygon (false in a disk's or a line's pipeline).
fn polygon_light() -> bool {
    return POLYGON_LIGHT == 1u && camera.light_kind == LIGHT_POLYGON;
}
const VT_SMOOTHSTEP: u32 = 0u;
const VT_SQRT: u32 = 1u;
const VT_EXACT: u32 = 2u;
const VT_LINEAR: u32 = 3u;

// Branch codes, as geometry::Branch::code().
const BRANCH_UMBRA: f32 = 0.0;
const BRANCH_PENUMBRA_HIDDEN: f32 = 1.0;
const BRANCH_PENUMBRA_VISIBLE: f32 = 2.0;
const BRANCH_LIT: f32 = 3.0;

// geometry::metrics::CLASS_EPS: V at or below it is umbra, at or above 1 - it lit.
const CLASS_EPSILON: f32 = 0.004;

struct Visibility {
    v: f32,
    t: f32,
    branch: f32,
    // The light arriving at x before shadowing, when the method computes it itself (w = 1:
    // extended-light-map reads it from its map, coloured); w = 0 (what `var` starts with, and
    // `plain` keeps): the shared diffuse term of fs_main.
    light: vec4<f32>,
};

// The visible fraction of the unit disk beyond a chord at signed distance h from its centre.
// Near h = 1 it is a difference of two nearly equal terms, which rounds a hair below 0: held at 0
// (V is a fraction; the NaN / range view counts anything below).
fn disk_segment_fraction(h_in: f32) -> f32 {
    let h = clamp(h_in, -1.0, 1.0);
    return max((acos(h) - h * sqrt(max(1.0 - h * h, 0.0))) / 3.14159265358979, 0.0);
}

// The area of the unit disk within dot(m1, p) >= h1 and dot(m2, p) >= h2 (m1, m2 unit), by
// Green's theorem: the arcs inside both, half their angle each, and each chord's part inside the
// other half-plane, half P x Q walked counter-clockwise (twin: geometry::visibility::disk_cut2_area).
fn disk_cut2_area(m1: vec2<f32>, h1: f32, m2: vec2<f32>, h2: f32) -> f32 {
    let pi = 3.14159265358979;
    if h1 >= 1.0 || h2 >= 1.0 {
        return 0.0;
    }
    let f1 = atan2(m1.y, m1.x);
    let f2 = atan2(m2.y, m2.x);
    let a1 = acos(max(h1, -1.0));
    let a2 = acos(max(h2, -1.0));
    if a1 >= pi && a2 >= pi {
        return pi;
    }
    var area = 0.0;
    for (var k = -1.0; k <= 1.0; k += 1.0) {
        let lo = max(f1 - a1, f2 - a2 + k * 2.0 * pi);
        let hi = min(f1 + a1, f2 + a2 + k * 2.0 * pi);
        area += 0.5 * max(hi - lo, 0.0);
    }
    let ms = array<vec2<f32>, 2>(m1, m2);
    let hs = vec2<f32>(h1, h2);
    for (var i = 0u; i < 2u; i++) {
        let m = ms[i];
        let h = hs[i];
        let mo = ms[1u - i];
        let ho = hs[1u - i];
        if h <= -1.0 {
            continue;
        }
        let d = vec2<f32>(m.y, -m.x);
        let half_len = sqrt(max(1.0 - h * h, 0.0));
        var s0 = -half_len;
        var s1 = half_len;
        let slope = dot(mo, d);
        let rest = ho - h * dot(mo, m);
        if abs(slope) < 1e-12 {
            if rest > 0.0 {
                continue;
            }
        } else if slope > 0.0 {
            s0 = max(s0, rest / slope);
        } else {
            s1 = min(s1, rest / slope);
        }
        if s1 > s0 {
            let p = h * m + s0 * d;
            let q = h * m + s1 * d;
            area += 0.5 * (p.x * q.y - p.y * q.x);
        }
    }
    return clamp(area, 0.0, pi);
}

// Interleaved gradient noise (Jimenez 2014): a value in [0, 1) per pixel, fixed by the pixel
// alone (the per-pixel rotation of pcss's taps, smrt's rays and steps).
fn interleaved_gradient_noise(pixel: vec2<f32>) -> f32 {
    return fract(52.9829189 * fract(dot(pixel, vec2<f32>(0.06711056, 0.00583715))));
}

fn v_of_t(t_in: f32) -> f32 {
    let t = clamp(t_in, 0.0, 1.0);
    if VT_VARIANT == VT_SQRT {
        return sqrt(t);
    }
    if VT_VARIANT == VT_EXACT {
        return disk_segment_fraction(1.0 - 2.0 * t);
    }
    if VT_VARIANT == VT_LINEAR {
        return t;
    }
    return t * t * (3.0 - 2.0 * t);
}

// Corner i of the polygon light, read from the uniforms in place (passing the array by value,
// as shared/polygon.wgsl's functions take it, copies it per pixel: on a CPU rasteriser that
// copy was most of the D-buffer's camera pass once the horizon called it on every receiver).
fn light_corner(i: u32) -> vec2<f32> {
    let q = camera.light_corners[i / 2u];
    return select(q.xy, q.zw, (i & 1u) == 1u);
}

// The share of the polygon light where dot(m, p) >= h, in one walk round it: the kept edges, the
// parts of the two it crosses, and the chord from where it leaves the half-plane to where it
// comes back (twin: geometry::outline::clipped_area).
fn light_share_above(m: vec2<f32>, h: f32) -> f32 {
    let n = min(camera.light_corner_count, 16u);
    var sum = 0.0;
    var leave = vec2<f32>(0.0);
    var enter = vec2<f32>(0.0);
    // Edge (i - 1, i), the last corner first: one corner read and no modulo a step.
    var a = light_corner(max(n, 1u) - 1u);
    var da = dot(m, a) - h;
    for (var i = 0u; i < n; i++) {
        let b = light_corner(i);
        let db = dot(m, b) - h;
        let p = a + (b - a) * (da / (da - db));
        let a_in = da >= 0.0;
        let b_in = db >= 0.0;
        let start = select(p, a, a_in);
        let end = select(p, b, b_in);
        sum += select(0.0, start.x * end.y - start.y * end.x, a_in || b_in);
        leave = select(leave, p, a_in && !b_in);
        enter = select(enter, p, !a_in && b_in);
        a = b;
        da = db;
    }
    sum += leave.x * enter.y - leave.y * enter.x;
    return clamp(0.5 * sum / max(camera.light_area, 1e-30), 0.0, 1.0);
}

// V(t), with the chord's direction for V exact under a polygon light: the share of the light
// beyond the chord a share t of the way across it toward its lit side m (twin:
// geometry::outline::Outline2d::fraction_beyond). A disk's, or no direction, is v_of_t's.
fn v_of_t_toward(t_in: f32, m_in: vec2<f32>) -> f32 {
    // A fan's corner marker (x <= -2, methods/dbuffer.wgsl) is no direction either.
    if VT_VARIANT != VT_EXACT || !polygon_light() || !(dot(m_in, m_in) > 1e-12) || m_in.x < -1.5 {
        return v_of_t(t_in);
    }
    let t = clamp(t_in, 0.0, 1.0);
    let m = normalize(m_in);
    var lo = 3.0e38;
    var hi = -3.0e38;
    for (var i = 0u; i < camera.light_corner_count; i++) {
        let x = dot(m, polygon_corner(camera.light_corners, i));
        lo = min(lo, x);
        hi = max(hi, x);
    }
    return light_share_above(m, hi - t * (hi - lo));
}

// The receiver's horizon: the part of the area light in front of the plane through x with
// normal n (twin: geometry::wedges::DiskFrame::horizon_fraction). With k = n . (c - x) and m the
// part of n in the light's plane, the far side of the chord at -k / (r |m|), V(t)'s exact
// disk-half-plane area (for a polygon, its share beyond that chord).
fn horizon_fraction(x: vec3<f32>, n: vec3<f32>) -> f32 {
    let nc = camera.light_normal;
    let k = dot(n, camera.light_center - x);
    let tilt = length(n - dot(n, nc) * nc);
    let s = tilt * camera.light_radius;
    // Where the plane misses the light (its bounding disk, for a polygon): all of it or none.
    var v = select(0.0, 1.0, k > 0.0);
    // The cut, in a loop run at most once rather than an `if`: a CPU rasteriser runs both sides
    // of every `if` for a whole group of pixels, but leaves a loop that no pixel of the group
    // enters (on llvmpipe that took a millisecond off the D-buffer's camera pass at 1024²,
    // where receivers whose plane cuts the light are few).
    for (var cuts = select(s, tilt * camera.light_bound, polygon_light()) > abs(k); cuts; cuts = false) {
        if polygon_light() {
            // In front where p . (n . u, n . w) > -k, p a corner-plane point about the centre.
            v = light_share_above(vec2<f32>(dot(n, camera.light_u), dot(n, camera.light_w)), -k);
        } else {
            v = disk_segment_fraction(-k / s);
        }
    }
    return v;
}

// The work the method did at this pixel, for the cost views (src/render/methods/mod.rs, Cost;
// docs/development/adding-a-method.md): x counts its units of work — shadow-map taps, march
// steps, listed edges, maps read, rays — and y the path it took (0 its plain path, other codes
// as its MethodSpec's `.cost(…)` names them). A method adds where it works, inside whatever
// helper does the work: `count_work(n)`, `took_path(code)`; one that never calls them reports
// 0 everywhere. fs_main writes it to the cost target. A module-scope private rather than a field
// of Visibility, so a helper deep in a method counts its own loop without threading a counter
// through every return value (and `plain()` replacing a Visibility cannot drop the count).
var<private> method_cost: vec2<f32>;

fn count_work(n: f32) {
    method_cost.x += n;
}

fn took_path(code: f32) {
    method_cost.y = code;
}

// V given for a method that is not the D-buffer: t = V, the branch by the class of V.
fn plain(v: f32) -> Visibility {
    var out: Visibility;
    out.v = v;
    out.t = v;
    out.branch = select(
        select(BRANCH_PENUMBRA_VISIBLE, BRANCH_LIT, v >= 1.0 - CLASS_EPSILON),
        BRANCH_UMBRA,
        v <= CLASS_EPSILON
    );
    return out;
}

// Whether x lies on the emitting side of the one-sided planar light (every point, for a line
// light).
fn in_front_of_light(x: vec3<f32>) -> bool {
    return camera.light_kind == LIGHT_LINE || dot(x - camera.light_center, camera.light_normal) > 0.0;
}

// Whether the side of the surface the camera sees faces the light centre (else it is its own
// shadow: nothing arrives, and the oracle agrees: rays from it run into the object).
fn faces_light_center(x: vec3<f32>, n: vec3<f32>) -> bool {
    return dot(n, camera.light_center - x) > 0.0;
}

struct SurfaceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) @interpolate(flat) albedo: f32,
};

@vertex
fn vs_main(v: SurfaceIn) -> SurfaceOut {
    var out: SurfaceOut;
    out.clip = camera.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.albedo = v.albedo;
    return out;
}

struct Targets {
    // Linear RGB (the sRGB target encodes it); a = 1.
    @location(0) color: vec4<f32>,
    // V, and t + 2 × branch code: t is in [0, 1], so both are exact in one f32.
    @location(1) data: vec2<f32>,
    // The method's work here and the path it took (method_cost).
    @location(2) cost: vec2<f32>,
};

// The flat normal of the triangle from the derivatives of its (affine) position, turned to the
// side the camera sees: surfaces are two-sided.
fn surface_normal(f: SurfaceOut) -> vec3<f32> {
    let to_eye = camera.eye - f.world;
    let m = cross(dpdx(f.world), dpdy(f.world));
    var n = select(normalize(to_eye), normalize(m), dot(m, m) > 1e-30);
    if dot(n, to_eye) < 0.0 {
        n = -n;
    }
    return n;
}

// t + 2 × branch code, as the data target holds it. A t the method returned outside [0, 1] must
// read back outside it, for the range view and compare's count (render::frame_data::
// out_of_range): the sum reads back the branch as round((sum - ½) / 2) and t as the rest, which
// gives back t only within about half a unit of [0, 1], and rounds away an excess below one f32
// step of the sum. Where the sum would read back a t in [0, 1], 1.25 (t above 1) or -0.25 (below
// 0) is written in its place, the branch kept. A NaN or infinite t stays as it is. Every t in
// [0, 1] is written as it was: no valid method's targets change.
fn encode_t(t: f32, branch: f32) -> f32 {
    let sum = t + 2.0 * branch;
    let back = sum - 2.0 * clamp(round((sum - 0.5) / 2.0), 0.0, 3.0);
    let reads_valid = back >= 0.0 && back <= 1.0;
    let is_valid = t >= 0.0 && t <= 1.0;
    if !is_valid && reads_valid {
        return select(-0.25, 1.25, t > 1.0) + 2.0 * branch;
    }
    return sum;
}

// The targets of a surface point with normal n and the method's visibility there.
fn shade(f: SurfaceOut, n: vec3<f32>, vis: Visibility) -> Targets {
    let l = normalize(camera.light_center - f.world);
    let cos_receiver = max(dot(n, l), 0.0);
    let cos_emitter = select(max(dot(-l, camera.light_normal), 0.0), 1.0, camera.light_kind == LIGHT_LINE);
    let diffuse = vec3<f32>(camera.light_intensity * cos_receiver * cos_emitter);
    let direct = select(diffuse, vis.light.xyz, vis.light.w > 0.5) * vis.v;
    let shade = f.albedo * (camera.ambient + (1.0 - camera.ambient) * min(direct, vec3<f32>(1.0)));
    var out: Targets;
    out.color = vec4<f32>(shade, 1.0);
    out.data = vec2<f32>(vis.v, encode_t(vis.t, vis.branch));
    out.cost = method_cost;
    return out;
}

@fragment
fn fs_main(f: SurfaceOut) -> Targets {
    let n = surface_normal(f);
    method_cost = vec2<f32>(0.0);
    return shade(f, n, method_visibility(f.world, n, f.clip.xy));
}
