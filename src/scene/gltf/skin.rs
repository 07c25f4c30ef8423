//! Skinned meshes in their rest pose: each vertex placed by its joints' world transforms (the
//! node hierarchy as the file holds it, no animation) times their inverse bind matrices,
//! blended by its weights, as glTF skinning says. The skinned mesh's own node transform is
//! ignored, as the spec says; tools rely on that (`gltf-transform quantize` folds a skinned
//! mesh's dequantization into its inverse bind matrices, not into a node).
//!
//! A skin is something dbuffer may do without: when its data cannot be used (an accessor of
//! the wrong type, counts that disagree), the caller draws the mesh by its node transform with
//! a warning instead of refusing the model.

use std::collections::HashMap;

use glam::{Mat4, Vec3};

use super::accessors::{parse_accessor, read_numbers, Component};
use super::buffers::Buffers;
use super::json::Doc;
use super::MAX_DEPTH;

/// Most joints one skin may have (JOINTS_0 is at most unsigned short).
const MAX_JOINTS: usize = 1 << 16;

/// Most vertices of one primitive placed by a skin: its joints and weights take 32 bytes a
/// vertex (128 MiB here); a larger skinned primitive is drawn by its node, with a warning.
const MAX_SKINNED_VERTICES: usize = 1 << 22;

/// World transforms of any node, from the parent links of every node's `children` (a joint
/// need not be under the scene's roots).
pub(super) struct Worlds {
    parent: Vec<Option<usize>>,
    cache: HashMap<usize, Mat4>,
}

impl Worlds {
    pub(super) fn new(doc: &Doc) -> Worlds {
        let n = doc.len("nodes");
        let mut parent = vec![None; n];
        for i in 0..n {
            let children = doc
                .element("nodes", i, "nodes")
                .ok()
                .and_then(|node| node.opt_indices("children").ok().flatten())
                .unwrap_or_default();
            for c in children {
                if let Some(p) = parent.get_mut(c) {
                    *p = Some(i);
                }
            }
        }
        Worlds {
            parent,
            cache: HashMap::new(),
        }
    }

    /// Node `i`'s world transform.
    pub(super) fn world(&mut self, doc: &Doc, i: usize) -> Result<Mat4, String> {
        let mut chain = vec![i];
        let mut at = i;
        while let Some(p) = self.parent.get(at).copied().flatten() {
            if self.cache.contains_key(&at) {
                break;
            }
            if chain.len() > MAX_DEPTH {
                return Err(format!(
                    "node {i}'s ancestors are more than {MAX_DEPTH} deep (or a cycle)"
                ));
            }
            chain.push(p);
            at = p;
        }
        let mut world = Mat4::IDENTITY;
        for &n in chain.iter().rev() {
            world = match self.cache.get(&n) {
                Some(&w) => w,
                None => {
                    let node = doc.element("nodes", n, "skins[].joints")?;
                    let w = world * super::document::local_transform(&node)?;
                    self.cache.insert(n, w);
                    w
                }
            };
        }
        Ok(world)
    }
}

/// Skin `s`: for each joint, its world transform times its inverse bind matrix.
pub(super) fn joint_matrices(
    doc: &Doc,
    s: usize,
    from: &str,
    worlds: &mut Worlds,
    buffers: &mut Buffers,
) -> Result<Vec<Mat4>, String> {
    let skin = doc.element("skins", s, from)?;
    let joints = skin.opt_indices("joints")?.unwrap_or_default();
    if joints.is_empty() || joints.len() > MAX_JOINTS {
        return Err(format!(
            "{} has {} joints: expected 1 to {MAX_JOINTS}",
            skin.at("joints"),
            joints.len()
        ));
    }
    let inverse = match skin.opt_index("inverseBindMatrices")? {
        Some(a) => {
            let acc = parse_accessor(doc, a, &skin.at("inverseBindMatrices"))?;
            if acc.count < joints.len() as u64 {
                return Err(format!(
                    "accessor {a} (inverse bind matrices of skin {s}) has {} matrices for {} \
                     joints",
                    acc.count,
                    joints.len()
                ));
            }
            let m = read_numbers(
                &acc,
                &format!("inverse bind matrices of skin {s}"),
                buffers,
                16,
                &[Component::F32],
                joints.len() as u64,
            )?;
            m.chunks_exact(16)
                .map(|c| {
                    let mut a = [0f32; 16];
                    a.copy_from_slice(c);
                    Mat4::from_cols_array(&a)
                })
                .collect()
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    joints
        .iter()
        .zip(inverse)
        .map(|(&j, ibm)| Ok(worlds.world(doc, j)? * ibm))
        .collect()
}

/// The joints and weights of a primitive's vertices (JOINTS_0 and WEIGHTS_0), `vertices` of
/// them, four each.
pub(super) fn influences(
    doc: &Doc,
    joints: usize,
    weights: usize,
    what: &str,
    vertices: usize,
    buffers: &mut Buffers,
) -> Result<(Vec<f32>, Vec<f32>), String> {
    if vertices > MAX_SKINNED_VERTICES {
        return Err(format!(
            "{what} has {vertices} vertices, more than the {MAX_SKINNED_VERTICES} dbuffer skins"
        ));
    }
    let read = |i: usize, name: &str, allowed: &[Component], buffers: &mut Buffers| {
        let acc = parse_accessor(doc, i, &format!("{name} of {what}"))?;
        if acc.count != vertices as u64 {
            return Err(format!(
                "accessor {i} ({name} of {what}) has {} elements for {vertices} positions",
                acc.count
            ));
        }
        read_numbers(
            &acc,
            &format!("{name} of {what}"),
            buffers,
            4,
            allowed,
            vertices as u64,
        )
    };
    let j = read(
        joints,
        "JOINTS_0",
        &[Component::U8, Component::U16],
        buffers,
    )?;
    let w = read(
        weights,
        "WEIGHTS_0",
        &[Component::F32, Component::U8, Component::U16],
        buffers,
    )?;
    Ok((j, w))
}

/// The blended joint matrix of vertex `k`, or `None` if its weights are all zero (or not
/// numbers) or a joint index is past the skin's joints.
pub(super) fn blended(
    k: usize,
    joints: &[f32],
    weights: &[f32],
    matrices: &[Mat4],
) -> Option<Mat4> {
    let w = &weights[4 * k..4 * k + 4];
    let sum: f32 = w.iter().sum();
    if !(sum.is_finite() && sum > 0.0) {
        return None;
    }
    let mut m = Mat4::ZERO;
    for c in 0..4 {
        if w[c] != 0.0 {
            let j = matrices.get(joints[4 * k + c] as usize)?;
            m += *j * (w[c] / sum);
        }
    }
    Some(m)
}

/// `p` placed by the blended matrix.
pub(super) fn place(m: &Mat4, p: Vec3) -> Vec3 {
    m.transform_point3(p)
}
