//! A metal: anisotropic GGX reflection with OpenPBR 1.1's F82-tint Fresnel,
//! sampled by visible normals, and scaled to return the light that single
//! scattering loses between microfacets.
//!
//! `f = F(wo·h) D(h) G2(wo, wi) / (4 cos θo cos θi) · (1 + F_ms (1 − E) / E)`
//!
//! The last factor is Turquin's (2019) compensation with Kulla and Conty's
//! (2017) multiple-bounce Fresnel `F_ms = F_avg E_avg / (1 − F_avg (1 −
//! E_avg))`: `E = E(μo, α)` is a white reflector's single-scattering albedo
//! ([`albedo::reflector`]), so a white metal (`F = 1`, `F_ms = 1`) reflects
//! everything it receives, and a coloured one gains the extra, more
//! saturated light of the bounces it would take. The factor depends on `wo`
//! alone, so the compensated lobe is not exactly reciprocal; the
//! single-scattering part is.

use super::albedo;
use super::ggx::Ggx;
use super::LobeSample;
use crate::bsdf::sampling::reflect_about;
use luster_core::math::Vec3;

/// The cosine at which F82-tint pins the reflectance to `edge` times
/// Schlick's: `1/7`, about 82°.
const MU_BAR: f32 = 1.0 / 7.0;

/// A GGX conductor with F82-tint Fresnel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Reflectance at normal incidence.
    pub f0: Vec3,
    /// F82-tint's tint: the reflectance near grazing (82°) relative to
    /// Schlick's; 1 is plain Schlick.
    pub edge: Vec3,
    /// The microfacet distribution.
    pub ggx: Ggx,
}

/// Schlick's Fresnel rising from `f0` head on to 1 at grazing.
#[inline]
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = 1.0 - cos.clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

/// F82-tint's coefficient `b`: the correction `b μ (1 − μ)⁶` that brings
/// Schlick's reflectance at `μ = 1/7` down to `edge` times itself.
#[inline]
fn f82_b(f0: Vec3, edge: Vec3) -> Vec3 {
    let m = 1.0 - MU_BAR;
    let m6 = (m * m * m) * (m * m * m);
    schlick(f0, MU_BAR) * (Vec3::ONE - edge) / (MU_BAR * m6)
}

/// OpenPBR 1.1's F82-tint Fresnel (Kutz et al. 2021): Schlick's minus
/// `b μ (1 − μ)⁶`, kept within 0–1.
#[inline]
pub fn f82_tint(f0: Vec3, edge: Vec3, cos: f32) -> Vec3 {
    let c = cos.clamp(0.0, 1.0);
    let m = 1.0 - c;
    let m6 = (m * m * m) * (m * m * m);
    (schlick(f0, c) - f82_b(f0, edge) * (c * m6)).clamp(Vec3::ZERO, Vec3::ONE)
}

impl Conductor {
    /// The conductor with normal-incidence reflectance `f0`, F82 tint `edge`,
    /// and GGX widths from `roughness` and `anisotropy` (0–1, OpenPBR's
    /// mapping, [`Ggx::from_roughness`]).
    pub fn new(f0: Vec3, edge: Vec3, roughness: f32, anisotropy: f32) -> Conductor {
        Conductor { f0, edge, ggx: Ggx::from_roughness(roughness, anisotropy) }
    }

    /// The Fresnel reflectance at cosine `cos` to the microfacet normal.
    #[inline]
    pub fn fresnel(&self, cos: f32) -> Vec3 {
        f82_tint(self.f0, self.edge, cos)
    }

    /// The cosine-weighted mean Fresnel `2 ∫ F(μ) μ dμ`, in closed form:
    /// `2 ∫ (1 − μ)⁵ μ dμ = 1/21` and `2 ∫ μ² (1 − μ)⁶ dμ = 1/126`.
    #[inline]
    pub fn fresnel_avg(&self) -> Vec3 {
        let avg = self.f0 + (Vec3::ONE - self.f0) / 21.0 - f82_b(self.f0, self.edge) / 126.0;
        avg.clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// The multiple-scattering factor `1 + F_ms (1 − E) / E` for `wo`.
    #[inline]
    fn compensation(&self, wo: Vec3) -> Vec3 {
        let e = albedo::reflector(&self.ggx, wo).max(1e-3);
        let e_avg = albedo::conductor().e_avg(self.ggx.alpha_rms());
        let f_avg = self.fresnel_avg();
        let f_ms = f_avg * e_avg / (Vec3::ONE - f_avg * (1.0 - e_avg));
        Vec3::ONE + f_ms * ((1.0 - e) / e)
    }

    /// The single-scattering BRDF `F D G2 / (4 cos θo cos θi)` without the
    /// compensation, which is reciprocal.
    pub fn single_scattering(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        if h.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.fresnel(wo.dot(h)) * (self.ggx.d(h) * self.ggx.g2(wo, wi) / (4.0 * wo.z * wi.z))
    }

    /// `f cos θi` and the density for `wi` reflected about `h`.
    #[inline]
    fn eval_half(&self, wo: Vec3, wi: Vec3, h: Vec3) -> (Vec3, f32) {
        let d = self.ggx.d(h);
        let f_cos =
            self.fresnel(wo.dot(h)) * (d * self.ggx.g2(wo, wi) / (4.0 * wo.z)) * self.compensation(wo);
        // D_wo(h) / (4 wo·h) with D_wo = G1(wo) (wo·h) D(h) / cos θo.
        let pdf = self.ggx.g1(wo) * d / (4.0 * wo.z);
        (f_cos, pdf)
    }

    /// `f(wi, wo) cos θi` and the density with which [`sample`](Self::sample)
    /// draws `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let h = (wo + wi).normalize_or_zero();
        if h.z <= 0.0 || wo.dot(h) <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        self.eval_half(wo, wi, h)
    }

    /// `wo` reflected about a visible normal drawn from `u`; `None` where
    /// the reflection falls below the surface. `_uc` is unused: one lobe.
    #[inline]
    pub fn sample(&self, wo: Vec3, _uc: f32, u: (f32, f32)) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let h = self.ggx.sample_visible(wo, u);
        let wi = reflect_about(wo, h);
        if wi.z <= 0.0 || wo.dot(h) <= 0.0 {
            return None;
        }
        let (f_cos, pdf) = self.eval_half(wo, wi, h);
        (pdf > 0.0).then_some(LobeSample { wi, f_cos, pdf })
    }

    /// The directional albedo from the tables: the single-scattering albedo
    /// under F82-tint from the Fresnel-weighted moments, times the
    /// compensation.
    #[inline]
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        if wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        // The isotropic moments at the RMS width, rescaled to the
        // anisotropic reflector's albedo.
        let (e, e5, e6) = albedo::conductor().moments(wo.z, self.ggx.alpha_rms());
        let single = self.f0 * e + (Vec3::ONE - self.f0) * e5 - f82_b(self.f0, self.edge) * e6;
        let scale = albedo::reflector(&self.ggx, wo) / e.max(1e-3);
        single.max(Vec3::ZERO) * scale * self.compensation(wo)
    }
}
