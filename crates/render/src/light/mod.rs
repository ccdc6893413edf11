//! Lights: point, spot, directional, square area, mesh and sphere emitters
//! ([`emitter`]) and environment, a closed set matched in place on the hot
//! path.
//!
//! Every light answers one question for direct lighting: from a shading
//! point, which direction does light arrive from, how far away is its source
//! (for the shadow ray), and what is `E`, the factor the course's shading
//! multiplies the BRDF terms by (`kd cos + ks (n·h)^p`)? For the course's
//! lights `E` is:
//!
//! | light | `E` |
//! |---|---|
//! | point | `I / d²` |
//! | spot | `s I / d²`, `s` the fall-off below |
//! | directional | `Radiance` (no attenuation) |
//! | area | `L · A · |n_l · ω| / d²` for one uniform point of the square (hw3) |
//! | mesh emitter | `L · A · |n_l · ω| / d²` for one point drawn by area (hw7) |
//! | sphere emitter | `L / p(ω)` for one direction of the cone it subtends (hw7) |
//! | environment | `L(ω) / p(ω)` for one sampled direction (hw5 eq. 8) |
//!
//! Every sample also carries `p(ω)`, its density over solid angle (0 for the
//! lights no ray can hit: point, spot, directional), which multiple
//! importance sampling weighs against the BSDF's density.
//!
//! The spot light's fall-off (hw5 eqs. 3–4): with `α` the angle between the
//! spot's axis and the direction to the point, full intensity while
//! `α ≤ falloff/2`, none beyond `coverage/2`, and in between
//! `s = ((cos α − cos(coverage/2)) / (cos(falloff/2) − cos(coverage/2)))⁴`,
//! which falls smoothly from 1 at the fall-off edge to 0 at the coverage edge.
//! (The hw5 text's numerator, `cos α − cos(falloff/2)`, would be negative in
//! the band and make `s` grow towards the rim, jumping from 0 to 1 at the
//! coverage edge; the figure and the prose — "the intensity will diminish" —
//! ask for the continuous form used here.)

pub mod distribution;
pub mod emitter;
pub mod environment;
pub mod power;
mod shell;
pub mod tree;

pub use emitter::{LightMesh, LightSphere, ShadedLight, ShadedShape};
pub use environment::Environment;

use crate::render::sampler::PixelSampler;
use luster_core::math::{orthonormal_basis, Vec3};
use luster_scene::description::{AreaLightDesc, SpotLightDesc};
use std::sync::Arc;

/// A point light, intensity `I`, irradiance `I / d²`.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// RGB intensity.
    pub intensity: Vec3,
}

/// A spot light: a point light limited to a cone.
#[derive(Clone, Copy, Debug)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3,
    /// Unit axis of the cone.
    pub axis: Vec3,
    /// RGB intensity.
    pub intensity: Vec3,
    /// `cos(falloff / 2)`: full intensity at or above it.
    pub cos_falloff: f32,
    /// `cos(coverage / 2)`: nothing at or below it.
    pub cos_coverage: f32,
}

impl SpotLight {
    /// From the description (angles in degrees, full opening angles).
    pub fn from_desc(d: &SpotLightDesc) -> SpotLight {
        SpotLight {
            position: d.position,
            axis: d.direction,
            intensity: d.intensity,
            cos_falloff: (d.falloff_angle * 0.5).to_radians().cos(),
            cos_coverage: (d.coverage_angle * 0.5).to_radians().cos(),
        }
    }

    /// The fall-off factor `s` for a point in unit direction `to_point` from the light.
    #[inline]
    pub fn falloff(&self, to_point: Vec3) -> f32 {
        let c = self.axis.dot(to_point);
        if c >= self.cos_falloff {
            1.0
        } else if c <= self.cos_coverage {
            0.0
        } else {
            let t = (c - self.cos_coverage) / (self.cos_falloff - self.cos_coverage);
            (t * t) * (t * t)
        }
    }
}

/// A square area light of uniform radiance, emitting from both faces.
#[derive(Clone, Copy, Debug)]
pub struct AreaLight {
    /// Centre.
    pub center: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// The square's edge vectors (length `size`, perpendicular to the normal).
    pub edge_u: Vec3,
    /// See `edge_u`.
    pub edge_v: Vec3,
    /// Area.
    pub area: f32,
    /// RGB radiance.
    pub radiance: Vec3,
}

impl AreaLight {
    /// From the description.
    pub fn from_desc(d: &AreaLightDesc) -> AreaLight {
        let (u, v) = orthonormal_basis(d.normal);
        AreaLight {
            center: d.position,
            normal: d.normal,
            edge_u: u * d.size,
            edge_v: v * d.size,
            area: d.size * d.size,
            radiance: d.radiance,
        }
    }

    /// The point of the square at `(a, b)` in `[0, 1)²`.
    #[inline]
    pub fn point(&self, (a, b): (f32, f32)) -> Vec3 {
        self.center + self.edge_u * (a - 0.5) + self.edge_v * (b - 0.5)
    }
}

