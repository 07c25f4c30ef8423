//! The CPU twin of `linear-ssm`'s skin extraction (`shaders/passes/ssm_skins.wgsl`): the "skins"
//! or "phantom polygons" of Heidrich et al. 2000, §3.2, from one light sample's distance map.
//!
//! The paper triangulates every depth sample of a map, warps the triangles into the other
//! sample's view and keeps the ones that span a depth discontinuity: they join an occluder to the
//! receiver behind it, and wherever the other sample sees one, a penumbra lies. Here each 2×2
//! cell of texel centres is a quad of two triangles (diagonal from its first to its last corner);
//! a cell whose four distances are discontinuous (the largest over the smallest beyond `1 + τ`,
//! or some texels with a surface and some without) is split at the largest gap between its
//! sorted values into near (the occluder: value 0) and far (the receiver: value 1) corners, and
//! each of its triangles with both kinds of corner is a skin. The paper finds discontinuities
//! with a Laplacian-of-Gaussian filter on the depth map; this per-cell test plays its role.
//!
//! A texel's world point is the sample point plus its distance along the direction through the
//! texel's centre (`NO_SURFACE` texels at the view's far distance).

use glam::{Mat4, Vec3, Vec4};

/// Relative gap between a cell's distances that makes it a discontinuity (τ).
pub const SKIN_TAU: f32 = 0.02;
/// Distances at or above this are "no surface" (the maps' `NO_SURFACE` clear value is 3e38).
pub const NO_SURFACE_AT: f32 = 1.5e38;

/// One corner of a skin triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkinCorner {
    pub position: Vec3,
    /// 0 on the occluder, 1 on the receiver.
    pub value: f32,
    /// The texel it stands for.
    pub texel: [u32; 2],
}

/// Which of a cell's four distances (order: (x, y), (x+1, y), (x, y+1), (x+1, y+1)) are near,
/// or `None` when the cell is continuous (or holds no surface at all).
pub fn cell_split(d: [f32; 4], tau: f32) -> Option<[bool; 4]> {
    let surface = d.map(|v| v < NO_SURFACE_AT);
    if !surface.iter().any(|&s| s) {
        return None;
    }
    let mut sorted = d.map(|v| if v < NO_SURFACE_AT { v } else { f32::INFINITY });
    sorted.sort_by(f32::total_cmp);
    let mixed = surface.iter().any(|&s| !s);
    if !mixed && sorted[3] <= sorted[0] * (1.0 + tau) {
        return None;
    }
    // The largest step between neighbours in sorted order (infinity wins for a mixed cell).
    let mut split = 0;
    let mut widest = -1.0f32;
    for i in 0..3 {
        let step = sorted[i + 1] - sorted[i];
        if step > widest {
            widest = step;
            split = i;
        }
    }
    let limit = sorted[split];
    Some(d.map(|v| v < NO_SURFACE_AT && v <= limit))
}

/// The two triangles of cell (`x`, `y`), as indices into the corner order of [`cell_split`].
pub const CELL_TRIANGLES: [[usize; 3]; 2] = [[0, 3, 1], [0, 2, 3]];

/// The world point of texel (`x`, `y`) at distance `d` from `point`, for a map of `size`² texels
/// drawn with a view-projection whose inverse is `inv_view_proj`.
pub fn texel_point(inv_view_proj: Mat4, point: Vec3, size: u32, x: u32, y: u32, d: f32) -> Vec3 {
    let s = size.max(1) as f32;
    let ndc_x = (x as f32 + 0.5) / s * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / s * 2.0;
    let p = inv_view_proj * Vec4::new(ndc_x, ndc_y, 0.5, 1.0);
    let dir = (p.truncate() / p.w - point).normalize_or_zero();
    point + dir * d
}

/// Every skin triangle of a `size`² distance map (row-major, row 0 at the top), in cell order.
pub fn skins(
    map: &[f32],
    size: u32,
    inv_view_proj: Mat4,
    point: Vec3,
    far: f32,
    tau: f32,
) -> Vec<[SkinCorner; 3]> {
    let mut out = Vec::new();
    let n = size as usize;
    if map.len() < n * n || n < 2 {
        return out;
    }
    for y in 0..size - 1 {
        for x in 0..size - 1 {
            let texels = [[x, y], [x + 1, y], [x, y + 1], [x + 1, y + 1]];
            let d = texels.map(|[tx, ty]| map[ty as usize * n + tx as usize]);
            let Some(near) = cell_split(d, tau) else {
                continue;
            };
            for tri in CELL_TRIANGLES {
                if tri.iter().all(|&i| near[i]) || tri.iter().all(|&i| !near[i]) {
                    continue;
                }
                out.push(tri.map(|i| {
                    let [tx, ty] = texels[i];
                    let dist = if d[i] < NO_SURFACE_AT { d[i] } else { far };
                    SkinCorner {
                        position: texel_point(inv_view_proj, point, size, tx, ty, dist),
                        value: if near[i] { 0.0 } else { 1.0 },
                        texel: [tx, ty],
                    }
                }));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_splits_at_its_largest_gap() {
        assert_eq!(cell_split([2.0, 2.01, 2.0, 2.02], SKIN_TAU), None);
        assert_eq!(
            cell_split([2.0, 4.0, 2.05, 4.1], SKIN_TAU),
            Some([true, false, true, false])
        );
        // Three near, one far; and a cell at the edge of the surfaces.
        assert_eq!(
            cell_split([2.0, 2.0, 2.0, 5.0], SKIN_TAU),
            Some([true, true, true, false])
        );
        assert_eq!(
            cell_split([3.0e38, 4.0, 3.0e38, 4.0], SKIN_TAU),
            Some([false, true, false, true])
        );
        assert_eq!(cell_split([3.0e38; 4], SKIN_TAU), None);
    }

    /// A synthetic map: an occluder at distance 2 over the left half of the columns, the
    /// receiver at 4 elsewhere. Skins sit on the boundary column pair only, 0 on the occluder
    /// side and 1 on the receiver side, two per row of cells.
    #[test]
    fn skins_lie_on_the_discontinuity_only() {
        let size = 8u32;
        let map: Vec<f32> = (0..size * size)
            .map(|i| if i % size < 3 { 2.0 } else { 4.0 })
            .collect();
        let skins = skins(&map, size, Mat4::IDENTITY, Vec3::ZERO, 100.0, SKIN_TAU);
        assert_eq!(skins.len(), 2 * (size as usize - 1));
        for t in &skins {
            for c in t {
                assert!(c.texel[0] == 2 || c.texel[0] == 3, "{c:?}");
                assert_eq!(c.value, if c.texel[0] == 2 { 0.0 } else { 1.0 });
                let expect = if c.texel[0] == 2 { 2.0 } else { 4.0 };
                assert!((c.position.length() - expect).abs() < 1e-5, "{c:?}");
            }
        }
    }
}
