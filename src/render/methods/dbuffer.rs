//! `dbuffer` (Jakobsen et al. 2004, with the corrections in docs/method/dbuffer.md) and `dbuffer-center` (its silhouettes and
//! volumes taken from the light centre only: the penumbra-wedge approximation Jakobsen et al. 2004, Fig. 1
//! criticises).
//!
//! Per light or caster move: the geometry stage (`geometry::PreparedCasters::build`: classes,
//! silhouettes, volumes), the volumes uploaded, then the light pass — the session's shadow map
//! (`|cx_o|`) and the volume channels (`passes::dbuffer_volumes`). Per frame: the camera pass
//! with `shaders/methods/dbuffer.wgsl`. CPU twin: `geometry::DBufferTwin`.

use std::time::Instant;

use glam::Vec3;

use super::{
    require, CameraGroup, Channel, Empty, FrameInputs, LightMaps, MethodSpec, MethodState, Prepare,
    SharedMaps,
};
use crate::geometry::light_view::LightView;
use crate::geometry::{CasterGeometry, SceneGeometry, VolumeParams};
use crate::render::gpu_scene::VertexChunks;
use crate::render::passes::dbuffer_volumes::{disjoint_groups, CasterVolumes, DBufferVolumes};
use crate::render::passes::shadow_map::{lookup_entries, LightUniforms, ShadowUniforms};
use crate::render::{
    buffer_entry, texture_entry, uniform_buffer, view_entry, GpuContext, RenderError, VolumeVertex,
};
use crate::scene::{DiskLight, LightKind};

pub static DBUFFER: MethodSpec = MethodSpec {
    name: "dbuffer",
    description: "D-buffer soft shadows (Jakobsen et al. 2004)",
    knobs: &[],
    cpu_side: false,
    hard: false,
    needs: Some(LightKind::Disk), // its volumes are the disk's
    new: |ctx| Box::new(DBuffer::new(ctx, false)),
};

pub static DBUFFER_CENTER: MethodSpec = MethodSpec {
    name: "dbuffer-center",
    description: "D-buffer with silhouettes from the light centre only",
    knobs: &[],
    cpu_side: false,
    hard: false,
    needs: Some(LightKind::Disk), // its volumes are the disk's
    new: |ctx| Box::new(DBuffer::new(ctx, true)),
};

const SHADER: &str = "methods/dbuffer.wgsl";

/// The D-buffer's channels, in `dbuffer.exr` order (R, G, B, A): textures 0 (`|cx_o|`), 1
/// (umbra: `|cx_uv|`, `|cx_s|`), 2 (penumbra: `|cx_pv|`, `|cx_s|`). `|cx_s|` is the umbra's
/// where it has one.
pub const CHANNELS: &[Channel] = &[
    Channel {
        name: "|cx_o|",
        texture: 0,
        component: 0,
        empty: Empty::Far,
        or: None,
    },
    Channel {
        name: "|cx_uv|",
        texture: 1,
        component: 0,
        empty: Empty::NonPositive,
        or: None,
    },
    Channel {
        name: "|cx_pv|",
        texture: 2,
        component: 0,
        empty: Empty::NonPositive,
        or: None,
    },
    Channel {
        name: "|cx_s|",
        texture: 1,
        component: 1,
        empty: Empty::NonPositive,
        or: Some((2, 1)),
    },
];

pub struct DBuffer {
    center_silhouettes: bool,
    /// Bound for the generations of the shadow map and the volume channels ([`Bound`]).
    camera: CameraGroup,
    uniforms: wgpu::Buffer,
    /// The geometry, and the revision it was built for.
    geometry: Option<(SceneGeometry, u64)>,
    builds: u64,
    geometry_ms: f64,
    casters: Vec<CasterVolumes>,
    penumbra: VertexChunks,
    /// Where the penumbra entries can be in the light view's image.
    penumbra_rect: [f32; 4],
    volumes: DBufferVolumes,
    /// What the volume channels hold.
    made_for: Option<Made>,
    view_proj: glam::Mat4,
}

