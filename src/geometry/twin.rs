//! The CPU twin of the D-buffer: what the light pass stores along a ray from the light centre,
//! and what the camera pass computes from it, evaluated exactly by ray casting (no texels, no
//! interpolation). The GPU passes are tested against it.
//!
//! Channel rules along the ray from `c` with unit direction `w` (the light pass must do the same):
//! - `|cx_o|`: the nearest hit of any scene triangle.
//! - `|cx_uv|`: for each caster, the **nearest umbra exit** — a hit on an umbra-volume triangle
//!   whose normal faces away from `c` (umbra quads, category-A silhouette faces; category-B
//!   silhouette faces face `c` and are culled). Untrimmed umbra quads cross each other at convex
//!   corners and beyond the apex of a closing umbra; the true boundary is always the first exit.
//!   Over casters the **farthest** of these wins (Jakobsen et al. 2004, §4, overlapping casters).
//! - `|cx_pv|`: the **nearest penumbra entry** — a hit on a penumbra quad or fan whose normal
//!   faces `c`. A ray from `c` enters a caster's penumbra once and never leaves it (every
//!   penumbra plane separates the disk, `c` included, from the caster), so along the ray the union
//!   of several penumbrae — overlapping casters, the parts of a concave one — starts at the
//!   nearest entry. The paper's "farthest wins" would call the points between two entries lit; on
//!   the built-ins it triples the class mismatch of the concave and overlapping scenes (measured in
//!   `tests/cpu/twin_builtins.rs`). For a single convex caster the two rules agree.
//! - `|cx_s|`: eq. (2) from the fragment that won each volume channel, so it is kept per volume
//!   (`s_u`, `s_p`), as `dbuffer.exr` + `dbuffer_s.exr` store it.
//!
//! The shaded point `x` at `D = |cx|` is hidden from `c` when `D > |cx_o| + bias`; then `t` comes
//! from the umbra channels, otherwise from the penumbra ones ([`super::visibility`]).

use glam::Vec3;

use super::bvh::Bvh;
use super::outline::Outline2d;
use super::visibility::{t_hidden, t_visible, Branch, VtVariant};
use super::volumes::{CasterGeometry, FanCorner, VolumeVertex};
use super::wedges::DiskFrame;
use crate::scene::{AreaLight, Scene};

/// One D-buffer texel: the four channels along one ray from the light centre.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Texel {
    /// `|cx_o|`: nearest scene surface.
    pub o: Option<f32>,
    /// `|cx_uv|`: the umbra boundary (see the module rules).
    pub u: Option<f32>,
    /// `|cx_s|` from the fragment that won `u`.
    pub s_u: f32,
    /// `|cx_pv|`: the penumbra boundary.
    pub p: Option<f32>,
    /// `|cx_s|` from the fragment that won `p`.
    pub s_p: f32,
    /// The lit side of the winning umbra and penumbra triangles, in the light's plane
    /// ([`super::volume_vertices::lit_side`]): the `.zw` of the GPU's volume channels.
    pub side_u: [f32; 2],
    pub side_p: [f32; 2],
    /// Where the winning umbra or penumbra triangle is a closing fan: its silhouette corner,
    /// for V exact.
    pub corner_u: Option<FanCorner>,
    pub corner_p: Option<FanCorner>,
}

/// What the camera pass computes for one shaded point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwinSample {
    /// `|cx|`.
    pub d: f32,
    pub texel: Texel,
    pub hidden: bool,
    pub t: f64,
    pub branch: Branch,
}

impl TwinSample {
    /// The lit side of the channel `t` came from (umbra when hidden from the centre).
    pub fn side(&self) -> [f32; 2] {
        if self.hidden {
            self.texel.side_u
        } else {
            self.texel.side_p
        }
    }

    /// The silhouette corner of the channel `t` came from, where a fan won it.
    pub fn corner(&self) -> Option<FanCorner> {
        if self.hidden {
            self.texel.corner_u
        } else {
            self.texel.corner_p
        }
    }
}

