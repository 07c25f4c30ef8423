//! What the fused method gathers on the CPU once per light or caster move, for its light passes
//! on the GPU (`render::methods::dbuffer_fused`) and its twin ([`super::FusedTwin`]) alike: the
//! candidate edges of every caster, how far below the light the receivers reach, each edge's
//! proxy in the light view and the part of the light view they cover.

use glam::{Mat4, Vec2};

use super::chord::{candidate_edges, FusedEdge};
use super::lists::proxy_hull;
use crate::geometry::light_view::LightView;
use crate::geometry::volume_vertices::{light_view_rect, union_all};
use crate::geometry::{PreparedCasters, SceneGeometry};
use crate::scene::{AreaLight, Scene};

/// Every candidate edge of the casters (`prepared`, with their face classes in `geometry`),
/// caster by caster: an edge carries its caster's index.
pub fn scene_candidate_edges(
    prepared: &PreparedCasters,
    geometry: &SceneGeometry,
) -> Vec<FusedEdge> {
    prepared
        .meshes
        .iter()
        .zip(&geometry.casters)
        .enumerate()
        .flat_map(|(k, (mesh, g))| candidate_edges(mesh, &g.classes, k as u32))
        .collect()
}

/// The largest height below `light` of any point of the scene's meshes (0 for none): the
/// proxies reach down to it.
pub fn max_receiver_height(scene: &Scene, light: &AreaLight) -> f32 {
    scene
        .objects
        .iter()
        .flat_map(|o| o.mesh.positions.iter())
        .map(|&p| light.height_of(p))
        .filter(|h| h.is_finite())
        .fold(0.0f32, f32::max)
}

/// The margin of `edge`'s proxy at each end: three list texels' footprint at the end's distance
/// from the light's centre (`half_slope`: half a list texel's diagonal, as a slope), which the
/// twin's proxy test holds.
pub fn proxy_pad(edge: &FusedEdge, light: &AreaLight, half_slope: f32) -> [f32; 2] {
    [edge.a, edge.b].map(|p| 3.0 * p.distance(light.center) * half_slope)
}

/// `edge`'s proxy as the light pass draws it: its hull in light-view NDC (`view_proj`), for
/// receivers no deeper than `h_max`, padded by [`proxy_pad`].
pub fn edge_proxy(
    edge: &FusedEdge,
    light: &AreaLight,
    h_max: f32,
    half_slope: f32,
    view_proj: &Mat4,
) -> Vec<Vec2> {
    let pad = proxy_pad(edge, light, half_slope);
    proxy_hull(edge, light, h_max, pad, view_proj)
}

/// The part of the light view (`[0, 1]²`, y down, as `[x0, y0, x1, y1]`) that the scene's casters
/// and the proxies' `corners` (light-view NDC) cover: outside it no texel has a crossing or a
/// list.
pub fn covered_rect(
    scene: &Scene,
    view: &LightView,
    corners: impl Iterator<Item = [f32; 2]>,
) -> [f32; 4] {
    let casters = scene
        .casters()
        .flat_map(|o| o.mesh.positions.iter().copied())
        .filter(|p| p.is_finite());
    let corners = corners.map(|[x, y]| {
        let [u, v] = [
            x.clamp(-1.0, 1.0) * 0.5 + 0.5,
            0.5 - y.clamp(-1.0, 1.0) * 0.5,
        ];
        [u, v, u, v]
    });
    union_all(corners.chain([light_view_rect(view, casters)]))
}