/// What the volume channels were drawn for.
#[derive(Clone, Copy, PartialEq)]
struct Made {
    revision: u64,
    map_size: u32,
    /// The shadow map's generation (the penumbra channel is drawn over its depth).
    map: u64,
}

/// What the camera bind group binds: the shadow map's and the volume channels' generations.
#[derive(PartialEq)]
struct Bound {
    map: u64,
    volumes: u64,
}

impl DBuffer {
    pub fn new(ctx: &GpuContext, center_silhouettes: bool) -> DBuffer {
        let mut entries = lookup_entries().to_vec();
        entries.extend([
            texture_entry(
                2,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2,
            ),
            texture_entry(
                3,
                wgpu::ShaderStages::FRAGMENT,
                wgpu::TextureViewDimension::D2,
            ),
        ]);
        DBuffer {
            center_silhouettes,
            camera: CameraGroup::new(ctx, SHADER, &entries),
            uniforms: uniform_buffer::<ShadowUniforms>(&ctx.device, "DBuffer::uniforms"),
            geometry: None,
            builds: 0,
            geometry_ms: 0.0,
            casters: Vec::new(),
            penumbra: VertexChunks::empty(),
            penumbra_rect: [0.0, 0.0, 1.0, 1.0],
            volumes: DBufferVolumes::new(ctx),
            made_for: None,
            view_proj: glam::Mat4::IDENTITY,
        }
    }

    /// The geometry stage and the volumes' upload, when the light or a caster moved.
    fn update_geometry(&mut self, inputs: &FrameInputs<'_>, light: DiskLight) {
        if self
            .geometry
            .as_ref()
            .is_some_and(|(_, r)| *r == inputs.revision)
        {
            return;
        }
        let params = VolumeParams {
            center_silhouettes: self.center_silhouettes,
            ..VolumeParams::for_scene(inputs.scene)
        };
        let t = Instant::now();
        let geometry = inputs.prepared().build(&light, &params);
        self.geometry_ms = t.elapsed().as_secs_f64() * 1e3;
        self.builds += 1;
        let device = &inputs.ctx.device;
        // The farthest any surface lies below the light's plane (a little beyond).
        let (lo, hi) = inputs.surfaces.bounds;
        let reach = (0..8)
            .map(|k| {
                let corner = Vec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                light.height_of(corner)
            })
            .fold(0.0f32, f32::max);
        let reach = if reach.is_finite() {
            reach * 1.01 + 1e-3
        } else {
            f32::MAX
        };
        // Each caster's umbra rectangle (from its volume's corners, before any ending), to
        // know whether umbrae are merged over casters: only umbrae drawn straight into the
        // target may end at the reach too.
        let rects: Vec<[f32; 4]> = geometry
            .casters
            .iter()
            .map(|g| {
                let corners = (0..g.volumes.triangle_count())
                    .map(|i| g.volumes.triangle(i))
                    .filter(|(_, attrs)| attrs.kind.is_umbra())
                    .flat_map(|(corners, _)| corners);
                light_view_rect(inputs.light_view, corners)
            })
            .collect();
        let merged = disjoint_groups(&rects).len() > 1;
        let umbra_reach = (!merged).then_some(reach);
        let mut penumbra = Vec::new();
        self.casters = geometry
            .casters
            .iter()
            .zip(rects)
            .map(|(g, rect)| {
                let (mut umbra, pen) = volume_vertices_within(g, &light, umbra_reach, Some(reach));
                penumbra.extend(pen);
                // Nearest first: the depth test then turns the farther crossings away before
                // shading.
                sort_near_first(&mut umbra, light.center);
                CasterVolumes {
                    rect,
                    umbra: VertexChunks::new(device, "DBuffer::umbra", &umbra),
                }
            })
            .collect();
        sort_near_first(&mut penumbra, light.center);
        self.penumbra_rect = light_view_rect(
            inputs.light_view,
            penumbra.iter().map(|v| Vec3::from(v.position)),
        );
        self.penumbra = VertexChunks::new(device, "DBuffer::penumbra", &penumbra);
        self.geometry = Some((geometry, inputs.revision));
        self.made_for = None;
    }
}

