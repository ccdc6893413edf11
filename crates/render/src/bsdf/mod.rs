//! How surfaces scatter light: every scattering model luster has, behind one
//! interface, [`Bsdf`], which both integrators call.
//!
//! A [`Material`] scatters in up to two parts:
//! - a diffuse and glossy part: a hw6 BRDF ([`brdf`]: the Phong family and
//!   Torrance–Sparrow) or, where the material names none, the course's
//!   Blinn-Phong reflectance ([`blinn_phong`](mod@blinn_phong)); or, where a
//!   shader returned a closure, its [`Lobes`] ([`closure`], built of the
//!   [`lobe`]s: diffuse, conductor, dielectric, sheen);
//! - a perfectly specular part ([`specular`]): a mirror, a conductor or a
//!   dielectric, each with the course's glossy roughness.
//!
//! [`Bsdf`] is a material at one shading point, in the local frame of the
//! normal facing the viewer ([`Frame`]: `+z` the normal; `wi` points towards
//! the light, `wo` towards the viewer, both unit length):
//!
//! | method | what |
//! |---|---|
//! | [`Bsdf::flags`] | which lobes exist ([`Flags`]: diffuse, glossy, specular; reflection, transmission) |
//! | [`Bsdf::f_cos`] | `f(wi, wo) cos θi`, the light sent to the viewer per unit irradiance from `wi` |
//! | [`Bsdf::sample`] | a direction drawn by a [`Strategy`], its density and `f cos` |
//! | [`Bsdf::pdf`] | the density with which [`Bsdf::sample`] draws `wi` |
//! | [`Bsdf::eval_pdf`] | `f cos` and, where MIS weighs it, the density, in one pass |
//! | [`Bsdf::specular`] | the delta lobes, which the integrators follow as rays |
//!
//! The models are checked against their own definitions (`tests.rs`): each
//! sampler against its pdf by a chi-square test, energy by quadrature and a
//! white-furnace albedo, reciprocity where the model is reciprocal; and the
//! interface against itself (`interface_tests.rs`): what `sample` returns is
//! what `pdf` and `f_cos` say of the same direction, for every strategy and
//! kind of material, and the density integrates to one.

pub mod blinn_phong;
pub mod brdf;
pub mod closure;
pub mod frame;
pub mod fresnel;
pub mod lobe;
pub mod phong;
pub mod sampling;
pub mod specular;
pub mod torrance_sparrow;

#[cfg(test)]
mod interface_tests;
#[cfg(test)]
mod tests;

pub use brdf::{diffuse_pdf, Brdf, DiffuseOnly, Sample};
pub use closure::Lobes;
pub use frame::Frame;
pub use phong::{Lobe, PhongFamily, Variant};
pub use specular::Specular;
pub use torrance_sparrow::TorranceSparrow;

use crate::material::Material;
use blinn_phong::blinn_phong;
use luster_core::math::{Vec3, Vec3A};
use sampling::{power_cosine, power_cosine_pdf};

/// Which lobes a [`Bsdf`] has (pbrt's `BxDFFlags`): how it scatters
/// (diffuse, glossy, perfectly specular) and where (reflection,
/// transmission).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flags(u8);

impl Flags {
    /// No lobe: the surface scatters nothing.
    pub const NONE: Flags = Flags(0);
    /// Light reflected to the side it came from.
    pub const REFLECTION: Flags = Flags(1);
    /// Light transmitted through the surface.
    pub const TRANSMISSION: Flags = Flags(2);
    /// A lobe spread over the whole hemisphere.
    pub const DIFFUSE: Flags = Flags(4);
    /// A lobe around a preferred direction.
    pub const GLOSSY: Flags = Flags(8);
    /// A delta lobe: one direction (or a few, with the course's roughness).
    pub const SPECULAR: Flags = Flags(16);

    /// Both sets of lobes.
    #[inline]
    pub const fn union(self, other: Flags) -> Flags {
        Flags(self.0 | other.0)
    }