/// Relative bias of the hidden-from-centre test `D > |cx_o| (1 + HIDDEN_BIAS) + HIDDEN_BIAS`.
pub const HIDDEN_BIAS: f32 = 1e-4;

struct CasterVolumes {
    umbra: Bvh,
    umbra_attrs: Vec<VolumeVertex>,
    umbra_corners: Vec<Option<FanCorner>>,
    penumbra: Bvh,
    penumbra_attrs: Vec<VolumeVertex>,
    penumbra_corners: Vec<Option<FanCorner>>,
}

/// The D-buffer lookup and camera-pass arithmetic on the CPU.
pub struct DBufferTwin {
    light: AreaLight,
    outline: Outline2d,
    /// The light in its own plane for the receiver's horizon and the fans' corners.
    frame: DiskFrame,
    /// `--dbuffer-horizon` (on unless set off): [`Self::visibility_on`] takes at most the part
    /// of the light in front of the receiver's own plane.
    pub horizon: bool,
    /// `--dbuffer-corners` (on unless set off): V exact behind a closing fan from the fan's
    /// corner where it can be trusted ([`DiskFrame::corner_visibility`]).
    pub corners: bool,
    surfaces: Bvh,
    casters: Vec<CasterVolumes>,
}

impl DBufferTwin {
    /// Build from every scene triangle (for `|cx_o|`) and each caster's volumes. The D-buffer
    /// needs a disk light (its methods refuse a line light before anything is built); for a
    /// line light this is the twin of a zero-radius disk at the midpoint, facing down.
    pub fn new(scene: &Scene, casters: &[CasterGeometry]) -> Self {
        let light = scene.light.area_or_centre();
        Self::from_parts(light, scene.all_triangles(), casters)
    }

    pub fn from_parts(
        light: AreaLight,
        surfaces: Vec<[Vec3; 3]>,
        casters: &[CasterGeometry],
    ) -> Self {
        let casters = casters
            .iter()
            .map(|g| {
                let (mut ut, mut ua, mut uc, mut pt, mut pa, mut pc) =
                    (vec![], vec![], vec![], vec![], vec![], vec![]);
                for i in 0..g.volumes.triangle_count() {
                    let (tri, attrs) = g.volumes.triangle(i);
                    let corner = g.volumes.corner_of(i).copied();
                    if attrs.kind.is_umbra() {
                        ut.push(tri);
                        ua.push(*attrs);
                        uc.push(corner);
                    } else {
                        pt.push(tri);
                        pa.push(*attrs);
                        pc.push(corner);
                    }
                }
                CasterVolumes {
                    umbra: Bvh::build(ut),
                    umbra_attrs: ua,
                    umbra_corners: uc,
                    penumbra: Bvh::build(pt),
                    penumbra_attrs: pa,
                    penumbra_corners: pc,
                }
            })
            .collect();
        Self {
            outline: Outline2d::of(&light),
            frame: DiskFrame::new(&light),
            horizon: true,
            corners: true,
            light,
            surfaces: Bvh::build(surfaces),
            casters,
        }
    }

    pub fn light(&self) -> &AreaLight {
        &self.light
    }

    /// The light in its own plane, as `V exact` needs it.
    pub fn outline(&self) -> &Outline2d {
        &self.outline
    }

