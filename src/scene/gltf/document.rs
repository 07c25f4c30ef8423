//! The model's scene: its node instances of mesh primitives, placed by their transforms and
//! counted against the budget before a buffer is read, and its first punctual light. Only what
//! the scene reaches is read (and so validated): nodes, meshes, their POSITION and indices
//! accessors, the lights; materials, textures, animations, skins and cameras are never read.

use std::collections::hash_map::Entry;
use std::collections::HashMap;

use glam::{Mat4, Quat, Vec3};

use super::accessors::{parse_accessor, read_indices, read_positions, Accessor};
use super::buffers::Buffers;
use super::json::{key_path, Doc, Obj};
use super::skin::{blended, influences, joint_matrices, place, Worlds};
use super::{
    GltfLight, GltfModel, MAX_DEPTH, MAX_PLACED_VERTICES, MAX_TRIANGLES, MAX_WELDED_VERTICES,
};
use crate::scene::Mesh;

/// A primitive's positions and triangles (indices into them), as read from its accessors.
pub(super) type Primitive = (Vec<Vec3>, Vec<[u32; 3]>);

/// A skinned primitive's joints and weights, four a vertex.
type Influences = (Vec<f32>, Vec<f32>);

/// Primitive modes (glTF's numbers).
const TRIANGLES: u64 = 4;
const TRIANGLE_STRIP: u64 = 5;
const TRIANGLE_FAN: u64 = 6;

/// A primitive of a mesh, as the JSON gives it (only triangle primitives have accessors read).
struct PrimitiveDef {
    index: usize,
    mode: u64,
    position: Option<Accessor>,
    indices: Option<Accessor>,
    /// JOINTS_0 and WEIGHTS_0 accessor indices, read only for a skinned instance.
    skinning: Option<(usize, usize)>,
}

/// A mesh placed in the model's scene by its node (or, skinned, by its skin's joints).
struct Instance {
    mesh: usize,
    world: Mat4,
    /// `(skin, node)` for a skinned mesh.
    skin: Option<(usize, usize)>,
}

/// Whether a primitive of this mode is read (triangles, strips, fans), not skipped.
fn has_triangles(mode: u64) -> bool {
    matches!(mode, TRIANGLES | TRIANGLE_STRIP | TRIANGLE_FAN)
}

/// How many triangles [`assemble`] makes of `corners` corners in `mode`.
fn triangles_of(mode: u64, corners: u64) -> u64 {
    match mode {
        TRIANGLE_STRIP | TRIANGLE_FAN => corners.saturating_sub(2),
        TRIANGLES => corners / 3,
        _ => 0,
    }
}

/// Which scene to draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneChoice {
    /// `Some(n)`: scene `n` (`--scene N`); `None`: the file's default scene (`scene`), else
    /// its first.
    pub scene: Option<usize>,
}

/// What reading a document found along the way, for the warnings.
#[derive(Default)]
struct Seen {
    skinned: Vec<usize>,
    morphed: usize,
    instanced: usize,
    lines: usize,
}

/// Reads mesh `m` (its primitives' modes and accessors), checking what is used.
fn parse_mesh(
    doc: &Doc,
    m: usize,
    from: &str,
    seen: &mut Seen,
) -> Result<Vec<PrimitiveDef>, String> {
    let mesh = doc.element("meshes", m, from)?;
    let list = match mesh.get("primitives") {
        Some(serde_json::Value::Array(a)) => a,
        _ => {
            return Err(format!(
                "invalid glTF: {} is missing or not an array",
                mesh.at("primitives")
            ))
        }
    };
    let mut out = Vec::with_capacity(list.len());
    for (p, v) in list.iter().enumerate() {
        let path = format!("{}[{p}]", mesh.at("primitives"));
        let Some(map) = v.as_object() else {
            return Err(format!("invalid glTF: {path} is not an object"));
        };
        let prim = Obj { map, path };
        let mode = prim.opt_uint("mode")?.unwrap_or(TRIANGLES);
        if mode > 6 {
            return Err(format!(
                "invalid glTF: {} is {mode}: not a glTF primitive mode (0 to 6)",
                prim.at("mode")
            ));
        }
        if !has_triangles(mode) {
            seen.lines += 1;
            out.push(PrimitiveDef {
                index: p,
                mode,
                position: None,
                indices: None,
                skinning: None,
            });
            continue;
        }
        let attributes = prim
            .opt_obj("attributes")?
            .ok_or_else(|| format!("invalid glTF: {} is missing", prim.at("attributes")))?;
        let position = match attributes.opt_index("POSITION")? {
            Some(i) => Some(parse_accessor(
                doc,
                i,
                &key_path(&attributes.path, "POSITION"),
            )?),
            None => None,
        };
        let indices = match prim.opt_index("indices")? {
            Some(i) => Some(parse_accessor(doc, i, &prim.at("indices"))?),
            None => None,
        };
        // Draco: the accessors are the decoded data's description; without a bufferView they
        // hold nothing dbuffer can read (zeros), so the primitive is refused by name.
        if prim.has_extension("KHR_draco_mesh_compression")
            && position.as_ref().is_some_and(|a| a.view.is_none())
        {
            return Err(format!(
                "{} is compressed with KHR_draco_mesh_compression, which dbuffer cannot \
                 decode (no maintained Draco decoder in Rust yet), and has no uncompressed \
                 fallback",
                prim.path
            ));
        }
        if matches!(prim.get("targets"), Some(serde_json::Value::Array(t)) if !t.is_empty()) {
            seen.morphed += 1;
        }
        let skinning = match (
            attributes.opt_index("JOINTS_0").ok().flatten(),
            attributes.opt_index("WEIGHTS_0").ok().flatten(),
        ) {
            (Some(j), Some(w)) => Some((j, w)),
            _ => None,
        };
        out.push(PrimitiveDef {
            index: p,
            mode,
            position,
            indices,
            skinning,
        });
    }
    Ok(out)
}