impl MethodState for DBuffer {
    fn prepare(&mut self, p: Prepare<'_, '_>) -> Result<&CameraGroup, RenderError> {
        let Prepare(inputs, shared, rec) = p;
        let light = *inputs.disk(if self.center_silhouettes {
            DBUFFER_CENTER.name
        } else {
            DBUFFER.name
        })?;
        self.update_geometry(inputs, light);
        let map = shared.shadow_map.update(inputs, rec)?;
        let key = Made {
            revision: inputs.revision,
            map_size: map.size,
            map: map.generation,
        };
        if self.made_for != Some(key) {
            let depth = shared.shadow_map.depth_for_drawing(inputs, rec)?;
            self.volumes.record(
                inputs.ctx,
                rec,
                &LightUniforms::new(&inputs.scene.light, inputs.light_view),
                depth,
                &self.casters,
                &self.penumbra,
                self.penumbra_rect,
            );
            self.made_for = Some(key);
            self.view_proj = inputs.light_view.view_projection();
        }
        let map = shared.shadow_map.made()?;
        let uniforms = ShadowUniforms::new(inputs.light_view, map.size, [0.0; 4]);
        inputs
            .ctx
            .queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let v = require(
            self.volumes.targets(),
            "the D-buffer's targets were not made",
        )?;
        let bound = Bound {
            map: map.generation,
            volumes: v.generation,
        };
        self.camera.bind(
            &inputs.ctx.device,
            bound,
            &[
                buffer_entry(0, &self.uniforms),
                view_entry(1, &map.distance.view),
                view_entry(2, &v.umbra.view),
                view_entry(3, &v.penumbra.view),
            ],
        );
        Ok(&self.camera)
    }

    fn light_maps<'a>(&'a self, shared: &'a SharedMaps) -> Option<LightMaps<'a>> {
        self.made_for?;
        let map = shared.shadow_map.targets()?;
        let v = self.volumes.targets()?;
        let generation = map.generation ^ v.generation.rotate_left(32);
        let textures = [&map.distance, &v.umbra, &v.penumbra];
        Some(LightMaps::new(
            v.size,
            self.view_proj,
            textures,
            CHANNELS,
            generation,
        ))
    }

    fn geometry(&self) -> Option<&SceneGeometry> {
        self.geometry.as_ref().map(|(g, _)| g)
    }

    fn geometry_builds(&self) -> (u64, f64) {
        (self.builds, self.geometry_ms)
    }

    fn invalidate(&mut self) {
        self.made_for = None;
    }
}

/// The caster's volume triangles as GPU vertices, umbra and penumbra apart (their winding says
/// which way a ray crosses them).
///
/// `|cx_s|` (eq. 2 in words) needs the height `h` below the light's plane of the edge point `e`
/// a fragment `q` was extruded from: `e` is where the line from the extrusion point `p` through
/// `q` meets the edge (the twin finds it as the closest point of the two lines). On the quad's
/// plane `q = p + μ(e − p)`; for any `w` across the edge, `μ = (q − p)·w / (a − p)·w` is affine in
/// `q`, so `h = (p − c)·n + ((q − p)·n) ((a − p)·w) / ((q − p)·w)` is `base + num/den` with `num`
/// and `den` affine over the triangle: their vertex values interpolate exactly, and the fragment
/// shader does one division instead of solving for `e`. A fan (its edge is its apex) and an edge
/// its extrusion point lies on have a constant `h`.
pub fn volume_vertices(
    g: &CasterGeometry,
    light: &crate::scene::DiskLight,
) -> (Vec<VolumeVertex>, Vec<VolumeVertex>) {
    volume_vertices_within(g, light, None, None)
}

