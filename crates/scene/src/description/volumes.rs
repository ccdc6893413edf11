//! Volumes in the scene description: their bounds, density scripts or VDB
//! files, and media.

use crate::error::Loc;
use luster_core::math::{Quat, Transform, Vec3};
use luster_shading::shader::ParamValue;
use std::path::PathBuf;

/// The region a volume fills, in its own space (before its transform).
#[derive(Clone, Debug, PartialEq)]
pub enum BoundDesc {
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Smallest corner.
        min: Vec3,
        /// Largest corner.
        max: Vec3,
    },
    /// An ellipsoid: the unit ball scaled by `radii`, rotated, then moved to `center`.
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axes along the rotated x, y, z.
        radii: Vec3,
        /// Rotation (identity when none is given).
        rotation: Quat,
    },
}

/// A Lua script with its parameters, as a scene names it.
#[derive(Clone, Debug)]
pub struct ScriptDesc {
    /// The script's path (relative ones resolved against the scene's folder).
    pub path: PathBuf,
    /// The script's text, read when the scene loads.
    pub code: String,
    /// `Parameter` elements, in order: what the script reads as `param.NAME`.
    pub params: Vec<(String, ParamValue)>,
}

/// An OpenVDB file as a medium's density (and emission) source, as a scene
/// names it; the file is read when the scene is built for rendering.
#[derive(Clone, Debug, PartialEq)]
pub struct VdbDesc {
    /// The file's path (relative ones resolved against the scene's folder).
    pub path: PathBuf,
    /// The float grid read as the density (`DensityGrid`, default `density`).
    pub density_grid: String,
    /// The float grid that, times `Emission`, is the emitted radiance per
    /// unit length (`EmissionGrid`); `None`: `Emission` times the density.
    pub emission_grid: Option<String>,
    /// Where the `VdbFile` element is.
    pub loc: Loc,
}

/// What a volume does with light.
#[derive(Clone, Debug)]
pub enum VolumeKind {
    /// A participating medium: absorbs, scatters and emits along rays.
    Medium {
        /// Absorption coefficient per unit length at density 1 (σa).
        absorption: Vec3,
        /// Scattering coefficient per unit length at density 1 (σs).
        scattering: Vec3,
        /// Emitted radiance per unit length at density 1 (when the script has no `emission`).
        emission: Vec3,
        /// Henyey–Greenstein asymmetry, −1 (back) to 1 (forward); 0 is isotropic.
        anisotropy: f32,
        /// Orders of the multiple-scattering approximation (1: single scattering only).
        octaves: u32,
    },
    /// A hypertexture: the surface where the density crosses `threshold`,
    /// shaded with a material like any surface.
    Surface {
        /// Index into [`Description::materials`](super::Description::materials).
        material: usize,
        /// The density of the surface.
        threshold: f32,
        /// Indices into [`Description::texture_maps`](super::Description::texture_maps).
        textures: Vec<usize>,
    },
}

/// A volume: a bounded region whose density is a constant or a script's.
#[derive(Clone, Debug)]
pub struct VolumeDesc {
    /// The volume's id.
    pub id: String,
    /// The region it fills; `None` only with a [`VdbDesc`], whose grids'
    /// active box is then the bound.
    pub bound: Option<BoundDesc>,
    /// Bound to world.
    pub transform: Transform,
    /// Density multiplier (the constant density when there is no script).
    pub density: f32,
    /// The script with `density(s)` (and, for media, optionally `emission(s)`).
    pub script: Option<ScriptDesc>,
    /// A medium's VDB file (never together with a script).
    pub vdb: Option<VdbDesc>,
    /// Ray-marching step in world units; `None`: chosen from the bound's size.
    pub step: Option<f32>,
    /// Precompute the script's density on a grid of this many cells per edge.
    pub grid: Option<u32>,
    /// Medium or surface.
    pub kind: VolumeKind,
    /// Where.
    pub loc: Loc,
    /// What its scripts read with `getattribute` (`<Attribute>`).
    pub attributes: super::AttributeList,
}
