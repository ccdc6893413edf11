//! Glass, water, a coat: a GGX dielectric boundary that reflects and
//! refracts (Walter et al. 2007, in the form of pbrt-v4's `DielectricBxDF`),
//! or a thin-walled sheet that reflects and passes light without bending
//! it, scaled to return the light single scattering loses between
//! microfacets.
//!
//! - `eta` is the relative index: below the surface over the viewer's side
//!   (the caller passes `ior` entering and `1/ior` leaving), so `eta < 1`
//!   has total internal reflection. It is kept within
//!   [`albedo::ETA_MIN`]–[`albedo::ETA_MAX`] and at least `10⁻³` from 1,
//!   where the transmitted lobe would collapse to a delta.
//! - Reflection and transmission are chosen per sampled normal by their
//!   Fresnel weights `R` and `T = 1 − R` (times the mean `specular` and
//!   `tint`); the exact unpolarized Fresnel equations give `R`.
//! - Radiance convention (pbrt-v4's `TransportMode::Radiance`): the
//!   transmitted `f` carries `1/η²`, the change of radiance as light crosses
//!   from below (index `η`) to the viewer's side (index 1). A white boundary
//!   therefore returns `R + T/η²` of the radiance while conserving energy:
//!   the energy is `R + T`. [`Dielectric::albedo`] follows the radiance
//!   (it is `∫ f |cos θi|`), [`Dielectric::transmittance`] the energy.
//! - Energy: each direction is divided by the white boundary's single-
//!   scattering albedo `E(μo, α, η)` ([`albedo::boundary`], energy terms),
//!   so reflection plus transmission keeps what it receives (Turquin 2019).
//! - Thin walls (OpenPBR `thin_walled`): a slab with two parallel faces.
//!   Its reflectance and transmittance per microfacet are the slab's sums
//!   over internal reflections, `R' = R + T²R / (1 − R²) = 2R / (1 + R)` and
//!   `T' = T² / (1 − R²)`; the transmitted lobe is the reflected one
//!   mirrored through the surface plane. Nothing bends, so no `1/η²`, and
//!   `R' + T' = 1` makes the GGX reflector's albedo `E(μo, α)` the
//!   compensation.
//! - Smooth surfaces use this same lobe at `α = MIN_ALPHA`: a lobe 10⁻³
//!   wide whose density peaks near 10⁵–10⁶ per steradian and stays finite,
//!   so there is no delta case and the lobe remains `GLOSSY`.
//! - `reflection_only` (a layer's top, [`Dielectric::coat`]): no
//!   transmission lobe; the light it does not reflect passes to the layer
//!   below through [`Dielectric::transmittance`].

use super::albedo::{self, ETA_MAX, ETA_MIN};
use super::ggx::Ggx;
use super::LobeSample;
use crate::bsdf::sampling::reflect_about;
use crate::bsdf::Flags;
use luster_core::math::Vec3;

/// The closest a bending boundary's `eta` comes to 1.
const ETA_GAP: f32 = 1e-3;

/// A GGX dielectric boundary or thin sheet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// The relative index (below over the viewer's side), kept in range by
    /// the constructors; at least 1 for a thin sheet.
    pub eta: f32,
    /// The microfacet distribution.
    pub ggx: Ggx,
    /// Multiplies transmission.
    pub tint: Vec3,
    /// Multiplies reflection.
    pub specular: Vec3,
    /// A thin-walled sheet rather than a boundary between two media.
    pub thin: bool,
    /// No transmission lobe: the top of a layer.
    pub reflection_only: bool,
}

