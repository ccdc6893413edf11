//! glTF 2.0 scenes (`.gltf` with its buffers, or `.glb`), read with the
//! `gltf` crate into a plain [`Description`](crate::Description).
//!
//! Two ways in: `luster render scene.gltf` ([`scene::scene`]: the file's
//! cameras and lights, or a studio around it), and a CENG795 scene's
//! `<Mesh><Faces gltfFile="model.glb"/></Mesh>` (`scene::ceng795::gltf_file`).
//! Both read the file with [`read`]: the document and buffers
//! ([`document`]), the drawn nodes ([`nodes`]) and their meshes ([`mesh`],
//! through [`accessor`]); [`Model::objects`] makes the description's objects, one
//! per primitive of each drawn node, a mesh drawn by several nodes being
//! one geometry and instances of it. Materials are [`material`]'s; nodes'
//! and meshes' `extras` are the objects' attributes ([`extras`]).
//!
//! The file is read whole when the scene loads; every fault is one error
//! naming the file and the JSON path (`accessors[3]`, `nodes[2].matrix`).
//! Animations, skins and extensions luster does not use are warned about,
//! once each.

pub mod accessor;
pub mod camera;
pub mod document;
pub mod extras;
pub mod lights;
pub mod material;
pub mod mesh;
pub mod nodes;
pub mod scene;

pub use document::GltfFile;
pub use scene::scene;

use crate::description::{AttributeList, MeshSource, ObjectDesc, Shape};
use crate::error::{Loc, SceneError, Warning};
use luster_core::math::{Transform, Vec3};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// Whether a path names a glTF file (`.gltf` or `.glb`, in any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Extensions read here or by [`material`]; others get a warning.
const KNOWN_EXTENSIONS: [&str; 2] = ["KHR_lights_punctual", "KHR_mesh_quantization"];

/// The warnings of one file, each at a JSON path; some given once per file.
#[derive(Debug, Default)]
pub struct Notes {
    /// The warnings, in order.
    pub warnings: Vec<Warning>,
    seen: HashSet<String>,
}

impl Notes {
    /// A warning at `path`.
    pub fn warn(&mut self, path: &str, message: impl Into<String>) {
        self.warnings
            .push(Warning { loc: Loc { line: None, path: path.to_string() }, message: message.into() });
    }

    /// A warning given at the first `path` it applies to, once per file.
    pub fn once(&mut self, path: &str, message: &str) {
        if self.seen.insert(message.to_string()) {
            self.warn(path, format!("{message} (said once per file)"));
        }
    }
}

/// A glTF file read: its document and buffers, the drawn nodes, and the
/// primitives of the meshes they draw.
pub struct Model {
    /// The document and buffers.
    pub file: GltfFile,
    /// The drawn nodes, depth first, with their world transforms.
    pub placed: Vec<nodes::Placed>,
    /// By mesh index: the mesh's triangle primitives, for meshes drawn.
    pub meshes: Vec<Option<Vec<mesh::Primitive>>>,
    /// By node index: the attributes of the drawn nodes' `extras` ([`extras`]).
    pub node_attributes: Vec<AttributeList>,
    /// By mesh index: the attributes of the drawn meshes' `extras`.
    pub mesh_attributes: Vec<AttributeList>,
    /// What was accepted but not used.
    pub notes: Notes,
}