/// [`volume_vertices`], each volume ended at its reach when one is given ([`end_at`]), made in
/// one pass: no full copy of a volume is held besides the one returned.
pub fn volume_vertices_within(
    g: &CasterGeometry,
    light: &crate::scene::DiskLight,
    umbra_reach: Option<f32>,
    penumbra_reach: Option<f32>,
) -> (Vec<VolumeVertex>, Vec<VolumeVertex>) {
    let (c, n) = (light.center, light.normal);
    let triangles = g.volumes.triangle_count();
    let umbrae = (0..triangles)
        .filter(|&i| g.volumes.triangle(i).1.kind.is_umbra())
        .count();
    let (mut umbra, mut penumbra) = (
        Vec::with_capacity(3 * umbrae),
        Vec::with_capacity(3 * (triangles - umbrae)),
    );
    for i in 0..triangles {
        let (corners, attrs) = g.volumes.triangle(i);
        let [a, b] = attrs.edge;
        let p = attrs.extrusion;
        let along = (b - a).normalize_or_zero();
        let w = (p - a) - along * (p - a).dot(along);
        let ratio = w.length_squared() > 1e-12 * (p - a).length_squared().max(1e-30);
        let (out, reach) = if attrs.kind.is_umbra() {
            (&mut umbra, umbra_reach)
        } else {
            (&mut penumbra, penumbra_reach)
        };
        let t = corners.map(|q| {
            let (base, num, den) = if ratio {
                let k = (a - p).dot(w);
                ((p - c).dot(n), (q - p).dot(n) * k, (q - p).dot(w))
            } else {
                ((a - c).dot(n), 0.0, 1.0)
            };
            VolumeVertex {
                position: q.to_array(),
                kind: attrs.kind.code(),
                base,
                num,
                den,
            }
        });
        match reach {
            Some(r) => clip_into(t, light, r, out),
            None => out.extend(t),
        }
    }
    (umbra, penumbra)
}

/// The parts of volume triangles whose height below the light's plane is at most `reach`.
///
/// Along a ray from `c` the height grows with the distance, so a volume crossing beyond the
/// greatest height of any surface lies behind every receiver on its ray: a penumbra entry there
/// is never looked up (only points visible from `c` read that channel), and an umbra exit there
/// reads as "no exit", which is what a receiver in front of it must get anyway. The extruded
/// quads would otherwise run on to the far plane, and most of their fragments would be
/// rasterised only to die behind the ground. (Not for umbrae merged over casters: there a
/// caster's missing exit would let another caster's win.)
pub fn end_at(
    volume: &[VolumeVertex],
    light: &crate::scene::DiskLight,
    reach: f32,
) -> Vec<VolumeVertex> {
    let mut out = Vec::with_capacity(volume.len());
    for t in volume.chunks_exact(3) {
        clip_into([t[0], t[1], t[2]], light, reach, &mut out);
    }
    out
}

/// Append the part of triangle `t` whose height below the light's plane is at most `reach`
/// (none, all of it, a triangle or a quad as two) to `out`.
fn clip_into(
    t: [VolumeVertex; 3],
    light: &crate::scene::DiskLight,
    reach: f32,
    out: &mut Vec<VolumeVertex>,
) {
    let height = |v: &VolumeVertex| light.height_of(Vec3::from(v.position)) - reach;
    let h = [height(&t[0]), height(&t[1]), height(&t[2])];
    if h.iter().all(|&x| x <= 0.0) {
        out.extend_from_slice(&t);
        return;
    }
    if h.iter().all(|&x| x > 0.0) {
        return;
    }
    // Walk the edges, keeping inside corners and the crossings (Sutherland–Hodgman, one
    // plane); num and den are affine, so they interpolate exactly.
    let mut poly: [VolumeVertex; 4] = [t[0]; 4];
    let mut n = 0;
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let (hp, hq) = (h[k], h[(k + 1) % 3]);
        if hp <= 0.0 {
            poly[n] = p;
            n += 1;
        }
        if (hp <= 0.0) != (hq <= 0.0) {
            let s = hp / (hp - hq);
            let lerp = |a: f32, b: f32| a + (b - a) * s;
            let (pp, qp) = (Vec3::from(p.position), Vec3::from(q.position));
            poly[n] = VolumeVertex {
                position: (pp + (qp - pp) * s).to_array(),
                num: lerp(p.num, q.num),
                den: lerp(p.den, q.den),
                ..t[0]
            };
            n += 1;
        }
    }
    for k in 1..n.saturating_sub(1) {
        out.extend([poly[0], poly[k], poly[k + 1]]);
    }
}

