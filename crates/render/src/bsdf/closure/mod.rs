//! A shader's closure at one shading point: the tree `material(s)` returned
//! flattened into at most [`MAX_LOBES`] weighted lobes, its layers turned
//! into weights, with the emission and the see-through part set apart.
//!
//! A layer passes to its base what its top lets through, seen from the
//! viewer (albedo scaling, as OpenPBR's reference implementation and
//! Cycles' Principled BSDF layer their coat and sheen):
//!
//! `base weight = w · (1 − Σ_top w_k (1 − t_k(ωo)))`
//!
//! where `w_k` are the top's lobe weights and `t_k` what each lets through
//! ([`Lobe::transmittance`]): a dielectric coat its tinted transmission, a
//! sheen what it does not scatter, an opaque lobe nothing. The top's
//! reflection plus the base's weighted albedo never exceed one, so a
//! white stack is exactly as bright as its parts allow.
//!
//! Sampling picks a lobe with probability proportional to its weighted
//! albedo's luminance and draws from it; the density of a direction is the
//! mixture's, `Σ p_k pdf_k`, and its value the sum of every lobe's, so MIS
//! with light samples weighs the whole closure.

use super::frame::Frame;
use super::lobe::{Conductor, Dielectric, Diffuse, Lobe, LobeSample, Sheen};
use super::Flags;
use luster_core::math::Vec3;
use luster_shading::shader::closure::{Closure, Node, NodeKind};

#[cfg(test)]
mod tests;

/// Most lobes one shading point may have after flattening.
pub const MAX_LOBES: usize = 8;

/// Most nodes a flattening visits: a node may be shared by several parents
/// (`d + d`), so a closure of few nodes can stand for a very large tree.
const MAX_VISITS: usize = 256;

/// Luminance weights (Rec. 709), for picking lobes.
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// What the recursive ray tracer follows of a closure as rays: its smooth
/// lobes' mirror reflection and refraction, each with its weight.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MirrorSplit {
    /// The weight of the mirror-reflected ray.
    pub reflect: Vec3,
    /// The weight of the refracted ray.
    pub refract: Vec3,
    /// The relative index of refraction the refracted ray bends by.
    pub eta: f32,
    /// A thin-walled dielectric: the ray passes without bending.
    pub thin: bool,
}

/// A closure with more lobes than [`MAX_LOBES`], or that stands for a tree
/// of more than 256 nodes (shared nodes counted each time they are used).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyLobes;

/// A closure flattened at a shading point, in the frame of its facing
/// shading normal (see [`crate::bsdf::lobe`] for the conventions).
#[derive(Clone, Copy, Debug)]
pub struct Lobes {
    lobe: [Lobe; MAX_LOBES],
    weight: [Vec3; MAX_LOBES],
    /// Each lobe's albedo for the viewer's direction, unweighted (worked
    /// out by [`finish`](Self::finish) where there is more than one lobe).
    albedo: [Vec3; MAX_LOBES],
    /// The chance of picking each lobe, summed up to it.
    cdf: [f32; MAX_LOBES],
    len: usize,
    /// Nodes visited by the flattening so far.
    visits: usize,
    /// The radiance the surface emits towards the viewer.
    pub emission: Vec3,
    /// What passes straight through the surface (cut-outs, `transparent{}`).
    pub transparency: Vec3,
    /// Which kinds of scattering the lobes have.
    pub flags: Flags,
    /// The frame: `+z` the shading normal on the viewer's side, `+x` the
    /// tangent anisotropic lobes stretch along.
    pub frame: Frame,
    /// The direction to the viewer in `frame`.
    pub wo: Vec3,
}

impl Default for Lobes {
    fn default() -> Lobes {
        let none = Lobe::Diffuse(Diffuse::new(Vec3::ZERO, 0.0));
        Lobes {
            lobe: [none; MAX_LOBES],
            weight: [Vec3::ZERO; MAX_LOBES],
            albedo: [Vec3::ZERO; MAX_LOBES],
            cdf: [0.0; MAX_LOBES],
            len: 0,
            visits: 0,
            emission: Vec3::ZERO,
            transparency: Vec3::ZERO,
            flags: Flags::NONE,
            frame: Frame::AXES,
            wo: Vec3::Z,
        }
    }
}

/// Where a closure is flattened: the frame of the facing shading normal,
/// the direction to the viewer in it, and which side the viewer is on.
#[derive(Clone, Copy, Debug)]
pub struct At {
    /// `+z` the shading normal on the viewer's side.
    pub frame: Frame,
    /// The direction to the viewer in `frame` (`z` raised to a small
    /// positive value where a shading normal hides the viewer).
    pub wo: Vec3,
    /// Whether the viewer is on the outside of the surface (the side its
    /// geometric normal points to): a dielectric's index is then its own,
    /// else its inverse.
    pub outside: bool,
}