/// The node's local transform: `matrix`, else translation · rotation · scale.
pub(super) fn local_transform(node: &Obj) -> Result<Mat4, String> {
    if let Some(m) = node.opt_floats("matrix", 16)? {
        let mut a = [0f32; 16];
        a.copy_from_slice(&m);
        return Ok(Mat4::from_cols_array(&a));
    }
    let t = node.opt_floats("translation", 3)?.unwrap_or(vec![0.0; 3]);
    let r = node
        .opt_floats("rotation", 4)?
        .unwrap_or(vec![0.0, 0.0, 0.0, 1.0]);
    let s = node.opt_floats("scale", 3)?.unwrap_or(vec![1.0; 3]);
    let q = Quat::from_xyzw(r[0], r[1], r[2], r[3]);
    // glTF asks for a unit quaternion; exporters round. One that cannot be normalised (zero,
    // not finite) is refused rather than turned into a collapse.
    let length = q.length();
    let q = match length {
        l if l.is_finite() && l > 0.0 => q / l,
        _ if !q.is_finite() => Quat::NAN,
        _ => {
            return Err(format!(
                "invalid glTF: {} is not a rotation (a quaternion of length 0)",
                node.at("rotation")
            ))
        }
    };
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::new(s[0], s[1], s[2]),
        q,
        Vec3::new(t[0], t[1], t[2]),
    ))
}

/// The light `l` of KHR_lights_punctual: its type, if the file says one dbuffer knows.
fn light_kind(doc: &Doc, l: usize) -> Option<&str> {
    doc.root()
        .get("extensions")?
        .get("KHR_lights_punctual")?
        .get("lights")?
        .get(l)?
        .get("type")?
        .as_str()
}

/// The roots to walk: the chosen scene's nodes, or (a file without `scenes`) every node that
/// is no node's child; and a note saying which.
fn roots(
    doc: &Doc,
    choice: SceneChoice,
    notes: &mut Vec<String>,
) -> Result<(Vec<usize>, String), String> {
    let n = doc.len("scenes");
    let wanted = match choice.scene {
        Some(s) if s >= n => {
            return Err(format!(
                "--scene {s}: the file has {n} scene{}{}",
                if n == 1 { "" } else { "s" },
                if n > 0 {
                    format!(" (0 to {})", n - 1)
                } else {
                    String::new()
                }
            ))
        }
        Some(s) => Some(s),
        None => match doc.root().opt_index("scene")? {
            Some(s) if s < n => Some(s),
            Some(s) => {
                return Err(format!(
                    "invalid glTF: scene is {s}, but the file has {n} scene{}",
                    if n == 1 { "" } else { "s" }
                ))
            }
            None if n > 0 => Some(0),
            None => None,
        },
    };
    if let Some(s) = wanted {
        let scene = doc.element("scenes", s, "scene")?;
        let nodes = scene.opt_indices("nodes")?.unwrap_or_default();
        return Ok((nodes, format!("scene {s}")));
    }
    // No scenes: what viewers show, every root node.
    let count = doc.len("nodes");
    let mut child = vec![false; count];
    for i in 0..count {
        let node = doc.element("nodes", i, "nodes")?;
        for c in node.opt_indices("children")?.unwrap_or_default() {
            if let Some(x) = child.get_mut(c) {
                *x = true;
            }
        }
    }
    let roots: Vec<usize> = (0..count).filter(|&i| !child[i]).collect();
    if roots.is_empty() {
        return Ok((roots, "a file without scenes or nodes".into()));
    }
    notes.push(format!(
        "has no scenes: drawn from its {} root node{} (what viewers show)",
        roots.len(),
        if roots.len() == 1 { "" } else { "s" }
    ));
    Ok((roots, "its root nodes".into()))
}

