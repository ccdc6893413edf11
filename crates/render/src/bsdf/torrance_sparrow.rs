//! The Torrance-Sparrow microfacet BRDF of the course (CENG795 hw6):
//!
//! `f(wi, wo) = kd/π + ks D(α) F(β) G(wi, wo) / (4 cos θi cos θo)`
//!
//! with the Blinn distribution `D(α) = (p+2)/2π cos^p α` (`α` the angle
//! between the normal and the half vector `h`), the Fresnel reflectance
//! `F(β)` at `cos β = wo · h` from the material's `RefractionIndex` and
//! `AbsorptionIndex` (the course's conductor formula; a zero absorption
//! index gives the dielectric value), and the V-groove shadowing term
//! `G = min(1, 2 (n·h)(n·wo)/(wo·h), 2 (n·h)(n·wi)/(wo·h))`.
//! With `kdfresnel="true"` the diffuse term becomes `(1 - F) kd/π`.

use super::sampling::{half_vector_pdf, power_cosine, power_cosine_pdf, reflect_about};
use crate::bsdf::fresnel;
use luster_core::math::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// A Torrance-Sparrow BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorranceSparrow {
    /// The distribution's exponent `p`.
    pub exponent: f32,
    /// Weight the diffuse term by `1 - F`.
    pub kd_fresnel: bool,
    /// Real part of the surface's index of refraction.
    pub eta: f32,
    /// Imaginary part (absorption index).
    pub k: f32,
}

impl TorranceSparrow {
    /// `f(wi, wo)` in the local frame (normal `+z`).
    #[inline]
    pub fn eval(&self, kd: Vec3, ks: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wi + wo).normalize_or_zero();
        let cos_h = h.z.max(0.0);
        let cos_b = wo.dot(h).max(1e-7);
        let d = (self.exponent + 2.0) / (2.0 * PI) * cos_h.powf(self.exponent);
        let f = fresnel::conductor(cos_b, self.eta, self.k);
        let g = (2.0 * cos_h * cos_o.min(cos_i) / cos_b).min(1.0);
        let diffuse = if self.kd_fresnel { kd * ((1.0 - f) * FRAC_1_PI) } else { kd * FRAC_1_PI };
        diffuse + ks * (d * f * g / (4.0 * cos_i * cos_o))
    }

    /// A direction reflected about a half vector drawn from `D(α) cos α`.
    #[inline]
    pub fn sample_lobe(&self, wo: Vec3, u: (f32, f32)) -> Vec3 {
        reflect_about(wo, power_cosine(self.exponent + 1.0, u))
    }

    /// Density of [`sample_lobe`](Self::sample_lobe) at `wi`.
    #[inline]
    pub fn lobe_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let h = (wi + wo).normalize_or_zero();
        half_vector_pdf(power_cosine_pdf(self.exponent + 1.0, h.z), wo, h)
    }
}
