//! Objects in the scene description: meshes (and where their triangles
//! come from), spheres, planes, ellipsoids, instances.

use crate::error::Loc;
use luster_core::math::{Quat, Transform, Vec2, Vec3};
use luster_shading::shader::ParamValue;
use std::path::PathBuf;
use std::sync::Arc;

/// Where a mesh's triangles come from.
#[derive(Clone, Debug)]
pub enum MeshSource {
    /// Triangles given inline, as 0-based indices into [`Description::vertices`](super::Description::vertices).
    Inline {
        /// The triangles.
        triangles: Vec<[u32; 3]>,
        /// Added to a vertex index to get the index of its texture coordinate
        /// in [`Description::tex_coords`](super::Description::tex_coords) (the `Faces` element's
        /// `textureOffset - vertexOffset`; 0 when they are numbered alike).
        tex_shift: i64,
    },
    /// A PLY file with its own vertices.
    Ply(PathBuf),
    /// Vertex arrays read when the scene loaded (an OBJ model's part).
    Arrays(Arc<MeshArrays>),
}

/// A mesh's own vertex arrays, 0-based: what an OBJ file gives.
#[derive(Clone, Debug, Default)]
pub struct MeshArrays {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, when the file has them for every vertex.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, when the file has them for every vertex.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles, as indices into the arrays.
    pub triangles: Vec<[u32; 3]>,
}

/// The shape of an object.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A sphere, before its transform.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
    /// An ellipsoid (luster's `<Ellipsoid>` extension), before its transform:
    /// the unit sphere scaled by `radii`, turned by `rotation`, moved to `center`.
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Radii along the ellipsoid's own axes, all positive.
        radii: Vec3,
        /// Its own axes to object space (the identity when not given).
        rotation: Quat,
    },
    /// A single triangle.
    Triangle {
        /// Its corners.
        vertices: [Vec3; 3],
        /// Texture coordinates of the corners, when `TexCoordData` has them.
        uvs: Option<[Vec2; 3]>,
    },
    /// An infinite plane through `point` with `normal`.
    Plane {
        /// A point on the plane.
        point: Vec3,
        /// Its normal.
        normal: Vec3,
    },
    /// A triangle mesh.
    Mesh {
        /// Its triangles.
        source: MeshSource,
        /// Interpolate vertex normals (`shadingMode="smooth"`): the file's own
        /// normals where [`MeshSource::Arrays`] has them, else area-weighted ones.
        smooth: bool,
    },
    /// A `MeshInstance`: the geometry of another mesh (resolved through any chain
    /// of instances), with this object's own material and full transform.
    Instance {
        /// Index into [`Description::objects`](super::Description::objects) of the mesh whose triangles are used.
        mesh: usize,
    },
}

/// An object of the scene.
#[derive(Clone, Debug)]
pub struct ObjectDesc {
    /// The object's id (meshes and instances share one namespace).
    pub id: String,
    /// Its shape.
    pub shape: Shape,
    /// Index into [`Description::materials`](super::Description::materials).
    pub material: usize,
    /// Object to world, composed in the listed order (and, for instances, on
    /// top of the base's transform unless `resetTransform` is true).
    pub transform: Transform,
    /// Translation over the shutter interval (`MotionBlur`): at time `τ` the
    /// object is moved by `τ · motion` after its transform.
    pub motion: Vec3,
    /// Indices into [`Description::texture_maps`](super::Description::texture_maps), in the order listed.
    pub textures: Vec<usize>,
    /// Where.
    pub loc: Loc,
    /// The object's own attributes (an instance's, a glTF node's), which
    /// shaders read with `getattribute` before [`ObjectDesc::geometry_attributes`].
    pub attributes: AttributeList,
    /// The attributes of the geometry, which every object drawing it shares
    /// (a CENG795 `Mesh`'s or `Sphere`'s, a glTF mesh's); read when the
    /// object's own have no such name. Only geometry objects (not
    /// [`Shape::Instance`]) have them.
    pub geometry_attributes: AttributeList,
}

/// User data for shaders (`<Attribute>`, glTF `extras`): names and values,
/// each name once, in the order given.
pub type AttributeList = Vec<(String, ParamValue)>;