/// Any light.
#[derive(Clone, Debug)]
pub enum Light {
    /// A point light.
    Point(PointLight),
    /// A spot light.
    Spot(SpotLight),
    /// Parallel light travelling along the unit `direction`.
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3,
        /// RGB radiance.
        radiance: Vec3,
    },
    /// A square area light.
    Area(AreaLight),
    /// An emitting mesh (`LightMesh`).
    Mesh(Arc<LightMesh>),
    /// An emitting sphere (`LightSphere`).
    Sphere(LightSphere),
    /// The environment map.
    Environment(Arc<Environment>),
    /// An object whose shader emits. Only the path tracer samples it (it
    /// traces to the sample and asks the shader); [`Light::sample`] gives
    /// nothing, so the recursive ray tracer shows the emission unlit.
    Shaded(Arc<ShadedLight>),
}

/// Light arriving at a point from one light (or one sample of it).
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction towards the light.
    pub wi: Vec3,
    /// Distance to the light along `wi` from the shading point (infinite
    /// for directional and environment lights).
    pub dist: f32,
    /// The factor the BRDF terms are multiplied by (see the module doc).
    pub e: Vec3,
    /// Whether the source is a point in space (point and spot lights): the
    /// shadow ray then reaches a little past it (see the integrator).
    pub point_source: bool,
    /// Density of `wi` over solid angle; 0 for lights no ray can hit.
    pub pdf: f32,
}

impl Light {
    /// Light from this light at a surface point `p` (`n` the normal when
    /// there is a surface), for a ray at shutter `time` (a moving object
    /// light is sampled where it is then). The direction, distance and
    /// density are measured from `p` itself. Area and environment lights draw one 2D sample from
    /// `sampler`; the others draw none, so adding them changes no other
    /// light's samples. `None` when no light arrives. Always inlined: a
    /// sample returned through memory would be read back in wide loads
    /// before its narrow stores had landed, a stall in every caller.
    #[inline(always)]
    pub fn sample(
        &self,
        p: Vec3,
        n: Option<Vec3>,
        time: f32,
        sampler: &mut PixelSampler,
    ) -> Option<LightSample> {
        self.sample_by(p, || n, time, sampler)
    }

    /// [`sample`](Self::sample) at a surface point of normal `n`. The
    /// `Some(n)` that only the environment reads is made in its arm: made by
    /// the caller, it would be stored to memory before every light's match
    /// (the environment's sampler takes it by reference).
    #[inline(always)]
    pub fn sample_at(&self, p: Vec3, n: Vec3, time: f32, sampler: &mut PixelSampler) -> Option<LightSample> {
        self.sample_by(p, || Some(n), time, sampler)
    }

    /// [`sample`](Self::sample) with the normal given by `n`.
    #[inline(always)]
    fn sample_by(
        &self,
        p: Vec3,
        n: impl FnOnce() -> Option<Vec3>,
        time: f32,
        sampler: &mut PixelSampler,
    ) -> Option<LightSample> {
        match self {
            Light::Point(l) => {
                let to = l.position - p;
                let dist = to.length();
                let e = l.intensity / to.length_squared();
                Some(LightSample { wi: to / dist, dist, e, point_source: true, pdf: 0.0 })
            }
            Light::Spot(l) => {
                let to = l.position - p;
                let d2 = to.length_squared();
                let dist = d2.sqrt();
                let wi = to / dist;
                let s = l.falloff(-wi);
                if s <= 0.0 {
                    return None;
                }
                let e = l.intensity * (s / d2);
                Some(LightSample { wi, dist, e, point_source: true, pdf: 0.0 })
            }
            Light::Directional { direction, radiance } => {
                let (wi, dist) = (-*direction, f32::INFINITY);
                Some(LightSample { wi, dist, e: *radiance, point_source: false, pdf: 0.0 })
            }
            Light::Area(l) => {
                let q = l.point(sampler.next_2d());
                let to = q - p;
                let dist = to.length();
                let wi = to / dist;
                let cos_light = l.normal.dot(wi).abs();
                if cos_light == 0.0 {
                    return None;
                }
                let pdf = dist * dist / (l.area * cos_light);
                Some(LightSample { wi, dist, e: l.radiance / pdf, point_source: false, pdf })
            }
            Light::Mesh(l) => l.sample_from(p, l.point_seen(sampler.next_2d(), p, time), time),
            Light::Sphere(l) => {
                // Moving the point back is moving the sphere forward.
                let (wi, dist, pdf) = l.sample(p - l.motion * time, sampler.next_2d())?;
                Some(LightSample { wi, dist, e: l.radiance / pdf, point_source: false, pdf })
            }
            Light::Environment(env) => {
                let n = n();
                let (wi, e, pdf) = env.sample(n, sampler.next_2d())?;
                Some(LightSample { wi, dist: f32::INFINITY, e, point_source: false, pdf })
            }
            Light::Shaded(_) => None,
        }
    }