    /// Whether every lobe of `other` is in `self`.
    #[inline]
    pub const fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }

    /// Whether `self` and `other` share a lobe.
    #[inline]
    pub const fn intersects(self, other: Flags) -> bool {
        self.0 & other.0 != 0
    }
}

impl std::ops::BitOr for Flags {
    type Output = Flags;
    #[inline]
    fn bitor(self, other: Flags) -> Flags {
        self.union(other)
    }
}

impl Material {
    /// The lobes this material scatters with.
    #[inline]
    pub fn flags(&self) -> Flags {
        let mut f = Flags::NONE;
        if self.diffuse.max_element() > 0.0 {
            f = f | Flags::DIFFUSE | Flags::REFLECTION;
        }
        if self.specular.max_element() > 0.0 {
            f = f | Flags::GLOSSY | Flags::REFLECTION;
        }
        match self.kind {
            Specular::None => f,
            Specular::Mirror | Specular::Conductor { .. } => f | Flags::SPECULAR | Flags::REFLECTION,
            Specular::Dielectric { .. } => f | Flags::SPECULAR | Flags::REFLECTION | Flags::TRANSMISSION,
        }
    }
}

/// How [`Bsdf::sample`] draws a direction: the course's `<RendererParams>`
/// variants of the path tracer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Uniform over the hemisphere, `p = 1/2π` (no `ImportanceSampling`).
    Uniform,
    /// Cosine-weighted, `p = cos/π` (`ImportanceSampling`).
    Cosine,
    /// From the BRDF's own mixture of diffuse and lobe (MIS); cosine-weighted
    /// where the material names no BRDF.
    Brdf,
}

/// A direction drawn by [`Bsdf::sample`], in world space.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// The direction towards the light.
    pub wi: Vec3,
    /// Its density per unit solid angle.
    pub pdf: f32,
    /// `f(wi, wo) cos θi`.
    pub f_cos: Vec3,
}

/// A material's scattering at one shading point: the facing shading normal
/// `n`, the incoming ray's direction `d` and, for a material with a BRDF,
/// the frame around `n` and the direction to the viewer in it (the course's
/// Blinn-Phong needs neither). For a Phong-family BRDF without
/// specular colour (every wall of the course's Cornell boxes) `f` holds its
/// value for directions above the surface (zero where the viewer is below
/// it), the same for every light sample and bounce; then `wo` holds only its
/// `z` (`x` and `y` are zero), since that BRDF's value, density and sample
/// need no more.
#[derive(Clone, Copy)]
pub struct Bsdf<'a> {
    m: &'a Material,
    /// The unit shading normal, on the side the directions are reflected to.
    pub n: Vec3,
    /// The frame around `n` where the material has a BRDF (the world's axes
    /// otherwise, which nothing reads).
    frame: Frame,
    /// The direction to the viewer in `frame` (only its `z` where `f` is
    /// set; zero without a BRDF).
    pub wo: Vec3,
    /// The incoming ray's direction, world space.
    pub d: Vec3,
    /// The BRDF's value where it is the same for every direction above the
    /// surface. A `Vec3A`: it is read right after it is written, and a
    /// `Vec3`'s narrower stores could not be forwarded to that wider load.
    pub f: Option<Vec3A>,
    /// A shader closure's lobes, which replace the material's models.
    lobes: Option<&'a Lobes>,
}

