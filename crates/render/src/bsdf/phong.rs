//! The Phong and Blinn-Phong families of the course (CENG795 hw6): a diffuse
//! term plus a specular lobe `cos^p α`, where `α` is the angle between the
//! outgoing direction and the mirrored incoming one (Phong, `α_r`) or between
//! the normal and the half vector (Blinn-Phong, `α_h`).
//!
//! | variant | `f(wi, wo)` |
//! |---|---|
//! | original | `kd + ks cos^p α / cos θi` |
//! | modified | `kd + ks cos^p α` |
//! | modified, normalized Phong | `kd/π + ks (p+2)/2π cos^p α_r` |
//! | modified, normalized Blinn-Phong | `kd/π + ks (p+8)/8π cos^p α_h` |
//!
//! The original Blinn-Phong is the course's default shading (hw1–hw5),
//! `kd cos θi + ks cos^p α_h` once multiplied by `cos θi`.

use super::sampling::{
    half_vector_pdf, power_cosine, power_cosine_about, power_cosine_pdf, reflect_about, reflect_z,
};
use luster_core::math::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// Which form of the lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Divides the specular term by `cos θi`: not reciprocal, not energy-conserving.
    Original,
    /// The specular term without the division.
    Modified,
    /// Modified, with the diffuse term over `π` and the lobe scaled to conserve energy.
    Normalized,
}

/// Where the lobe is centred.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobe {
    /// Around the mirror direction (`cos α_r = wo · reflect(wi)`).
    Phong,
    /// Around the normal, in half-vector space (`cos α_h = n · h`).
    BlinnPhong,
}

/// A Phong-family BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhongFamily {
    /// Phong or Blinn-Phong.
    pub lobe: Lobe,
    /// Original, modified or normalized.
    pub variant: Variant,
    /// The exponent `p`.
    pub exponent: f32,
}

impl PhongFamily {
    /// The cosine the lobe is raised to the exponent of, and the half vector
    /// when the lobe uses one.
    #[inline]
    fn cos_alpha(&self, wi: Vec3, wo: Vec3) -> f32 {
        match self.lobe {
            Lobe::Phong => reflect_z(wi).dot(wo).max(0.0),
            Lobe::BlinnPhong => (wi + wo).normalize_or_zero().z.max(0.0),
        }
    }

    /// `f(wi, wo)` in the local frame (normal `+z`); zero unless both
    /// directions are above the surface.
    #[inline]
    pub fn eval(&self, kd: Vec3, ks: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
        let cos_i = wi.z;
        if cos_i <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        // A material without a specular colour (the course's Cornell walls)
        // skips the `powf`: `ks * lobe` is zero either way.
        let lobe = if ks == Vec3::ZERO { 0.0 } else { self.cos_alpha(wi, wo).powf(self.exponent) };
        self.combine(kd, ks, lobe, cos_i)
    }

    /// [`eval`](Self::eval) for a material without specular colour, from the
    /// two directions' cosines alone (the lobe weighs nothing, so neither
    /// direction is needed whole): the same operations, so the same bits.
    #[inline(always)]
    pub fn eval_diffuse(&self, kd: Vec3, ks: Vec3, cos_i: f32, cos_o: f32) -> Vec3 {
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return Vec3::ZERO;
        }
        self.combine(kd, ks, 0.0, cos_i)
    }

    /// What [`eval_diffuse`](Self::eval_diffuse) gives for any `cos_i > 0`
    /// and `cos_o > 0`, the same bits: its lobe is zero, and so is `0 / cos_i`
    /// (the original variant's division) for every such `cos_i`. A material
    /// works it out once ([`crate::material::Traits`]).
    #[inline]
    pub fn diffuse_value(&self, kd: Vec3, ks: Vec3) -> Vec3 {
        self.combine(kd, ks, 0.0, 1.0)
    }

    /// The variant's sum of the diffuse term and the lobe's value `lobe`.
    #[inline(always)]
    fn combine(&self, kd: Vec3, ks: Vec3, lobe: f32, cos_i: f32) -> Vec3 {
        let p = self.exponent;
        match self.variant {
            Variant::Original => kd + ks * (lobe / cos_i),
            Variant::Modified => kd + ks * lobe,
            Variant::Normalized => {
                let scale = match self.lobe {
                    Lobe::Phong => (p + 2.0) / (2.0 * PI),
                    Lobe::BlinnPhong => (p + 8.0) / (8.0 * PI),
                };
                kd * FRAC_1_PI + ks * (scale * lobe)
            }
        }
    }

    /// A direction drawn from the specular lobe: `cos^p` about the mirrored
    /// `wo` (Phong) or a half vector `cos^p` about the normal (Blinn-Phong).
    #[inline]
    pub fn sample_lobe(&self, wo: Vec3, u: (f32, f32)) -> Vec3 {
        match self.lobe {
            Lobe::Phong => power_cosine_about(reflect_z(wo), self.exponent, u),
            Lobe::BlinnPhong => reflect_about(wo, power_cosine(self.exponent, u)),
        }
    }

    /// Density of [`sample_lobe`](Self::sample_lobe) at `wi`.
    #[inline]
    pub fn lobe_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.lobe {
            Lobe::Phong => power_cosine_pdf(self.exponent, reflect_z(wo).dot(wi)),
            Lobe::BlinnPhong => {
                let h = (wi + wo).normalize_or_zero();
                half_vector_pdf(power_cosine_pdf(self.exponent, h.z), wo, h)
            }
        }
    }
}
