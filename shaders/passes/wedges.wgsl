// Penumbra wedges (Akenine-Möller & Assarsson 2002/2003; render::passes::wedges, CPU twin
// geometry::wedges): after the hard stencil count from the disk's centre
// (passes/stencil_volumes.wgsl), one wedge per silhouette edge of that volume is rasterised by
// its back faces, no depth test, so every pixel whose camera ray meets the wedge gets exactly one
// fragment; the fragment takes the receiver from the prepass's position target and adds the
// part of the disk the edge covers as that receiver sees it (negative: the edge uncovers light)
// into a float sum buffer (passes/wedges_resolve.wgsl then makes V of it).

// #include shared/polygon.wgsl

// As ScreenUniforms of passes/stencil_volumes.wgsl (the same bind group).
struct ScreenUniforms {
    infinite_view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    size: vec4<f32>,
};

// The light, as render::passes::wedges::WedgeDisk: u x w = -normal.
struct WedgeDisk {
    // xyz: the centre c; w: the radius r (of the disk, or the disk a polygon fits in).
    center: vec4<f32>,
    // xyz: the unit normal n (toward the scene).
    normal: vec4<f32>,
    u: vec4<f32>,
    w: vec4<f32>,
    // x: a rectangle's or polygon's corner count (0: a disk); y: their area (radius units^2).
    polygon: vec4<f32>,
    // The corners in (u, w), radius units, counter-clockwise there: two per vector.
    corners: array<vec4<f32>, 8>,
};

@group(0) @binding(0) var<uniform> screen: ScreenUniforms;
@group(1) @binding(0) var<uniform> disk: WedgeDisk;
// 1 in the pipeline for rectangle and polygon lights (render::passes::wedges::WedgePass): a
// constant, so the disk's pipeline has no polygon clip to run.
override POLYGON_LIGHT: f32 = 0.0;
@group(1) @binding(1) var positions: texture_2d<f32>;

const PI: f32 = 3.14159265358979;
// geometry::wedges::SLAB_EPS
const SLAB_EPS: f32 = 1e-4;

// The part of the unit disk between the directed segment a -> b and the arc, inside the angle its
// ends subtend at the centre, over pi (geometry::wedges::edge_coverage_2d).
fn edge_coverage_2d(a: vec2<f32>, b: vec2<f32>) -> f32 {
    let d = b - a;
    let len = length(d);
    if !(len > 0.0) {
        return 0.0;
    }
    let dh = d / len;
    let h = a.x * dh.y - a.y * dh.x;
    if abs(h) >= 1.0 {
        return 0.0;
    }
    let half = sqrt(1.0 - h * h);
    let foot = -dot(a, dh);
    let t0 = clamp(foot - half, 0.0, len);
    let t1 = clamp(foot + half, 0.0, len);
    if t1 <= t0 {
        return 0.0;
    }
    let p0 = a + dh * t0;
    let p1 = a + dh * t1;
    let cr = p0.x * p1.y - p0.y * p1.x;
    return (cr - atan2(cr, dot(p0, p1))) / (2.0 * PI);
}

// q projected from x onto the light's plane, in disk units.
fn to_disk(x: vec3<f32>, q: vec3<f32>, tx: f32) -> vec2<f32> {
    let tq = dot(disk.normal.xyz, q - disk.center.xyz);
    let g = x + (q - x) * (tx / (tx - tq)) - disk.center.xyz;
    return vec2<f32>(dot(g, disk.u.xyz), dot(g, disk.w.xyz)) / disk.center.w;
}

// The coverage of the disk by the edge e0 -> e1 as x sees it (geometry::wedges::DiskFrame::
// edge_coverage): the edge clipped to the slab between the light's plane and x's.
fn edge_coverage(x: vec3<f32>, e0: vec3<f32>, e1: vec3<f32>) -> f32 {
    let c = disk.center.xyz;
    let n = disk.normal.xyz;
    let tx = dot(n, x - c);
    if !(tx > 0.0) {
        return 0.0;
    }
    let t0 = dot(n, e0 - c);
    let t1 = dot(n, e1 - c);
    let lo = SLAB_EPS * tx;
    let hi = (1.0 - SLAB_EPS) * tx;
    var s = vec2<f32>(0.0, 1.0);
    let dt = t1 - t0;
    if abs(dt) < 1e-12 * tx {
        if t0 < lo || t0 > hi {
            return 0.0;
        }
    } else {
        let sa = (lo - t0) / dt;
        let sb = (hi - t0) / dt;
        s = vec2<f32>(max(0.0, min(sa, sb)), min(1.0, max(sa, sb)));
        if s.y <= s.x {
            return 0.0;
        }
    }
    let a = to_disk(x, mix(e0, e1, s.x), tx);
    let b = to_disk(x, mix(e0, e1, s.y), tx);
    if POLYGON_LIGHT > 0.5 && disk.polygon.x > 0.5 {
        return polygon_edge_coverage(disk.corners, u32(disk.polygon.x), disk.polygon.y, a, b);
    }
    return edge_coverage_2d(a, b);
}

struct WedgeIn {
    @location(0) position: vec3<f32>,
    @location(1) e0: vec3<f32>,
    @location(2) e1: vec3<f32>,
};

struct WedgeOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) e0: vec3<f32>,
    @location(1) @interpolate(flat) e1: vec3<f32>,
};

@vertex
fn vs_wedge(v: WedgeIn) -> WedgeOut {
    var out: WedgeOut;
    out.clip = screen.infinite_view_proj * vec4<f32>(v.position, 1.0);
    out.e0 = v.e0;
    out.e1 = v.e1;
    return out;
}

@fragment
fn fs_wedge(f: WedgeOut) -> @location(0) vec4<f32> {
    let x = textureLoad(positions, vec2<i32>(f.clip.xy), 0);
    if x.w < 0.5 {
        discard;
    }
    // y counts the fragment (the wedges' cost view), whether its edge covers any light or not.
    return vec4<f32>(edge_coverage(x.xyz, f.e0, f.e1), 1.0, 0.0, 0.0);
}