/// Reorder the triangles of `volume` by the distance of their centroid from `c`, nearest first.
fn sort_near_first(volume: &mut [VolumeVertex], c: Vec3) {
    // In place, by whole triangles (no copy: a 1.4M-triangle volume is 118 MB).
    let whole = volume.len() / 3 * 3;
    let tris: &mut [[VolumeVertex; 3]] = bytemuck::cast_slice_mut(&mut volume[..whole]);
    let key = |t: &[VolumeVertex; 3]| {
        let centroid = t.iter().map(|v| Vec3::from(v.position)).sum::<Vec3>() / 3.0;
        (centroid - c).length_squared()
    };
    tris.sort_unstable_by(|a, b| key(a).total_cmp(&key(b)));
}

/// The part `[x0, y0, x1, y1]` of the light view's image (`[0, 1]²`, y down) that triangles
/// with these corners can cover; all of it if a corner lies behind the light centre.
fn light_view_rect(view: &LightView, points: impl Iterator<Item = Vec3>) -> [f32; 4] {
    let vp = view.view_projection();
    let mut rect = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
    for p in points {
        let c = vp * p.extend(1.0);
        if c.w.is_nan() || c.w <= 1e-6 {
            return [0.0, 0.0, 1.0, 1.0];
        }
        let (u, v) = (c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5);
        rect = [
            rect[0].min(u),
            rect[1].min(v),
            rect[2].max(u),
            rect[3].max(v),
        ];
    }
    if rect[0] > rect[2] {
        return [0.0; 4];
    }
    [
        rect[0].clamp(0.0, 1.0),
        rect[1].clamp(0.0, 1.0),
        rect[2].clamp(0.0, 1.0),
        rect[3].clamp(0.0, 1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(points: [[f32; 3]; 3]) -> Vec<VolumeVertex> {
        points
            .iter()
            .map(|p| VolumeVertex {
                position: *p,
                kind: 3,
                base: 0.5,
                // Affine in position: num = x + 2y, den = 1 + z.
                num: p[0] + 2.0 * p[1],
                den: 1.0 + p[2],
            })
            .collect()
    }

    #[test]
    fn ending_volumes_keeps_the_part_in_reach_with_exact_attributes_and_winding() {
        let light = crate::scene::DiskLight {
            center: Vec3::new(0.0, 4.0, 0.0),
            normal: Vec3::NEG_Y,
            radius: 0.5,
            intensity: 1.0,
        };
        // Heights below the light: 4 - y. A triangle from y = 3 (height 1) down to y = -1 (5).
        let t = tri([[0.0, 3.0, 0.0], [2.0, -1.0, 0.0], [0.0, -1.0, 2.0]]);
        assert_eq!(end_at(&t, &light, 10.0), t, "all in reach");
        assert!(end_at(&t, &light, 0.5).is_empty(), "all beyond");
        let kept = end_at(&t, &light, 3.0);
        assert_eq!(kept.len(), 3, "one corner in reach: one triangle");
        let normal = |v: &[VolumeVertex]| {
            let p = |i: usize| Vec3::from(v[i].position);
            (p(1) - p(0)).cross(p(2) - p(0))
        };
        for k in kept.chunks_exact(3) {
            assert!(normal(k).dot(normal(&t)) > 0.0, "winding kept");
            for v in k {
                let [x, y, z] = v.position;
                assert!(4.0 - y <= 3.0 + 1e-5, "{y}");
                assert!((v.num - (x + 2.0 * y)).abs() < 1e-5 && (v.den - (1.0 + z)).abs() < 1e-5);
                assert_eq!((v.kind, v.base), (3, 0.5));
            }
        }
        // Two corners in reach: a quad, two triangles.
        let t2 = tri([[0.0, 3.0, 0.0], [2.0, 3.0, 0.0], [0.0, -1.0, 2.0]]);
        assert_eq!(end_at(&t2, &light, 3.0).len(), 6);
    }
}
