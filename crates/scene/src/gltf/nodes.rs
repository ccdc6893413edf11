//! The node graph of a glTF scene: which nodes are drawn and where.
//!
//! The scene drawn is the file's `scene`, else its first; a file with no
//! scenes draws every node that is no other's child. Each node's transform
//! (a `matrix`, or `translation`, `rotation` and `scale`) applies after
//! its children's, so a child's world transform is its parent's times its
//! own. The graph must be a forest: a node listed as a child twice, a child
//! of itself, or a cycle is an error naming the node, found without
//! recursion (an explicit stack), so no depth of nesting overflows a stack.
//! A node whose world transform is singular (a zero scale, which glTF
//! allows to hide a node) is not drawn, nor are its children.

use super::document::at;
use super::Notes;
use crate::error::SceneError;
use luster_core::math::{Mat4, Quat, Transform, Vec3};
use std::path::Path;

/// Deepest nesting of nodes accepted.
const MAX_DEPTH: usize = 4096;

/// A node of the drawn scene with its world transform.
#[derive(Clone, Debug)]
pub struct Placed {
    /// Index into the document's nodes.
    pub node: usize,
    /// Object to world.
    pub world: Transform,
}

/// Every node of the scene drawn, depth first in the order the scene and
/// the nodes list them, with its world transform.
pub fn placed(file: &Path, doc: &gltf::Document, notes: &mut Notes) -> Result<Vec<Placed>, SceneError> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            if c == node.index() {
                return Err(at(file, format!("nodes[{c}].children"), "the node is its own child"));
            }
            if let Some(p) = parent[c] {
                return Err(at(
                    file,
                    format!("nodes[{}].children", node.index()),
                    format!("nodes[{c}] is already a child of nodes[{p}] (a node may have one parent)"),
                ));
            }
            parent[c] = Some(node.index());
        }
    }
    // With one parent each, a cycle is a chain of parents that comes back.
    let mut state = vec![0u8; n]; // 0: not seen, 1: on the current chain, 2: done
    for start in 0..n {
        let mut chain = Vec::new();
        let mut cur = Some(start);
        while let Some(i) = cur {
            match state[i] {
                2 => break,
                1 => {
                    return Err(at(
                        file,
                        format!("nodes[{i}]"),
                        "the node is its own ancestor (a cycle of children)",
                    ))
                }
                _ => {}
            }
            state[i] = 1;
            chain.push(i);
            cur = parent[i];
        }
        for i in chain {
            state[i] = 2;
        }
    }
    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            let roots: Vec<usize> = scene.nodes().map(|s| s.index()).collect();
            if let Some((&r, p)) = roots.iter().find_map(|r| parent[*r].map(|p| (r, p))) {
                return Err(at(
                    file,
                    format!("scenes[{}].nodes", scene.index()),
                    format!("nodes[{r}] is a child of nodes[{p}], so it cannot be a root of the scene"),
                ));
            }
            roots
        }
        None => (0..n).filter(|&i| parent[i].is_none()).collect(),
    };
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut out = Vec::new();
    let mut stack: Vec<(usize, Transform, usize)> =
        roots.iter().rev().map(|&r| (r, Transform::IDENTITY, 1)).collect();
    while let Some((i, parent_world, depth)) = stack.pop() {
        if depth > MAX_DEPTH {
            return Err(at(
                file,
                format!("nodes[{i}]"),
                format!("nodes are nested more than {MAX_DEPTH} deep"),
            ));
        }
        let node = &nodes[i];
        let local = local_matrix(file, node)?;
        let Some(world) =
            Transform::from_matrix(parent_world.matrix() * local).filter(|t| t.matrix().is_finite())
        else {
            notes.warn(
                &format!("nodes[{i}]"),
                "the node's transform is singular (a zero scale); it and its children are not drawn",
            );
            continue;
        };
        out.push(Placed { node: i, world });
        for c in node.children().collect::<Vec<_>>().iter().rev() {
            stack.push((c.index(), world, depth + 1));
        }
    }
    Ok(out)
}

/// A node's own matrix: its `matrix`, or `T · R · S`; every number finite,
/// the matrix affine and the rotation a (normalized) non-zero quaternion.
fn local_matrix(file: &Path, node: &gltf::Node) -> Result<Mat4, SceneError> {
    let name = format!("nodes[{}]", node.index());
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let m = Mat4::from_cols_array_2d(&matrix);
            if !m.is_finite() {
                return Err(at(file, format!("{name}.matrix"), "the matrix has a number that is not finite"));
            }
            let last = m.row(3);
            if (last - glam::Vec4::W).abs().max_element() > 1e-6 {
                return Err(at(
                    file,
                    format!("{name}.matrix"),
                    "the matrix is not affine (its last row is not 0 0 0 1)",
                ));
            }
            Ok(m)
        }
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let (t, r, s) = (Vec3::from(translation), Quat::from_array(rotation), Vec3::from(scale));
            for (what, ok) in
                [("translation", t.is_finite()), ("rotation", r.is_finite()), ("scale", s.is_finite())]
            {
                if !ok {
                    return Err(at(file, format!("{name}.{what}"), "a number is not finite"));
                }
            }
            let len = r.length();
            if len <= 1e-6 {
                return Err(at(file, format!("{name}.rotation"), "the rotation quaternion is zero"));
            }
            Ok(Mat4::from_scale_rotation_translation(s, r / len, t))
        }
    }
}
