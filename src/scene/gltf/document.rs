//! The model's default scene: its node instances of mesh primitives, placed by their transforms
//! and counted against the budget before a buffer is read, and its first punctual light.

use std::collections::hash_map::Entry;
use std::collections::HashMap;

use glam::{Mat4, Vec3};

use super::accessors::{read_indices, read_positions};
use super::buffers::Buffers;
use super::{
    GltfLight, GltfModel, MAX_DEPTH, MAX_PLACED_VERTICES, MAX_TRIANGLES, MAX_WELDED_VERTICES,
};
use crate::scene::Mesh;

/// A mesh placed in the model's scene by its node.
struct Instance<'a> {
    mesh: ::gltf::Mesh<'a>,
    world: Mat4,
}

/// A primitive's positions and triangles (indices into them), as read from its accessors.
pub(super) type Primitive = (Vec<Vec3>, Vec<[u32; 3]>);

/// Whether a primitive of this mode is read (triangles, strips, fans), not skipped.
fn has_triangles(mode: ::gltf::mesh::Mode) -> bool {
    use ::gltf::mesh::Mode;
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// How many triangles [`assemble`] makes of `corners` corners in `mode`.
fn triangles_of(mode: ::gltf::mesh::Mode, corners: u64) -> u64 {
    use ::gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip | Mode::TriangleFan => corners.saturating_sub(2),
        Mode::Triangles => corners / 3,
        _ => 0,
    }
}

/// An accessor's count, or fewer: at most what its buffer view's declared length can hold (a
/// larger count is refused with the accessor's own range error when it is read).
fn readable_count(acc: &::gltf::Accessor) -> u64 {
    let count = acc.count() as u64;
    match acc.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(acc.size()).max(1) as u64;
            count.min((view.length() as u64 / stride).saturating_add(1))
        }
        None => count,
    }
}

/// The triangles and positions the scene's instances would place, from the accessors' counts,
/// before a byte of a buffer is read: a small file can place one big primitive many times
/// (2 KB of nodes over a 60 KB strip is 18M triangles), so the budget is checked here, not
/// once they are made.
fn check_instances_budget(instances: &[Instance]) -> Result<(), String> {
    let (mut assembled, mut placed) = (0u64, 0u64);
    for inst in instances {
        for primitive in inst.mesh.primitives() {
            let mode = primitive.mode();
            if !has_triangles(mode) {
                continue;
            }
            let vertices = primitive
                .get(&::gltf::Semantic::Positions)
                .map_or(0, |a| readable_count(&a));
            let corners = primitive.indices().map_or(vertices, |a| readable_count(&a));
            assembled = assembled.saturating_add(triangles_of(mode, corners));
            placed = placed.saturating_add(vertices);
        }
        if assembled > MAX_TRIANGLES as u64 || placed > MAX_PLACED_VERTICES as u64 {
            return Err(format!(
                "its scene places at least {assembled} triangles and {placed} vertices over its                  node instances (counted from the accessors, before reading them): the budget                  is {MAX_TRIANGLES} triangles per scene (MAX_SCENE_TRIANGLES) and                  {MAX_PLACED_VERTICES} placed vertices, three per triangle"
            ));
        }
    }
    Ok(())
}