impl At {
    /// The shading point of world shading normal `ns` (on either side),
    /// geometric normal `ng`, tangent `t` (any length; zero for none) and
    /// incoming ray direction `d` (unit length).
    pub fn new(ns: Vec3, ng: Vec3, t: Vec3, d: Vec3) -> At {
        let outside = d.dot(ng) < 0.0;
        let n = if outside { ns } else { -ns };
        let frame = Frame::with_tangent(n, t);
        let mut wo = frame.to_local(-d);
        // A shading normal may turn away from the viewer: the lobes need
        // `wo.z > 0`, and a grazing view is what such a point shows.
        if wo.z < 1e-4 {
            wo.z = 1e-4;
            wo = wo.normalize();
        }
        At { frame, wo, outside }
    }
}

impl Lobes {
    /// Flattens `c` at `at`, or fails when it has more than [`MAX_LOBES`]
    /// lobes of non-zero weight.
    pub fn flatten(c: &Closure, at: &At) -> Result<Lobes, TooManyLobes> {
        let mut out = Lobes::default();
        out.flatten_into(c, at)?;
        Ok(out)
    }

    /// [`flatten`](Self::flatten) into `self`, whose arrays are written only
    /// as far as the lobes go (a shading point's lobes are flattened where
    /// the path keeps them, not built elsewhere and copied there).
    pub fn flatten_into(&mut self, c: &Closure, at: &At) -> Result<(), TooManyLobes> {
        self.start(at);
        if c.len > 0 {
            self.walk(c, c.root as usize, Vec3::ONE, at, false)?;
        }
        self.finish();
        Ok(())
    }

    /// The lobes `parts` (weight, lobe) side by side at `at`.
    pub fn of(parts: &[(Vec3, Lobe)], at: &At) -> Result<Lobes, TooManyLobes> {
        let mut out = Lobes::default();
        out.of_into(parts, at)?;
        Ok(out)
    }

    /// [`of`](Self::of) into `self` (see [`flatten_into`](Self::flatten_into)).
    pub fn of_into(&mut self, parts: &[(Vec3, Lobe)], at: &At) -> Result<(), TooManyLobes> {
        self.start(at);
        for &(w, lobe) in parts {
            self.push(w, lobe, false)?;
        }
        self.finish();
        Ok(())
    }

    /// Empties `self` for a flattening at `at`.
    fn start(&mut self, at: &At) {
        (self.len, self.visits, self.flags) = (0, 0, Flags::NONE);
        (self.emission, self.transparency) = (Vec3::ZERO, Vec3::ZERO);
        (self.frame, self.wo) = (at.frame, at.wo);
    }

    /// The same lobes seen from `at`: a later map bent the shading normal.
    /// The weights stay those of the first view.
    pub fn reframe(&mut self, at: &At) {
        (self.frame, self.wo) = (at.frame, at.wo);
    }

    /// Adds node `i` of `c` with weight `w`; `top`: inside a layer's top,
    /// where a dielectric reflects only (its transmission is the layer's
    /// business).
    fn walk(&mut self, c: &Closure, i: usize, w: Vec3, at: &At, top: bool) -> Result<(), TooManyLobes> {
        self.visits += 1;
        if self.visits > MAX_VISITS {
            return Err(TooManyLobes);
        }
        let node: &Node = &c.nodes[i];
        let col = |k: usize| Vec3::from_array(node.c[k]);
        let [x0, x1, x2] = node.x;
        match node.kind {
            NodeKind::Diffuse => self.push(w, Lobe::Diffuse(Diffuse::new(col(0), x0)), top),
            NodeKind::Conductor => self.push(w, Lobe::Conductor(Conductor::new(col(0), col(1), x0, x1)), top),
            NodeKind::Dielectric => {
                let eta = if node.thin || at.outside { x0 } else { 1.0 / x0 };
                let mut d = Dielectric::new(eta, x1, x2, col(0), col(1), node.thin);
                d.reflection_only = top;
                self.push(w, Lobe::Dielectric(d), top)
            }
            NodeKind::Sheen => self.push(w, Lobe::Sheen(Sheen::new(col(0), x0)), top),
            NodeKind::Emission => {
                self.emission += w * col(0);
                Ok(())
            }
            NodeKind::Transparent => {
                // A hole in a layer's top lets light on to the base, which
                // the layer's weights account for: not a hole in the surface.
                if !top {
                    self.transparency += w * col(0);
                }
                Ok(())
            }
            NodeKind::Add => {
                self.walk(c, node.a as usize, w, at, top)?;
                self.walk(c, node.b as usize, w, at, top)
            }
            NodeKind::Scale => self.walk(c, node.a as usize, w * col(0), at, top),
            NodeKind::Layer => self.layer(c, node, w, at, top),
        }
    }

    /// A layer of weight `w`: its top at weight one, to measure what it
    /// lets through, then scaled by `w`, and its base at `w` times that.
    fn layer(&mut self, c: &Closure, node: &Node, w: Vec3, at: &At, top: bool) -> Result<(), TooManyLobes> {
        let (start, emission) = (self.len, self.emission);
        self.walk(c, node.a as usize, Vec3::ONE, at, true)?;
        let mut through = Vec3::ONE;
        for k in start..self.len {
            through -= self.weight[k] * (Vec3::ONE - self.lobe[k].transmittance(at.wo));
            self.weight[k] *= w;
        }
        self.emission = emission + (self.emission - emission) * w;
        self.walk(c, node.b as usize, w * through.max(Vec3::ZERO), at, top)
    }