    /// The D-buffer channels along the ray from the light centre with unit direction `w`.
    pub fn texel(&self, w: Vec3) -> Texel {
        let c = self.light.center;
        let mut texel = Texel {
            o: self
                .surfaces
                .closest_hit(c, w, 0.0, f32::INFINITY)
                .map(|h| h.t),
            ..Texel::default()
        };
        let facing = |tri: &[Vec3; 3]| (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(w);
        for caster in &self.casters {
            // Nearest umbra exit of this caster.
            let mut exit: Option<(f32, u32)> = None;
            caster.umbra.for_each_hit(c, w, 0.0, f32::INFINITY, |h| {
                if facing(caster.umbra.triangle(h.triangle as usize)) > 0.0
                    && exit.is_none_or(|(t, _)| h.t < t)
                {
                    exit = Some((h.t, h.triangle));
                }
            });
            if let Some((t, k)) = exit {
                if texel.u.is_none_or(|u| t > u) {
                    texel.u = Some(t);
                    let tri = *caster.umbra.triangle(k as usize);
                    texel.side_u = super::volume_vertices::lit_side(tri, &self.light);
                    texel.corner_u = caster.umbra_corners[k as usize];
                    let attrs = &caster.umbra_attrs[k as usize];
                    texel.s_u = attrs.edge_plane_distance(c + t * w, w, &self.light);
                }
            }
            // Nearest penumbra entry over all casters.
            caster.penumbra.for_each_hit(c, w, 0.0, f32::INFINITY, |h| {
                if facing(caster.penumbra.triangle(h.triangle as usize)) < 0.0
                    && texel.p.is_none_or(|p| h.t < p)
                {
                    texel.p = Some(h.t);
                    let tri = *caster.penumbra.triangle(h.triangle as usize);
                    texel.side_p = super::volume_vertices::lit_side(tri, &self.light);
                    texel.corner_p = caster.penumbra_corners[h.triangle as usize];
                    let attrs = &caster.penumbra_attrs[h.triangle as usize];
                    texel.s_p = attrs.edge_plane_distance(c + h.t * w, w, &self.light);
                }
            });
        }
        texel
    }

    /// The camera pass at world point `x`: `|cx|`, the texel, the branch and `t`.
    pub fn sample(&self, x: Vec3) -> TwinSample {
        let v = x - self.light.center;
        let d = v.length();
        let height = self.light.height_of(x);
        if height.is_nan() || height <= 0.0 || !d.is_finite() {
            // Behind the one-sided light (or not a point): it receives nothing.
            return TwinSample {
                d,
                texel: Texel::default(),
                hidden: true,
                t: 0.0,
                branch: Branch::Umbra,
            };
        }
        let w = v / d;
        let texel = self.texel(w);
        let hidden = texel
            .o
            .is_some_and(|o| d > o * (1.0 + HIDDEN_BIAS) + HIDDEN_BIAS);
        let (t, branch) = if hidden {
            t_hidden(f64::from(d), f64::from(texel.s_u), texel.u.map(f64::from))
        } else {
            t_visible(f64::from(d), f64::from(texel.s_p), texel.p.map(f64::from))
        };
        TwinSample {
            d,
            texel,
            hidden,
            t,
            branch,
        }
    }

    /// `V(t)` at `x` with the chosen variant: the lookup alone, whatever surface `x` is on.
    /// V exact where a closing fan won the channel at an [`FanCorner::exact`] corner: the chord's
    /// V moved toward the light less the caster's corner seen from `x`, as far as
    /// [`DiskFrame::corner_visibility`] trusts the corner there.
    pub fn visibility(&self, x: Vec3, vt: VtVariant) -> f64 {
        let s = self.sample(x);
        let chord = vt.apply_toward(s.t, s.side(), &self.outline);
        let in_penumbra = matches!(s.branch, Branch::PenumbraHidden | Branch::PenumbraVisible);
        if vt == VtVariant::Exact && in_penumbra && self.corners {
            let corner = s.corner().filter(|c| c.exact);
            if let Some((v, weight)) = corner.and_then(|c| {
                self.frame
                    .corner_visibility(x, c.apex, c.ends, c.normals, c.supports)
            }) {
                return chord + weight * (v - chord);
            }
        }
        chord
    }

    /// What the camera pass gives at `x` on a surface of normal `n`: nothing on a side turned
    /// away from the light's centre, else [`Self::visibility`], with [`Self::horizon`] at most
    /// the part of the light in front of the surface's own plane (a caster's face whose plane
    /// cuts the light is on its own silhouette, where no volume darkens it).
    pub fn visibility_on(&self, x: Vec3, n: Vec3, vt: VtVariant) -> f64 {
        let facing = n.dot(self.light.center - x);
        if facing.is_nan() || facing <= 0.0 {
            return 0.0;
        }
        let v = self.visibility(x, vt);
        if self.horizon {
            v.min(self.frame.horizon_fraction(x, n))
        } else {
            v
        }
    }
}
