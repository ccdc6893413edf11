//! Hypertexture surfaces: finding where a ray first crosses the threshold of
//! a volume's density, and the surface normal there.
//!
//! The ray is sampled at the volume's step from where it enters the bound
//! (or from its origin, inside); the first sample on the other side of the
//! threshold from the start brackets the crossing, which bisection then
//! narrows to 2⁻¹⁰ of a step. Outside its bound a volume's density is 0, so
//! where the density at the bound already exceeds the threshold the bound
//! itself is the surface, with the bound's normal: a constant density gives
//! exactly the bound's shape. Elsewhere the normal is the density's negative
//! gradient (central differences, a tenth of a step apart), falling back to
//! the bound's normal where the gradient vanishes.
//!
//! A feature thinner than a step can be stepped over; `StepSize` is the knob.

use super::{steps, Kind, Probe, Volume, Volumes};
use luster_core::math::{Ray, Vec3};
use luster_shading::shader::ShaderError;

/// Bisection steps after a crossing is bracketed.
const BISECTIONS: u32 = 10;

/// A ray's crossing of a hypertexture's surface.
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    /// Index into [`Volumes::surfaces`].
    pub index: usize,
    /// Ray parameter.
    pub t: f32,
    /// Unit outward normal (towards lower density), world space.
    pub normal: Vec3,
}

impl Volumes {
    /// The nearest hypertexture crossing along `ray` in `(t_min, t_max)`.
    /// A failing script fails the query, with the volume named.
    pub fn surface_hit(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        probe: &Probe,
    ) -> Result<Option<Crossing>, ShaderError> {
        let mut best: Option<Crossing> = None;
        for (index, v) in self.surfaces.iter().enumerate() {
            let limit = best.map_or(t_max, |b| b.t);
            if let Some((t, normal)) =
                v.crossing(self, ray, t_min, limit, probe).map_err(|e| e.with_object(&v.label))?
            {
                best = Some(Crossing { index, t, normal });
            }
        }
        Ok(best)
    }

    /// Whether some hypertexture surface crosses `ray` in `(t_min, t_max)`:
    /// the same answer as [`Volumes::surface_hit`] `.is_some()`, without
    /// narrowing the crossing down or computing its normal (16 density
    /// evaluations per blocked shadow ray).
    pub fn surface_blocks(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        probe: &Probe,
    ) -> Result<bool, ShaderError> {
        for v in &self.surfaces {
            if v.bracket(self, ray, t_min, t_max, probe).map_err(|e| e.with_object(&v.label))?.is_some() {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// What the march along a ray found.
enum Bracket {
    /// The crossing is on the bound, at this ray parameter.
    Bound(f32),
    /// The crossing lies in `(lo, hi]`; `inside` is the side the ray starts on.
    Between { lo: f32, hi: f32, inside: bool },
}

impl Volume {
    fn threshold(&self) -> f32 {
        match self.kind {
            Kind::Surface { threshold, .. } => threshold,
            Kind::Medium { .. } => f32::INFINITY,
        }
    }

    /// This surface's first crossing in `(t_min, t_max)`: `(t, normal)`.
    fn crossing(
        &self,
        v: &Volumes,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        probe: &Probe,
    ) -> Result<Option<(f32, Vec3)>, ShaderError> {
        let threshold = self.threshold();
        let dense =
            |t: f32| -> Result<bool, ShaderError> { Ok(self.density(v, ray.at(t), probe)? >= threshold) };
        Ok(match self.bracket(v, ray, t_min, t_max, probe)? {
            None => None,
            Some(Bracket::Bound(t)) => Some((t, self.bound.normal(ray.at(t)))),
            Some(Bracket::Between { mut lo, mut hi, inside }) => {
                for _ in 0..BISECTIONS {
                    let mid = 0.5 * (lo + hi);
                    if dense(mid)? == inside {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let t_hit = if inside { lo } else { hi };
                Some((t_hit, self.normal_at(v, ray.at(t_hit), probe)?))
            }
        })
    }

    /// Where the first crossing in `(t_min, t_max)` lies, as the march finds
    /// it, before any bisection: enough for a shadow ray, which needs only
    /// to know that there is one.
    fn bracket(
        &self,
        v: &Volumes,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        probe: &Probe,
    ) -> Result<Option<Bracket>, ShaderError> {
        let Some((t0, t1)) = self.bound.interval(ray) else { return Ok(None) };
        let threshold = self.threshold();
        let start = t0.max(t_min);
        let end = t1.min(t_max);
        if start >= end {
            return Ok(None);
        }
        let dense =
            |t: f32| -> Result<bool, ShaderError> { Ok(self.density(v, ray.at(t), probe)? >= threshold) };
        let from_outside = t0 >= t_min;
        let inside = dense(start)?;
        if from_outside && inside {
            // Entering the bound where it is already dense: the bound is the surface.
            return Ok(Some(Bracket::Bound(start)));
        }
        let n = steps(end - start, self.step);
        let dt = (end - start) / n as f32;
        let mut prev = start;
        for k in 1..=n {
            let t = if k == n { end } else { start + dt * k as f32 };
            if dense(t)? != inside {
                return Ok(Some(Bracket::Between { lo: prev, hi: t, inside }));
            }
            prev = t;
        }
        if inside && t1 <= t_max {
            // Dense up to where the ray leaves the bound: it leaves the surface there.
            return Ok(Some(Bracket::Bound(t1)));
        }
        Ok(None)
    }

    /// The outward normal at world point `p` on the surface.
    fn normal_at(&self, v: &Volumes, p: Vec3, probe: &Probe) -> Result<Vec3, ShaderError> {
        let h = self.step * 0.1;
        let d = |q: Vec3| self.density(v, q, probe);
        let g = Vec3::new(
            d(p + Vec3::X * h)? - d(p - Vec3::X * h)?,
            d(p + Vec3::Y * h)? - d(p - Vec3::Y * h)?,
            d(p + Vec3::Z * h)? - d(p - Vec3::Z * h)?,
        );
        Ok((-g).try_normalize().unwrap_or_else(|| self.bound.normal(p)))
    }
}