/// The exact unpolarized Fresnel reflectance for light meeting a boundary of
/// relative index `eta` (far side over near side) at cosine `cos` to its
/// normal; a negative `cos` is light from the far side. 1 under total
/// internal reflection.
#[inline]
pub fn fresnel_dielectric(cos: f32, eta: f32) -> f32 {
    let (c, eta) = if cos < 0.0 { (-cos, 1.0 / eta) } else { (cos, eta) };
    let c = c.min(1.0);
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let parallel = (eta * c - cos_t) / (eta * c + cos_t);
    let perpendicular = (c - eta * cos_t) / (c + eta * cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

/// `w` refracted through a boundary with normal `n` on `w`'s side
/// (`w·n > 0`) and relative index `eta` (far over near); `None` under total
/// internal reflection.
#[inline]
pub fn refract(w: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let c = w.dot(n);
    let sin2_t = (1.0 - c * c).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-w / eta + n * (c / eta - cos_t))
}

/// The mean of a colour's channels: a colour's weight when choosing a lobe.
#[inline]
fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

impl Dielectric {
    /// A boundary (or, `thin`, a sheet) of relative index `eta`, with GGX
    /// widths from `roughness` and `anisotropy` (OpenPBR's mapping), `tint`
    /// on transmission and `specular` on reflection.
    pub fn new(
        eta: f32,
        roughness: f32,
        anisotropy: f32,
        tint: Vec3,
        specular: Vec3,
        thin: bool,
    ) -> Dielectric {
        let eta = eta.clamp(ETA_MIN, ETA_MAX);
        let eta = if thin {
            // A sheet is the same from both sides: its index over the outside.
            eta.max(1.0 / eta)
        } else if (eta - 1.0).abs() < ETA_GAP {
            if eta < 1.0 {
                1.0 - ETA_GAP
            } else {
                1.0 + ETA_GAP
            }
        } else {
            eta
        };
        Dielectric {
            eta,
            ggx: Ggx::from_roughness(roughness, anisotropy),
            tint,
            specular,
            thin,
            reflection_only: false,
        }
    }

    /// The top of a layer: reflection only, the rest passing through
    /// [`transmittance`](Self::transmittance) tinted by `tint`.
    pub fn coat(eta: f32, roughness: f32, anisotropy: f32, tint: Vec3, specular: Vec3) -> Dielectric {
        Dielectric {
            reflection_only: true,
            ..Dielectric::new(eta, roughness, anisotropy, tint, specular, false)
        }
    }

    /// The lobe's kinds of scattering.
    pub fn flags(&self) -> Flags {
        if self.reflection_only {
            Flags::GLOSSY | Flags::REFLECTION
        } else {
            Flags::GLOSSY | Flags::REFLECTION | Flags::TRANSMISSION
        }
    }

    /// Reflectance and transmittance of a microfacet met at cosine `cos`:
    /// the boundary's Fresnel, or the thin slab's sums.
    #[inline]
    fn split(&self, cos: f32) -> (f32, f32) {
        let r = fresnel_dielectric(cos, self.eta);
        if self.thin {
            ((2.0 * r) / (1.0 + r), (1.0 - r) / (1.0 + r))
        } else {
            (r, 1.0 - r)
        }
    }

    /// The probability of choosing reflection, given `R` and `T`; `None`
    /// where neither part carries light.
    #[inline]
    fn reflect_probability(&self, r: f32, t: f32) -> Option<f32> {
        let pr = r * mean(self.specular).max(0.0);
        let pt = if self.reflection_only { 0.0 } else { t * mean(self.tint).max(0.0) };
        (pr + pt > 0.0).then(|| pr / (pr + pt))
    }

    /// `1 / E`, the white lobe's single-scattering energy albedo from `wo`.
    #[inline]
    fn compensation(&self, wo: Vec3) -> f32 {
        let e = if self.thin {
            albedo::reflector(&self.ggx, wo)
        } else {
            albedo::boundary(&self.ggx, wo, self.eta).0
        };
        1.0 / e.max(1e-3)
    }

    /// The fraction of the energy from `wo` the (compensated, white) lobe
    /// reflects rather than transmits.
    #[inline]
    fn reflected_fraction(&self, wo: Vec3) -> f32 {
        let (total, reflect, thin) = albedo::boundary(&self.ggx, wo, self.eta);
        if self.thin {
            (thin / albedo::reflector(&self.ggx, wo).max(1e-3)).clamp(0.0, 1.0)
        } else {
            (reflect / total.max(1e-3)).clamp(0.0, 1.0)
        }
    }

    /// `f cos θi` and density of `wi = reflect(wo, h)`, or of its mirror
    /// image `wi` through the plane for a thin sheet's transmission
    /// (`wr = reflect(wo, h)` either way).
    #[inline]
    fn eval_mirror(&self, wo: Vec3, wr: Vec3, h: Vec3, transmit: bool) -> (Vec3, f32) {
        let (r, t) = self.split(wo.dot(h));
        let Some(p_reflect) = self.reflect_probability(r, t) else {
            return (Vec3::ZERO, 0.0);
        };
        let d = self.ggx.d(h);
        let base = d * self.ggx.g2(wo, wr) / (4.0 * wo.z) * self.compensation(wo);
        let pdf = self.ggx.g1(wo) * d / (4.0 * wo.z);
        if transmit {
            (self.tint * (t * base), pdf * (1.0 - p_reflect))
        } else {
            (self.specular * (r * base), pdf * p_reflect)
        }
    }

    /// `f cos θi` and density of `wi` refracted through the normal `h`
    /// (Walter et al.'s generalized half vector and Jacobian).
    #[inline]
    fn eval_refract(&self, wo: Vec3, wi: Vec3, h: Vec3) -> (Vec3, f32) {
        let (co, ci) = (wo.dot(h), wi.dot(h));
        if co <= 0.0 || ci >= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let (r, t) = self.split(co);
        let Some(p_reflect) = self.reflect_probability(r, t) else {
            return (Vec3::ZERO, 0.0);
        };
        let denom = ci + co / self.eta;
        let jacobian = -ci / (denom * denom);
        let d = self.ggx.d(h);
        // f |cos θi| = T D G2 |wi·h| (wo·h) / (cos θo denom²) / η² (radiance).
        let f_cos = t * d * self.ggx.g2(wo, wi) * co * jacobian / (wo.z * self.eta * self.eta)
            * self.compensation(wo);
        let pdf = self.ggx.d_visible(wo, h) * jacobian * (1.0 - p_reflect);
        (self.tint * f_cos, pdf)
    }

    /// `f(wi, wo) |cos θi|` and the density with which
    /// [`sample`](Self::sample) draws `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if wo.z <= 0.0 || wi.z == 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        if wi.z > 0.0 {
            let h = (wo + wi).normalize_or_zero();
            return if h.z > 0.0 { self.eval_mirror(wo, wi, h, false) } else { (Vec3::ZERO, 0.0) };
        }
        if self.reflection_only {
            return (Vec3::ZERO, 0.0);
        }
        if self.thin {
            let wr = Vec3::new(wi.x, wi.y, -wi.z);
            let h = (wo + wr).normalize_or_zero();
            return if h.z > 0.0 { self.eval_mirror(wo, wr, h, true) } else { (Vec3::ZERO, 0.0) };
        }
        let h = (wo + wi * self.eta).normalize_or_zero();
        let h = if h.z < 0.0 { -h } else { h };
        if h.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        self.eval_refract(wo, wi, h)
    }

    /// A visible normal drawn from `u`, then reflection or transmission
    /// through it chosen by `uc` against their weights; `None` where the
    /// chosen direction falls on the wrong side.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: (f32, f32)) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let h = self.ggx.sample_visible(wo, u);
        let co = wo.dot(h);
        if co <= 0.0 {
            return None;
        }
        let (r, t) = self.split(co);
        let reflect = uc < self.reflect_probability(r, t)?;
        let (wi, (f_cos, pdf)) = if reflect || self.thin {
            let wr = reflect_about(wo, h);
            if wr.z <= 0.0 {
                return None;
            }
            if reflect {
                (wr, self.eval_mirror(wo, wr, h, false))
            } else {
                (Vec3::new(wr.x, wr.y, -wr.z), self.eval_mirror(wo, wr, h, true))
            }
        } else {
            let wi = refract(wo, h, self.eta)?;
            if wi.z >= 0.0 {
                return None;
            }
            (wi, self.eval_refract(wo, wi, h))
        };
        (pdf > 0.0).then_some(LobeSample { wi, f_cos, pdf })
    }

    /// `∫ f |cos θi| dωi` from the tables, per channel: reflection's share
    /// times `specular`, plus, unless reflection only, transmission's share
    /// times `tint` (and `1/η²` through a bending boundary).
    #[inline]
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        if wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let r = self.reflected_fraction(wo);
        let reflected = self.specular * r;
        if self.reflection_only {
            return reflected;
        }
        let scale = if self.thin { 1.0 } else { 1.0 / (self.eta * self.eta) };
        reflected + self.tint * ((1.0 - r) * scale)
    }

    /// The energy from `wo` that passes through to a layer below:
    /// `tint (1 − reflection albedo)`.
    #[inline]
    pub fn transmittance(&self, wo: Vec3) -> Vec3 {
        if wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.tint * (Vec3::ONE - self.specular * self.reflected_fraction(wo))
    }
}