    /// Appends a lobe of weight `w`, unless the weight is zero, or (outside
    /// a layer's top, where even a black lobe hides what is under it) the
    /// lobe's colours are black.
    fn push(&mut self, w: Vec3, lobe: Lobe, top: bool) -> Result<(), TooManyLobes> {
        if w.max_element() <= 0.0 || (!top && lobe.is_black()) {
            return Ok(());
        }
        if self.len == MAX_LOBES {
            return Err(TooManyLobes);
        }
        self.lobe[self.len] = lobe;
        self.weight[self.len] = w;
        self.len += 1;
        Ok(())
    }

    /// Works out the lobes' albedos and chances of being picked (by
    /// weighted albedo) and their flags. A lone lobe is always picked: its
    /// albedo is worked out only when asked for.
    fn finish(&mut self) {
        if self.len == 1 {
            self.cdf[0] = 1.0;
            self.flags = self.lobe[0].flags();
            return;
        }
        let mut total = 0.0;
        for k in 0..self.len {
            self.albedo[k] = self.lobe[k].albedo(self.wo);
            let a = (self.weight[k] * self.albedo[k]).dot(LUMINANCE).max(0.0);
            total += a;
            self.cdf[k] = total;
            self.flags = self.flags | self.lobe[k].flags();
        }
        if total > 0.0 {
            for k in 0..self.len {
                self.cdf[k] /= total;
            }
        } else {
            // No albedo anywhere (black lobes): pick evenly, so the density
            // stays a proper mixture.
            for k in 0..self.len {
                self.cdf[k] = (k + 1) as f32 / self.len as f32;
            }
        }
    }

    /// The number of lobes.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there is no lobe: the surface scatters nothing (it may still
    /// emit or let light through).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Lobe `k` and its weight.
    #[inline]
    pub fn lobe(&self, k: usize) -> (&Lobe, Vec3) {
        (&self.lobe[k], self.weight[k])
    }

    /// The chance of picking lobe `k`.
    #[inline]
    fn chance(&self, k: usize) -> f32 {
        self.cdf[k] - if k == 0 { 0.0 } else { self.cdf[k - 1] }
    }

    /// `f(wi, wo) |cos θi|` for a local `wi`, and the mixture's density.
    #[inline]
    pub fn eval(&self, wi: Vec3) -> (Vec3, f32) {
        let (mut f, mut pdf) = (Vec3::ZERO, 0.0);
        for k in 0..self.len {
            let (fk, pk) = self.lobe[k].eval(self.wo, wi);
            f += self.weight[k] * fk;
            pdf += self.chance(k) * pk;
        }
        (f, pdf)
    }

    /// A local direction: the lobe picked by `choice`, drawn from `u` (the
    /// part of `choice` past the pick chooses within the lobe), with the
    /// whole closure's value and density there.
    #[inline]
    pub fn sample(&self, choice: f32, u: (f32, f32)) -> Option<LobeSample> {
        if self.len == 0 {
            return None;
        }
        let k = self.cdf[..self.len].iter().position(|&c| choice < c).unwrap_or(self.len - 1);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let p = self.chance(k);
        let uc = if p > 0.0 { ((choice - lo) / p).clamp(0.0, 1.0 - f32::EPSILON) } else { 0.5 };
        let s = self.lobe[k].sample(self.wo, uc, u)?;
        if self.len == 1 {
            return (s.pdf > 0.0).then_some(LobeSample { f_cos: s.f_cos * self.weight[0], ..s });
        }
        let (f_cos, pdf) = self.eval(s.wi);
        (pdf > 0.0).then_some(LobeSample { wi: s.wi, f_cos, pdf })
    }

    /// The mixture's density of a local `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        self.eval(wi).1
    }

    /// `f(wi, wo) |cos θi|` of the lobes that are not smooth (see
    /// [`Lobe::mirror_split`]): what the recursive ray tracer takes from
    /// its light samples, the smooth lobes being traced as rays.
    pub fn eval_rough(&self, wi: Vec3) -> Vec3 {
        (0..self.len)
            .filter(|&k| !self.lobe[k].is_smooth())
            .map(|k| self.weight[k] * self.lobe[k].eval(self.wo, wi).0)
            .sum()
    }

    /// The smooth lobes as the recursive ray tracer traces them.
    pub fn mirror_split(&self) -> MirrorSplit {
        let mut split = MirrorSplit { eta: 1.0, ..MirrorSplit::default() };
        for k in 0..self.len {
            if let Some(s) = self.lobe[k].mirror_split(self.wo) {
                split.reflect += self.weight[k] * s.reflect;
                split.refract += self.weight[k] * s.refract;
                if s.refract != Vec3::ZERO {
                    (split.eta, split.thin) = (s.eta, s.thin);
                }
            }
        }
        split
    }
}
