//! Materials and BRDFs in the scene description (`<Material>`, `<BRDFs>`).

use crate::error::Loc;
use luster_core::math::Vec3;

/// What kind of surface a material is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    /// Blinn-Phong only.
    Plain,
    /// Blinn-Phong plus perfect reflection weighted by `MirrorReflectance`.
    Mirror,
    /// Glass-like: Fresnel reflection and refraction, Beer absorption inside.
    Dielectric,
    /// Metal: reflection weighted by the conductor Fresnel term.
    Conductor,
}

/// A material.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    /// The material's id.
    pub id: String,
    /// Its kind.
    pub kind: MaterialKind,
    /// Ambient reflectance.
    pub ambient: Vec3,
    /// Diffuse reflectance.
    pub diffuse: Vec3,
    /// Specular reflectance.
    pub specular: Vec3,
    /// Mirror reflectance (mirror and conductor).
    pub mirror: Vec3,
    /// Blinn-Phong exponent.
    pub phong_exponent: f32,
    /// Index of refraction (dielectric; real part for conductors).
    pub refraction_index: f32,
    /// Beer's-law absorption coefficient per unit distance (dielectric).
    pub absorption_coefficient: Vec3,
    /// Imaginary part of the index of refraction (conductor).
    pub absorption_index: f32,
    /// Glossiness of mirrors and conductors: how far reflected rays stray (0: perfect).
    pub roughness: f32,
    /// The reflection model named by `BRDF="id"`; the course's Blinn-Phong when absent.
    pub brdf: Option<BrdfDesc>,
    /// Where.
    pub loc: Loc,
}

/// Which reflection model a `<BRDFs>` entry is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrdfKind {
    /// `OriginalPhong`.
    OriginalPhong,
    /// `ModifiedPhong`.
    ModifiedPhong,
    /// `OriginalBlinnPhong`.
    OriginalBlinnPhong,
    /// `ModifiedBlinnPhong`.
    ModifiedBlinnPhong,
    /// `TorranceSparrow`.
    TorranceSparrow,
}

/// A `<BRDFs>` entry.
#[derive(Clone, Debug)]
pub struct BrdfDesc {
    /// Its id.
    pub id: String,
    /// The model.
    pub kind: BrdfKind,
    /// `<Exponent>`; the material's `PhongExponent` when absent.
    pub exponent: Option<f32>,
    /// `normalized="true"` (modified Phong and Blinn-Phong).
    pub normalized: bool,
    /// `kdfresnel="true"` (Torrance-Sparrow): the diffuse term is weighted by `1 - F`.
    pub kd_fresnel: bool,
    /// Where.
    pub loc: Loc,
}