impl<'a> Bsdf<'a> {
    /// The scattering of `m` at a point of unit shading normal `n`, seen along
    /// the ray direction `d`.
    #[inline(always)]
    pub fn new(m: &'a Material, n: Vec3, d: Vec3) -> Bsdf<'a> {
        if m.brdf.is_none() {
            return Bsdf { m, n, frame: Frame::AXES, wo: Vec3::ZERO, d, f: None, lobes: None };
        }
        let frame = Frame::new(n);
        // [`PhongFamily::eval_diffuse`]'s test of the viewer's cosine. The
        // local `z` of `-d` is `-d·n`, as [`Frame::to_local`] works it out.
        let (wo, f) = match m.traits.phong_diffuse {
            Some(f) => {
                let z = (-d).dot(n);
                (Vec3::new(0.0, 0.0, z), Some(Vec3A::from(if z <= 0.0 { Vec3::ZERO } else { f })))
            }
            None => (frame.to_local(-d), None),
        };
        Bsdf { m, n, frame, wo, d, f, lobes: None }
    }

    /// The scattering of a shader closure's `lobes` (flattened for the ray
    /// direction `d`) on material `m`.
    #[inline]
    pub fn closure(m: &'a Material, lobes: &'a Lobes, d: Vec3) -> Bsdf<'a> {
        let (frame, wo) = (lobes.frame, lobes.wo);
        Bsdf { m, n: frame.normal(), frame, wo, d, f: None, lobes: Some(lobes) }
    }