pub(super) fn read_document(
    doc: &Doc,
    buffers: &mut Buffers,
    choice: SceneChoice,
    mut warnings: Vec<String>,
) -> Result<GltfModel, String> {
    let (roots, scene_name) = roots(doc, choice, &mut warnings)?;
    let mut seen_things = Seen::default();
    let mut instances: Vec<Instance> = Vec::new();
    let mut meshes: HashMap<usize, Vec<PrimitiveDef>> = HashMap::new();
    let mut light = None;
    // Depth-first over the node forest, without recursion; each node at most once.
    let mut seen = vec![false; doc.len("nodes")];
    let mut stack: Vec<(usize, Mat4, usize, String)> = roots
        .iter()
        .enumerate()
        .rev()
        .map(|(k, &n)| (n, Mat4::IDENTITY, 0, format!("{scene_name}, node {k}")))
        .collect();
    while let Some((i, parent, depth, from)) = stack.pop() {
        let node = doc.element("nodes", i, &from)?;
        if seen.get(i).copied().unwrap_or(true) {
            return Err(format!(
                "node {i} is reached twice from {scene_name}: the node hierarchy must be a tree"
            ));
        }
        seen[i] = true;
        if depth > MAX_DEPTH {
            return Err(format!(
                "the node hierarchy is deeper than {MAX_DEPTH} levels (at node {i})"
            ));
        }
        let world = parent * local_transform(&node)?;
        if !world.is_finite() {
            return Err(format!(
                "node {i}: its transform has a number that is not finite"
            ));
        }
        if let Some(m) = node.opt_index("mesh")? {
            if let Entry::Vacant(e) = meshes.entry(m) {
                e.insert(parse_mesh(doc, m, &node.at("mesh"), &mut seen_things)?);
            }
            let skin = node.opt_index("skin").ok().flatten();
            instances.push(Instance {
                mesh: m,
                world,
                skin: skin.map(|s| (s, i)),
            });
            if skin.is_some() {
                seen_things.skinned.push(i);
            }
            if node.has_extension("EXT_mesh_gpu_instancing") {
                seen_things.instanced += 1;
            }
        }
        if let Some(ext) = node.extension("KHR_lights_punctual") {
            if let Some(l) = ext.opt_index("light")? {
                let position = world.transform_point3(Vec3::ZERO);
                match light_kind(doc, l) {
                    Some(kind @ ("spot" | "point")) if light.is_none() => {
                        let spot = kind == "spot";
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
                                "light {l} on node {i}: its transform collapses it; ignored"
                            )),
                        }
                    }
                    Some("directional") => warnings.push(format!(
                        "light {l} on node {i} is directional (no position): ignored; a disk \
                         light needs a spot or point light"
                    )),
                    Some("spot" | "point") => warnings.push(format!(
                        "light {l} on node {i}: only the first spot or point light is used"
                    )),
                    _ => warnings.push(format!(
                        "light {l} on node {i}: not a spot, point or directional light of \
                         KHR_lights_punctual; ignored"
                    )),
                }
            }
        }
        let children = node.opt_indices("children")?.unwrap_or_default();
        for (k, child) in children.into_iter().enumerate().rev() {
            stack.push((child, world, depth + 1, format!("nodes[{i}].children[{k}]")));
        }
    }

    // Nothing to draw in the scene (no nodes, or none with a triangle mesh), but the file has
    // meshes: each drawn once, where its own coordinates put it, as viewers list a file's
    // meshes.
    let draws = |instances: &[Instance], meshes: &HashMap<usize, Vec<PrimitiveDef>>| {
        instances.iter().any(|i| {
            meshes
                .get(&i.mesh)
                .is_some_and(|p| p.iter().any(|p| has_triangles(p.mode)))
        })
    };
    let all = doc.len("meshes");
    if !draws(&instances, &meshes) && all > 0 {
        instances.clear();
        for m in 0..all {
            if let Entry::Vacant(e) = meshes.entry(m) {
                e.insert(parse_mesh(doc, m, "meshes", &mut seen_things)?);
            }
            instances.push(Instance {
                mesh: m,
                world: Mat4::IDENTITY,
                skin: None,
            });
        }
        if draws(&instances, &meshes) {
            warnings.push(format!(
                "{scene_name}: no triangle mesh placed; drawn from the file's {all} mesh{} \
                 instead, each once, untransformed",
                if all == 1 { "" } else { "es" }
            ));
        }
    }

    check_instances_budget(doc, &instances, &meshes)?;

    let mut positions: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    // Each primitive's positions and triangles, read once however many nodes use it.
    let mut read: HashMap<(usize, usize), Primitive> = HashMap::new();
    let mut primitives = 0usize;
    let mut worlds = Worlds::new(doc);
    let mut skins: HashMap<usize, Result<Vec<Mat4>, String>> = HashMap::new();
    let mut influences_read: HashMap<(usize, usize), Result<Influences, String>> = HashMap::new();
    let mut unskinned: Vec<String> = Vec::new();
    let mut no_position = 0usize;
    for inst in &instances {
        let Some(prims) = meshes.get(&inst.mesh) else {
            continue;
        };
        for prim in prims {
            if !has_triangles(prim.mode) {
                continue;
            }
            let what = format!("mesh {}, primitive {}", inst.mesh, prim.index);
            if prim.position.is_none() {
                // glTF lets an extension supply positions; without them nothing is drawn of
                // this primitive.
                no_position += 1;
                continue;
            }
            primitives += 1;
            let (local, tris) = match read.entry((inst.mesh, prim.index)) {
                Entry::Occupied(e) => &*e.into_mut(),
                Entry::Vacant(e) => {
                    let position = prim
                        .position
                        .as_ref()
                        .ok_or_else(|| format!("{what} has no POSITION attribute"))?;
                    if position.all_zeros() {
                        // Every corner at the origin: nothing to draw, whatever the count says
                        // (16M zeros would be 320 MB to weld back into one point).
                        &*e.insert((vec![Vec3::ZERO], Vec::new()))
                    } else {
                        let local =
                            read_positions(position, &format!("POSITION of {what}"), buffers)?;
                        let corners = match &prim.indices {
                            Some(acc) => read_indices(
                                acc,
                                &format!("indices of {what}"),
                                buffers,
                                local.len(),
                            )?,
                            None => (0..local.len() as u32).collect(),
                        };
                        let tris = assemble(prim.mode, &corners);
                        &*e.insert((local, tris))
                    }
                }
            };
            // A skinned instance: each vertex by its joints (rest pose); else by the node.
            let skinned = match (inst.skin, prim.skinning) {
                (Some((s, node)), Some((j, w))) if !tris.is_empty() => {
                    let matrices = match skins.entry(s) {
                        Entry::Occupied(e) => e.into_mut(),
                        Entry::Vacant(e) => e.insert(
                            joint_matrices(
                                doc,
                                s,
                                &format!("nodes[{node}].skin"),
                                &mut worlds,
                                buffers,
                            )
                            .map_err(|e| format!("skin {s}: {e}")),
                        ),
                    };
                    let infl = match influences_read.entry((inst.mesh, prim.index)) {
                        Entry::Occupied(e) => e.into_mut(),
                        Entry::Vacant(e) => {
                            e.insert(influences(doc, j, w, &what, local.len(), buffers))
                        }
                    };
                    match (&*matrices, &*infl) {
                        (Ok(m), Ok((joints, weights))) => Some((m, joints, weights)),
                        (Err(e), _) | (_, Err(e)) => {
                            if unskinned.len() < 3 {
                                unskinned.push(e.clone());
                            }
                            None
                        }
                    }
                }
                _ => None,
            };
            let flip = Mat4::determinant(&inst.world) < 0.0;
            let mut flips: Vec<bool> = Vec::new();
            let mut remap = Vec::with_capacity(local.len());
            for (k, p) in local.iter().enumerate() {
                let p = match skinned {
                    Some((matrices, joints, weights)) => {
                        match blended(k, joints, weights, matrices) {
                            Some(m) => {
                                flips.push(m.determinant() < 0.0);
                                place(&m, *p)
                            }
                            None => {
                                flips.push(flip);
                                inst.world.transform_point3(*p)
                            }
                        }
                    }
                    None => inst.world.transform_point3(*p),
                };
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
                let flip = flips.get(a as usize).copied().unwrap_or(flip);
                let (a, b, c) = (remap[a as usize], remap[b as usize], remap[c as usize]);
                if a != b && b != c && a != c {
                    triangles.push(if flip { [a, c, b] } else { [a, b, c] });
                }
            }
        }
    }
    let s = |n: usize| if n == 1 { "" } else { "s" };
    let skipped = seen_things.lines;
    if skipped > 0 {
        warnings.push(format!(
            "{skipped} point or line primitive{} skipped: only triangles cast shadows",
            s(skipped)
        ));
    }
    if let Some(&first) = seen_things.skinned.first() {
        let n = seen_things.skinned.len();
        warnings.push(format!(
            "{n} skinned mesh{} (node {first}{}) drawn in {} rest pose (the joints as the file \
             places them): animations are not played",
            if n == 1 { "" } else { "es" },
            if n > 1 { " and others" } else { "" },
            if n == 1 { "its" } else { "their" }
        ));
    }
    if no_position > 0 {
        warnings.push(format!(
            "{no_position} triangle primitive{} without POSITION skipped: nothing to place",
            s(no_position)
        ));
    }
    for e in unskinned {
        warnings.push(format!(
            "a skin cannot be applied, its mesh is drawn by its node instead: {e}"
        ));
    }
    if seen_things.morphed > 0 {
        warnings.push(format!(
            "{} primitive{} with morph targets drawn without them",
            seen_things.morphed,
            s(seen_things.morphed)
        ));
    }
    if seen_things.instanced > 0 {
        warnings.push(format!(
            "{} node{} with EXT_mesh_gpu_instancing: each mesh drawn once, at its node, not at \
             its instances",
            seen_things.instanced,
            s(seen_things.instanced)
        ));
    }
    warnings.append(&mut buffers.notes);
    if triangles.is_empty() && primitives > 0 {
        // A triangle mesh whose every triangle has coinciding corners (zeros where the file has
        // no data): it loads, with nothing to draw, and says so.
        warnings.push(format!(
            "{scene_name}: its {primitives} triangle primitive{} have no triangle with three \
             distinct corners (positions without data are zeros): nothing to draw",
            s(primitives)
        ));
    }
    if triangles.is_empty() && primitives == 0 {
        return Err(format!(
            "contains no triangles: no triangle primitive with positions in {scene_name}{}",
            if no_position > 0 {
                format!(", {no_position} without POSITION")
            } else if skipped > 0 {
                format!(", only {skipped} point or line primitive{}", s(skipped))
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

/// The triangles and positions the scene's instances would place, from the accessors' counts,
/// before a byte of a buffer is read: a small file can place one big primitive many times
/// (2 KB of nodes over a 60 KB strip is 18M triangles), so the budget is checked here, not
/// once they are made.
fn check_instances_budget(
    doc: &Doc,
    instances: &[Instance],
    meshes: &HashMap<usize, Vec<PrimitiveDef>>,
) -> Result<(), String> {
    let (mut assembled, mut placed) = (0u64, 0u64);
    for inst in instances {
        for prim in meshes.get(&inst.mesh).into_iter().flatten() {
            if !has_triangles(prim.mode) {
                continue;
            }
            let vertices = prim.position.as_ref().map_or(0, |a| a.readable_count(doc));
            let corners = prim
                .indices
                .as_ref()
                .map_or(vertices, |a| a.readable_count(doc));
            assembled = assembled.saturating_add(triangles_of(prim.mode, corners));
            placed = placed.saturating_add(vertices);
        }
        if assembled > MAX_TRIANGLES as u64 || placed > MAX_PLACED_VERTICES as u64 {
            return Err(format!(
                "its scene places at least {assembled} triangles and {placed} vertices over its \
                 node instances (counted from the accessors, before reading them): the budget \
                 is {MAX_TRIANGLES} triangles per scene (MAX_SCENE_TRIANGLES) and \
                 {MAX_PLACED_VERTICES} placed vertices, three per triangle"
            ));
        }
    }
    Ok(())
}

/// Triangles (as indices into the primitive's vertices) from a triangle list, strip or fan.
fn assemble(mode: u64, corners: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        TRIANGLE_STRIP => corners
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
        TRIANGLE_FAN => match corners.split_first() {
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
        assert_eq!(
            assemble(TRIANGLE_STRIP, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [2, 1, 3]]
        );
        assert_eq!(
            assemble(TRIANGLE_FAN, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(assemble(TRIANGLES, &[0, 1, 2, 3]), vec![[0, 1, 2]]);
    }
}