    /// Moves `sampler` past the draw [`sample`](Self::sample) would make,
    /// without making it (for a surface that reflects no direct light).
    #[inline]
    pub fn skip_sample(&self, sampler: &mut PixelSampler) {
        if self.draws() && !matches!(self, Light::Shaded(_)) {
            sampler.skip();
        }
    }

    /// Whether a sample of this light draws from the sampler: every light
    /// with an extent (an emissive shader's in the path tracer, which draws
    /// its point itself; [`sample`](Self::sample) draws for the others).
    #[inline]
    pub fn draws(&self) -> bool {
        matches!(
            self,
            Light::Area(_) | Light::Mesh(_) | Light::Sphere(_) | Light::Environment(_) | Light::Shaded(_)
        )
    }
}

impl LightMesh {
    /// [`Light::sample`] of this mesh from `p` at shutter `time`, for its
    /// point `q` of normal `nq`, drawn from `area` ([`LightMesh::point_seen`],
    /// at rest).
    #[inline(always)]
    pub fn sample_from(&self, p: Vec3, (q, nq, area): (Vec3, Vec3, f32), time: f32) -> Option<LightSample> {
        let q = q + self.motion * time;
        let to = q - p;
        let dist = to.length();
        let wi = to / dist;
        let pdf = LightMesh::pdf_drawn(p, q, nq, area);
        // `pdf <= 0 || !pdf.is_finite()` in one test (NaN fails both).
        if !(pdf > 0.0 && pdf < f32::INFINITY) {
            return None;
        }
        Some(LightSample { wi, dist, e: self.radiance / pdf, point_source: false, pdf })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(coverage: f32, falloff: f32) -> SpotLight {
        SpotLight::from_desc(&SpotLightDesc {
            position: Vec3::ZERO,
            direction: Vec3::new(0.0, -1.0, 0.0),
            intensity: Vec3::splat(100.0),
            coverage_angle: coverage,
            falloff_angle: falloff,
            loc: Default::default(),
        })
    }

    fn at_angle(deg: f32) -> Vec3 {
        let a = deg.to_radians();
        Vec3::new(a.sin(), -a.cos(), 0.0)
    }

    #[test]
    fn spot_falloff_is_one_inside_zero_outside_and_continuous() {
        let s = spot(30.0, 20.0);
        assert_eq!(s.falloff(at_angle(0.0)), 1.0);
        assert_eq!(s.falloff(at_angle(9.9)), 1.0);
        assert_eq!(s.falloff(at_angle(15.1)), 0.0);
        assert_eq!(s.falloff(at_angle(90.0)), 0.0);
        // Continuous at both edges, decreasing in between.
        assert!((s.falloff(at_angle(10.01)) - 1.0).abs() < 0.01);
        assert!(s.falloff(at_angle(14.99)) < 1e-4);
        let mut last = 1.0;
        for k in 1..50 {
            let f = s.falloff(at_angle(10.0 + 5.0 * k as f32 / 50.0));
            assert!(f <= last && f > 0.0, "not decreasing at step {k}");
            last = f;
        }
        // The quartic of the cosine ratio at the middle of the band.
        let (cf, cc) = (10f32.to_radians().cos(), 15f32.to_radians().cos());
        let t = (12.5f32.to_radians().cos() - cc) / (cf - cc);
        assert!((s.falloff(at_angle(12.5)) - t.powi(4)).abs() < 1e-5);
    }

    #[test]
    fn spot_with_equal_angles_has_a_hard_edge() {
        let s = spot(20.0, 20.0);
        assert_eq!(s.falloff(at_angle(9.9)), 1.0);
        assert_eq!(s.falloff(at_angle(10.1)), 0.0);
    }

    #[test]
    fn point_and_spot_attenuate_with_distance_directional_does_not() {
        let mut sampler = PixelSampler::new(1, 0, 0, 0, 1);
        let p = Vec3::new(0.0, -2.0, 0.0);
        let l = Light::Spot(spot(30.0, 20.0));
        let s = l.sample(p, None, 0.0, &mut sampler).expect("inside the cone");
        assert!((s.e - Vec3::splat(25.0)).abs().max_element() < 1e-4);
        assert!((s.wi - Vec3::Y).length() < 1e-6 && (s.dist - 2.0).abs() < 1e-6);
        let d = Light::Directional { direction: Vec3::new(0.0, -1.0, 0.0), radiance: Vec3::splat(7.0) };
        let s = d.sample(p * 100.0, None, 0.0, &mut sampler).expect("always lit");
        assert_eq!(s.e, Vec3::splat(7.0));
        assert_eq!(s.wi, Vec3::Y);
        assert!(s.dist.is_infinite());
    }
}

/// SplitMix64 uniforms shared by the light module's statistical tests.
#[cfg(test)]
pub(crate) mod test_rng {
    /// The generator's state.
    pub(crate) struct Rng(pub(crate) u64);
    impl Rng {
        /// The next uniform in [0, 1).
        pub(crate) fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
    }
}
