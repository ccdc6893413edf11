//! The lobes a shader's closure is made of (`docs/closures.md`): diffuse,
//! conductor, dielectric and sheen, each able to evaluate itself, draw a
//! direction, give that direction's density and estimate its own albedo.
//!
//! Conventions shared by every lobe:
//! - directions are in the local shading frame: `+z` the shading normal on
//!   the viewer's side, `+x` the tangent anisotropy stretches along;
//! - `wo` points towards the viewer and `wo.z > 0` (the caller flips the
//!   frame so); a lobe given `wo.z <= 0` returns nothing;
//! - `wi` points towards the light; `wi.z < 0` is transmission;
//! - what a lobe returns is `f(wi, wo) |cos θi|`, its density per unit solid
//!   angle of `wi`, and for albedos the hemispherical (reflection plus
//!   transmission) integral of `f |cos θi|` over `wi`;
//! - roughness `r` in 0–1 maps to the microfacet width `α = r²`, clamped to
//!   [`ggx::MIN_ALPHA`] (OpenPBR's and Disney's mapping).

pub mod albedo;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod ggx;
pub mod sheen;

#[cfg(test)]
pub(crate) mod tests;

pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use sheen::Sheen;

use super::closure::MirrorSplit;
use super::Flags;
use luster_core::math::Vec3;

/// A direction drawn from a lobe, in the local frame.
#[derive(Clone, Copy, Debug)]
pub struct LobeSample {
    /// Towards the light; `z < 0` for a transmitted direction.
    pub wi: Vec3,
    /// `f(wi, wo) |cos θi|`.
    pub f_cos: Vec3,
    /// The density of `wi` per unit solid angle.
    pub pdf: f32,
}

/// One lobe of a closure, matched in place on the hot path.
#[derive(Clone, Copy, Debug)]
pub enum Lobe {
    /// Lambertian, or energy-preserving Oren–Nayar (EON) when rough.
    Diffuse(Diffuse),
    /// A metal: GGX with F82-tint Fresnel and multiple-scattering compensation.
    Conductor(Conductor),
    /// Glass, water, a coat: GGX reflection and refraction.
    Dielectric(Dielectric),
    /// Cloth and dust: a retro- and grazing-reflective fuzz.
    Sheen(Sheen),
}

impl Lobe {
    /// `f(wi, wo) |cos θi|` and the density with which [`Lobe::sample`]
    /// draws `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        match self {
            Lobe::Diffuse(l) => l.eval(wo, wi),
            Lobe::Conductor(l) => l.eval(wo, wi),
            Lobe::Dielectric(l) => l.eval(wo, wi),
            Lobe::Sheen(l) => l.eval(wo, wi),
        }
    }

    /// A direction drawn from `uc` (a choice between the lobe's parts, such
    /// as a dielectric's reflection and refraction) and `u`; `None` where
    /// the draw brings no light.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: (f32, f32)) -> Option<LobeSample> {
        match self {
            Lobe::Diffuse(l) => l.sample(wo, uc, u),
            Lobe::Conductor(l) => l.sample(wo, uc, u),
            Lobe::Dielectric(l) => l.sample(wo, uc, u),
            Lobe::Sheen(l) => l.sample(wo, uc, u),
        }
    }

    /// The fraction of the light from `wo` the lobe scatters, per channel:
    /// an estimate (a table or a fit) good to a few percent, which picks
    /// lobes and weighs layers.
    #[inline]
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        match self {
            Lobe::Diffuse(l) => l.albedo(wo),
            Lobe::Conductor(l) => l.albedo(wo),
            Lobe::Dielectric(l) => l.albedo(wo),
            Lobe::Sheen(l) => l.albedo(wo),
        }
    }

    /// Whether the lobe's colours are black, so that it scatters nothing
    /// (a conductor's Fresnel rises towards white at grazing angles
    /// whatever its colours, so it never is).
    #[inline]
    pub fn is_black(&self) -> bool {
        match self {
            Lobe::Diffuse(l) => l.color() == Vec3::ZERO,
            Lobe::Conductor(_) => false,
            Lobe::Dielectric(l) => l.specular == Vec3::ZERO && (l.reflection_only || l.tint == Vec3::ZERO),
            Lobe::Sheen(l) => l.color() == Vec3::ZERO,
        }
    }

    /// What of the light from `wo` passes through the lobe to a layer below
    /// it, where the lobe is a layer's top: a dielectric's transmission
    /// (tinted), the part a sheen does not scatter; none through a diffuse
    /// or conducting top.
    #[inline]
    pub fn transmittance(&self, wo: Vec3) -> Vec3 {
        match self {
            Lobe::Diffuse(_) | Lobe::Conductor(_) => Vec3::ZERO,
            Lobe::Dielectric(l) => l.transmittance(wo),
            Lobe::Sheen(l) => Vec3::ONE - l.albedo(wo),
        }
    }

    /// The lobe as the recursive ray tracer follows it, where it is smooth
    /// enough to be a mirror (roughness under 0.1): the weights of the
    /// mirror-reflected and the refracted ray, by the Fresnel equations at
    /// the viewer's angle. `None` for a rough lobe, which reflects the
    /// lights only.
    #[inline]
    pub fn mirror_split(&self, wo: Vec3) -> Option<MirrorSplit> {
        if !self.is_smooth() {
            return None;
        }
        match self {
            Lobe::Conductor(c) => Some(MirrorSplit { reflect: c.fresnel(wo.z), ..MirrorSplit::default() }),
            Lobe::Dielectric(d) => {
                let r = dielectric::fresnel_dielectric(wo.z, d.eta);
                let (r, t) = if d.thin && r < 1.0 {
                    // The sheet's two faces, every internal reflection summed.
                    let t = 1.0 - r;
                    (r + t * t * r / (1.0 - r * r), t * t / (1.0 - r * r))
                } else {
                    (r, 1.0 - r)
                };
                let refract = if d.reflection_only { Vec3::ZERO } else { d.tint * t };
                Some(MirrorSplit { reflect: d.specular * r, refract, eta: d.eta, thin: d.thin })
            }
            _ => None,
        }
    }

    /// Whether the recursive ray tracer follows the lobe as rays
    /// ([`mirror_split`](Self::mirror_split)): a conductor or dielectric of
    /// roughness under 0.1 (`α` under 0.01).
    #[inline]
    pub fn is_smooth(&self) -> bool {
        const SMOOTH: f32 = 0.01;
        match self {
            Lobe::Conductor(c) => c.ggx.alpha_rms() < SMOOTH,
            Lobe::Dielectric(d) => d.ggx.alpha_rms() < SMOOTH,
            Lobe::Diffuse(_) | Lobe::Sheen(_) => false,
        }
    }

    /// The lobe's kinds of scattering.
    #[inline]
    pub fn flags(&self) -> Flags {
        match self {
            Lobe::Diffuse(_) => Flags::DIFFUSE | Flags::REFLECTION,
            Lobe::Conductor(_) => Flags::GLOSSY | Flags::REFLECTION,
            Lobe::Dielectric(l) => l.flags(),
            Lobe::Sheen(_) => Flags::GLOSSY | Flags::REFLECTION,
        }
    }
}