pub(super) fn read_document(
    doc: &::gltf::Document,
    buffers: &mut Buffers,
) -> Result<GltfModel, String> {
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| "has no scene: expected at least one entry in `scenes`".to_string())?;
    let mut warnings = Vec::new();
    let mut instances: Vec<Instance> = Vec::new();
    let mut light = None;
    // Depth-first over the node forest, without recursion; each node at most once.
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(::gltf::Node, Mat4, usize)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    stack.reverse();
    while let Some((node, parent, depth)) = stack.pop() {
        let i = node.index();
        if seen.get(i).copied().unwrap_or(true) {
            return Err(format!(
                "node {i} is reached twice from scene {}: the node hierarchy must be a tree",
                scene.index()
            ));
        }
        seen[i] = true;
        if depth > MAX_DEPTH {
            return Err(format!(
                "the node hierarchy is deeper than {MAX_DEPTH} levels (at node {i})"
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(format!(
                "node {i}: its transform has a number that is not finite"
            ));
        }
        if let Some(mesh) = node.mesh() {
            instances.push(Instance { mesh, world });
        }
        if let Some(l) = node.light() {
            use ::gltf::khr_lights_punctual::Kind;
            let position = world.transform_point3(Vec3::ZERO);
            match l.kind() {
                Kind::Spot { .. } | Kind::Point if light.is_none() => {
                    let spot = matches!(l.kind(), Kind::Spot { .. });
                    let direction = if spot {
                        world.transform_vector3(Vec3::NEG_Z).try_normalize()
                    } else {
                        Some(Vec3::NEG_Y)
                    };
                    match direction {
                        Some(direction) if position.is_finite() => {
                            light = Some(GltfLight {
                                position,
                                direction,
                                kind: if spot { "spot" } else { "point" },
                            })
                        }
                        _ => warnings.push(format!(
                            "light {} on node {i}: its transform collapses it; ignored",
                            l.index()
                        )),
                    }
                }
                Kind::Directional => warnings.push(format!(
                    "light {} on node {i} is directional (no position): ignored; a disk light \
                     needs a spot or point light",
                    l.index()
                )),
                _ => warnings.push(format!(
                    "light {} on node {i}: only the first spot or point light is used",
                    l.index()
                )),
            }
        }
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }

    check_instances_budget(&instances)?;

    let mut positions: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    // Each primitive's positions and triangles, read once however many nodes use it.
    let mut read: HashMap<(usize, usize), Primitive> = HashMap::new();
    let mut skipped = 0usize;
    let mut primitives = 0usize;
    for inst in &instances {
        for primitive in inst.mesh.primitives() {
            let what = format!(
                "mesh {}, primitive {}",
                inst.mesh.index(),
                primitive.index()
            );
            let mode = primitive.mode();
            if !has_triangles(mode) {
                skipped += 1;
                continue;
            }
            primitives += 1;
            let (local, tris) = match read.entry((inst.mesh.index(), primitive.index())) {
                Entry::Occupied(e) => &*e.into_mut(),
                Entry::Vacant(e) => {
                    let position = primitive
                        .get(&::gltf::Semantic::Positions)
                        .ok_or_else(|| format!("{what} has no POSITION attribute"))?;
                    let local = read_positions(&position, &format!("POSITION of {what}"), buffers)?;
                    let corners = match primitive.indices() {
                        Some(acc) => {
                            read_indices(&acc, &format!("indices of {what}"), buffers, local.len())?
                        }
                        None => (0..local.len() as u32).collect(),
                    };
                    let tris = assemble(mode, &corners);
                    &*e.insert((local, tris))
                }
            };
            let flip = Mat4::determinant(&inst.world) < 0.0;
            let mut remap = Vec::with_capacity(local.len());
            for p in local {
                let p = inst.world.transform_point3(*p);
                if !p.is_finite() {
                    return Err(format!(
                        "{what}: a position is not finite once placed by its node"
                    ));
                }
                let p = Vec3::new(p.x + 0.0, p.y + 0.0, p.z + 0.0);
                let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                let next = positions.len() as u32;
                let id = *welded.entry(key).or_insert_with(|| {
                    positions.push(p);
                    next
                });
                remap.push(id);
            }
            if positions.len() > MAX_WELDED_VERTICES {
                return Err(format!(
                    "has more than {MAX_WELDED_VERTICES} distinct vertices over its node \
                     instances, reached at {what}: the budget is {MAX_WELDED_VERTICES} vertices \
                     per scene (MAX_SCENE_VERTICES)"
                ));
            }
            for &[a, b, c] in tris {
                let (a, b, c) = (remap[a as usize], remap[b as usize], remap[c as usize]);
                if a != b && b != c && a != c {
                    triangles.push(if flip { [a, c, b] } else { [a, b, c] });
                }
            }
        }
    }
    if skipped > 0 {
        warnings.push(format!(
            "{skipped} point or line primitive{} skipped: only triangles cast shadows",
            if skipped == 1 { "" } else { "s" }
        ));
    }
    if triangles.is_empty() {
        return Err(format!(
            "contains no triangles: scene {} has {primitives} triangle primitive{} with no \
             non-degenerate triangle{}",
            scene.index(),
            if primitives == 1 { "" } else { "s" },
            if skipped > 0 {
                format!(" and {skipped} point or line primitives")
            } else {
                String::new()
            }
        ));
    }
    Ok(GltfModel {
        mesh: Mesh::new(positions, triangles),
        light,
        warnings,
    })
}

/// Triangles (as indices into the primitive's vertices) from a triangle list, strip or fan.
fn assemble(mode: ::gltf::mesh::Mode, corners: &[u32]) -> Vec<[u32; 3]> {
    use ::gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => corners
            .windows(3)
            .enumerate()
            .map(|(i, w)| {
                if i % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[1], w[0], w[2]]
                }
            })
            .collect(),
        Mode::TriangleFan => match corners.split_first() {
            Some((&first, rest)) => rest.windows(2).map(|w| [first, w[0], w[1]]).collect(),
            None => Vec::new(),
        },
        _ => corners
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_become_triangles() {
        use ::gltf::mesh::Mode;
        assert_eq!(
            assemble(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [2, 1, 3]]
        );
        assert_eq!(
            assemble(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(assemble(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]]);
    }
}