    /// The closure's lobes, where the material is a closure.
    #[inline(always)]
    pub fn lobes(&self) -> Option<&'a Lobes> {
        self.lobes
    }

    /// The material.
    #[inline(always)]
    pub fn material(&self) -> &'a Material {
        self.m
    }

    /// The lobes it scatters with.
    #[inline]
    pub fn flags(&self) -> Flags {
        match self.lobes {
            Some(l) => l.flags,
            None => self.m.flags(),
        }
    }

    /// The perfectly specular part, which the integrators trace as rays
    /// ([`specular`]).
    #[inline(always)]
    pub fn specular(&self) -> Specular {
        self.m.kind
    }

    /// The whole view direction in the frame, where `wo` may hold its `z`
    /// alone.
    #[inline]
    pub fn wo_full(&self) -> Vec3 {
        if self.f.is_some() {
            self.frame.to_local(-self.d)
        } else {
            self.wo
        }
    }

    /// `f(wi, wo) cos` for a world direction `wi` with `cos = n·wi > 0`: the
    /// material's BRDF, or the course's Blinn-Phong reflectance where it names
    /// none. Where `f` is set the local `z` of `wi` is `wi·n`, the bits of
    /// `cos`, so `wi` need not be brought into the frame.
    #[inline(always)]
    pub fn f_cos(&self, wi: Vec3, cos: f32) -> Vec3 {
        if let Some(l) = self.lobes {
            return l.eval(self.frame.to_local(wi)).0;
        }
        let m = self.m;
        match (&m.brdf, self.f) {
            (_, Some(f)) => Vec3::from(f) * cos,
            (Some(b), None) => b.eval(m.diffuse, m.specular, self.frame.to_local(wi), self.wo) * cos,
            (None, None) => blinn_phong(m, self.n, wi, self.d, cos),
        }
    }

    /// For a light sample from `wi` (`cos = n·wi > 0`): `f cos`, and the
    /// density with which [`sample`](Self::sample) would draw `wi` under
    /// `strategy` (zero for a BRDF not sampled by its own mixture, which no
    /// weight then needs), the local directions worked out once.
    #[inline(always)]
    pub fn eval_pdf(&self, wi: Vec3, cos: f32, strategy: Strategy) -> (Vec3, f32) {
        if let Some(l) = self.lobes {
            return l.eval(self.frame.to_local(wi));
        }
        let m = self.m;
        match &m.brdf {
            Some(b) if strategy == Strategy::Brdf => {
                // Without a lobe only the cosines count: the local `z` of
                // `wi` is `n·wi`, the bits of `cos`.
                if let (true, Some(f)) = (m.traits.diffuse_only, self.f) {
                    return (Vec3::from(f) * cos, diffuse_pdf(self.wo.z, cos));
                }
                let local = self.frame.to_local(wi);
                let wo = self.wo_full();
                let f = b.eval(m.diffuse, m.specular, local, wo) * cos;
                (f, b.pdf(m.diffuse, m.specular, wo, local))
            }
            Some(_) => (self.f_cos(wi, cos), 0.0),
            None => {
                let e = if strategy == Strategy::Uniform { 0.0 } else { 1.0 };
                (self.f_cos(wi, cos), power_cosine_pdf(e, cos))
            }
        }
    }

    /// The density with which [`sample`](Self::sample) draws the world
    /// direction `wi` (`cos = n·wi`) under `strategy`; zero below the surface.
    #[inline]
    pub fn pdf(&self, wi: Vec3, cos: f32, strategy: Strategy) -> f32 {
        if let Some(l) = self.lobes {
            return l.pdf(self.frame.to_local(wi));
        }
        let m = self.m;
        match (&m.brdf, strategy) {
            (Some(b), Strategy::Brdf) => {
                if let (true, Some(_)) = (m.traits.diffuse_only, self.f) {
                    return diffuse_pdf(self.wo.z, cos);
                }
                b.pdf(m.diffuse, m.specular, self.wo_full(), self.frame.to_local(wi))
            }
            (_, Strategy::Uniform) => power_cosine_pdf(0.0, cos),
            _ => power_cosine_pdf(1.0, cos),
        }
    }

    /// A direction drawn by `strategy` from `choice` (which part of a BRDF's
    /// mixture; unused otherwise) and `u`, with its density and `f cos`;
    /// `None` where it brings no light (below the surface, or a zero
    /// density).
    #[inline(always)]
    pub fn sample(&self, strategy: Strategy, choice: f32, u: (f32, f32)) -> Option<BsdfSample> {
        if let Some(l) = self.lobes {
            // A closure draws from its own lobes under every strategy: a
            // hemisphere would miss its transmission.
            let s = l.sample(choice, u)?;
            return Some(BsdfSample { wi: self.frame.to_world(s.wi), pdf: s.pdf, f_cos: s.f_cos });
        }
        let (m, n) = (self.m, self.n);
        // Each arm tests the direction (`n·wi > 0`, `p > 0`) before its
        // `f cos`: the same tests as one after the match, without carrying an
        // optional value out of it.
        match (&m.brdf, strategy) {
            (Some(b), Strategy::Brdf) => {
                let only = if m.traits.diffuse_only { b.assume_diffuse_only() } else { None };
                let s = match only {
                    // Only the mixture's fallback (a choice not below 1) needs
                    // more of the view direction than its `z`.
                    Some(d) if choice < 1.0 => d.sample(m.diffuse, m.specular, self.wo, choice, u),
                    Some(d) => d.sample(m.diffuse, m.specular, self.wo_full(), choice, u),
                    None => b.sample(m.diffuse, m.specular, self.wo_full(), choice, u),
                };
                let s = s?;
                // The BRDF's sample carries its value: no second evaluation.
                let wi = self.frame.to_world(s.wi);
                let cos = n.dot(wi);
                if cos <= 0.0 || s.pdf <= 0.0 {
                    return None;
                }
                Some(BsdfSample { wi, pdf: s.pdf, f_cos: s.f * cos })
            }
            (b, _) => {
                // The exponent a constant in each arm: its tests fold away.
                let (local, pdf) = if strategy == Strategy::Uniform {
                    let local = power_cosine(0.0, u);
                    (local, power_cosine_pdf(0.0, local.z))
                } else {
                    let local = power_cosine(1.0, u);
                    (local, power_cosine_pdf(1.0, local.z))
                };
                // Without a BRDF the frame was not built (see [`Bsdf::new`]).
                let frame = if b.is_some() { self.frame } else { Frame::new(n) };
                let wi = frame.to_world(local);
                let cos = n.dot(wi);
                if cos <= 0.0 || pdf <= 0.0 {
                    return None;
                }
                Some(BsdfSample { wi, pdf, f_cos: self.f_cos(wi, cos) })
            }
        }
    }
}