/// Reads a glTF file: the document, its buffers, the scene's node graph
/// and every mesh a drawn node uses.
pub fn read(path: &Path) -> Result<Model, SceneError> {
    let file = document::open(path)?;
    let doc = &file.doc;
    let mut notes = Notes::default();
    for ext in doc.extensions_used() {
        let theirs = ext.starts_with("KHR_materials_") || ext.starts_with("KHR_texture_");
        if !theirs && !KNOWN_EXTENSIONS.contains(&ext) {
            notes.warn("extensionsUsed", format!("extension {} is not supported; ignored", identifier(ext)));
        }
    }
    if doc.animations().len() > 0 {
        notes.warn("animations", "animations are not played; the scene is drawn as its nodes stand");
    }
    if doc.skins().len() > 0 {
        notes.warn("skins", "skins are not applied; skinned meshes are drawn in their bind pose");
    }
    for image in doc.images() {
        if let gltf::image::Source::Uri { uri, .. } = image.source() {
            document::check_uri(path, &file.base_dir, uri, &format!("images[{}].uri", image.index()))?;
        }
    }
    let placed = nodes::placed(path, doc, &mut notes)?;
    let accessors = accessor::Accessors::new(path, &file.buffers);
    let mut meshes: Vec<Option<Vec<mesh::Primitive>>> = vec![None; doc.meshes().len()];
    let all: Vec<gltf::Mesh> = doc.meshes().collect();
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut node_attributes = vec![AttributeList::new(); nodes.len()];
    let mut mesh_attributes = vec![AttributeList::new(); all.len()];
    for p in &placed {
        if let Some(m) = nodes[p.node].mesh() {
            if meshes[m.index()].is_none() {
                meshes[m.index()] = Some(mesh::read(&accessors, &all[m.index()], &mut notes)?);
                let at = format!("meshes[{}]", m.index());
                mesh_attributes[m.index()] = extras::attributes(m.extras(), &at, &mut notes);
            }
            let at = format!("nodes[{}]", p.node);
            node_attributes[p.node] = extras::attributes(nodes[p.node].extras(), &at, &mut notes);
        }
    }
    Ok(Model { file, placed, meshes, node_attributes, mesh_attributes, notes })
}

/// A name from the file for a message: shown when it is a short
/// identifier, else only its length.
fn identifier(s: &str) -> String {
    if !s.is_empty() && s.len() <= 64 && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        s.to_string()
    } else {
        format!("(a name of {} characters)", s.chars().count())
    }
}

impl Model {
    /// The description's objects for the drawn nodes: one per primitive of
    /// each node's mesh, its transform the node's world transform followed
    /// by `after`. The first node to draw a primitive makes its mesh; the
    /// others are instances of it (`first` is the index the first object
    /// will have in the description). `material` gives the description's
    /// material and texture maps for a document material (`None`: the
    /// default one).
    pub fn objects(
        &self,
        first: usize,
        after: &Transform,
        mut material: impl FnMut(Option<usize>) -> Result<(usize, Vec<usize>), SceneError>,
    ) -> Result<Vec<ObjectDesc>, SceneError> {
        let nodes: Vec<gltf::Node> = self.file.doc.nodes().collect();
        let mut out = Vec::new();
        let mut made: HashMap<(usize, usize), usize> = HashMap::new();
        for p in &self.placed {
            let node = &nodes[p.node];
            let Some(m) = node.mesh() else { continue };
            let Some(prims) = self.meshes.get(m.index()).and_then(Option::as_ref) else { continue };
            let id = node.name().map_or_else(|| format!("nodes[{}]", p.node), identifier);
            for (k, prim) in prims.iter().enumerate() {
                let (shape, geometry_attributes) = match made.get(&(m.index(), k)) {
                    Some(&base) => (Shape::Instance { mesh: base }, Vec::new()),
                    None => {
                        made.insert((m.index(), k), first + out.len());
                        let smooth = prim.arrays.normals.is_some();
                        let shape = Shape::Mesh { source: MeshSource::Arrays(prim.arrays.clone()), smooth };
                        (shape, self.mesh_attributes.get(m.index()).cloned().unwrap_or_default())
                    }
                };
                let (mat, textures) = material(prim.material)?;
                out.push(ObjectDesc {
                    id: id.clone(),
                    shape,
                    material: mat,
                    transform: p.world.then(after),
                    motion: Vec3::ZERO,
                    textures,
                    loc: Loc { line: None, path: format!("nodes[{}] ({})", p.node, prim.path) },
                    attributes: self.node_attributes.get(p.node).cloned().unwrap_or_default(),
                    geometry_attributes,
                });
            }
        }
        Ok(out)
    }
}
