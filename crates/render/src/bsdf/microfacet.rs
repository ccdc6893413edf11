//! luster's physically based reflection model for shader-driven materials
//! (`docs/shaders.md`, "Material outputs"): a Lambertian base under a
//! Trowbridge-Reitz (GGX) microfacet lobe, a reduced form of the
//! Disney/Cycles Principled BSDF (one specular lobe, no sheen or coat):
//!
//! `f(wi, wo) = (1 - max F0) kd/π + D(h) G(wi, wo) F(wo·h) / (4 cos θi cos θo)`
//!
//! * `D` is the GGX distribution of width `α` (a shader's `roughness` r gives
//!   `α = r²`, the Disney remapping, so equal steps of r look like equal steps
//!   of blur);
//! * `G` is Smith's height-correlated masking-shadowing term for GGX;
//! * `F` is Schlick's Fresnel with the normal-incidence reflectance `F0`,
//!   the material's (or shader's) specular colour; a metal's `F0` is its
//!   base colour. A specular colour of 0 reflects nothing (see [`schlick`]).
//!
//! The diffuse part is dimmed by `1 - max F0` so that a white base under a
//! white specular colour cannot reflect more than it receives. Like every
//! single-scattering microfacet model it loses the light that would bounce
//! between microfacets: for a white metal 0.01% at roughness 0.1, 1–2% at
//! 0.3 and 8–14% at 0.5, more towards grazing views (`bsdf/tests.rs`
//! measures it).

use super::sampling::{half_vector_pdf, reflect_about};
use luster_core::math::{sin_cos_turns, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// Narrowest lobe: below this width a lobe is a mirror in all but name, and
/// its peak value overflows single precision.
pub const MIN_ALPHA: f32 = 1e-3;

/// A GGX microfacet lobe over a Lambertian base.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    /// The distribution's width `α`, in `[MIN_ALPHA, 1]`.
    pub alpha: f32,
}

impl Microfacet {
    /// The lobe for a roughness `r` in 0–1 (`α = r²`).
    pub fn from_roughness(r: f32) -> Microfacet {
        Microfacet { alpha: (r * r).clamp(MIN_ALPHA, 1.0) }
    }

    /// The lobe whose width matches a Blinn-Phong exponent `p`: Walter et
    /// al.'s (2007) `α = sqrt(2 / (p + 2))`, so a material that states only
    /// its `PhongExponent` keeps its highlight's width.
    pub fn from_exponent(p: f32) -> Microfacet {
        Microfacet { alpha: (2.0 / (p.max(0.0) + 2.0)).sqrt().clamp(MIN_ALPHA, 1.0) }
    }

    /// `D(h)` for a half vector with cosine `c` to the normal.
    #[inline]
    fn d(&self, c: f32) -> f32 {
        if c <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = c * c * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }

    /// Smith's `Λ(w)` for GGX.
    #[inline]
    fn lambda(&self, cos: f32) -> f32 {
        let c2 = cos * cos;
        let tan2 = (1.0 - c2).max(0.0) / c2.max(1e-12);
        0.5 * ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0)
    }

    /// `f(wi, wo)` in the local frame (normal `+z`), with base colour `kd`
    /// and normal-incidence reflectance `f0`.
    #[inline]
    pub fn eval(&self, kd: Vec3, f0: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wi + wo).normalize_or_zero();
        let g = 1.0 / (1.0 + self.lambda(cos_i) + self.lambda(cos_o));
        let f = schlick(f0, wo.dot(h).max(0.0));
        let diffuse = kd * ((1.0 - f0.max_element().clamp(0.0, 1.0)) * FRAC_1_PI);
        diffuse + f * (self.d(h.z) * g / (4.0 * cos_i * cos_o))
    }

    /// A direction reflected about a half vector drawn from `D(h) cos θh`.
    #[inline]
    pub fn sample_lobe(&self, wo: Vec3, (u1, u2): (f32, f32)) -> Vec3 {
        let a2 = self.alpha * self.alpha;
        let tan2 = a2 * u1 / (1.0 - u1).max(1e-7);
        let cos = 1.0 / (1.0 + tan2).sqrt();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let (sp, cp) = sin_cos_turns(u2);
        reflect_about(wo, Vec3::new(sin * cp, sin * sp, cos))
    }

    /// Density of [`sample_lobe`](Self::sample_lobe) at `wi`.
    #[inline]
    pub fn lobe_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let h = (wi + wo).normalize_or_zero();
        half_vector_pdf(self.d(h.z) * h.z.max(0.0), wo, h)
    }
}

/// Schlick's Fresnel approximation for reflectance `f0` at normal incidence,
/// rising towards the grazing reflectance `f90`. `f90` is 1 except for a
/// specular colour below 2%, where it falls to 0 with it (as in Unreal's
/// shading model): no real material reflects under 2% head on, so such a
/// colour means "no specular", and a zero specular colour reflects nothing.
#[inline]
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = 1.0 - cos.clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    let f90 = (50.0 * f0.max_element()).clamp(0.0, 1.0);
    f0 + (Vec3::splat(f90) - f0) * m5
}
