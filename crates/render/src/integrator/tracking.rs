//! Null-scattering tracking through media, for the path tracer: where along
//! a ray light first really collides (delta tracking, with the spectral
//! tracking probabilities of Kutz et al. 2017 for RGB coefficients), and an
//! unbiased estimate of the transmittance along a shadow ray (ratio tracking;
//! Novák et al. 2014).
//!
//! Each medium is sampled against its [`Majorant`](crate::volume::Majorant): tentative collisions
//! arrive at the rate `σ̄` of the block the ray is in, and one at `x` is an
//! absorption, a scattering or a null collision with chances proportional
//! to the path-weighted `σa(x)`, `σs(x)` and `σn = σ̄ − σt(x)` (averaged over
//! the channels); the path's weight is multiplied by the coefficient over
//! `σ̄` times its chance, which keeps every channel unbiased. Where media
//! overlap, each has its own stream of tentative collisions and the nearest
//! is taken: the union of independent streams is the stream of the summed
//! majorants. Emission (`ε`, radiance per unit length) is gathered at every
//! tentative collision as `weight · ε / σ̄`, whose mean is `∫ T ε dt`.

use super::PathState;
use crate::render::scene::Scene;
use crate::volume::{majorant::Segments, Interior, Kind, Probe, Volume};
use luster_core::math::{Ray, Vec3};

/// Below this largest channel, a shadow ray's transmittance estimate plays
/// Russian roulette (survivors are divided by their chance), so that dense
/// media are not walked to the end for a negligible result.
const ROULETTE_BELOW: f32 = 0.1;

/// What [`track`] found along a ray.
#[derive(Clone, Copy, Debug)]
pub enum Event {
    /// No real collision before the end of the ray: what lies there arrives,
    /// times the weight.
    Pass,
    /// A real scattering at `t` in a medium of asymmetry `g`: the light
    /// scattered there arrives, times the weight.
    Scatter {
        /// Where along the ray.
        t: f32,
        /// The Henyey–Greenstein g there.
        g: f32,
    },
    /// Absorbed: only the emission gathered on the way arrives.
    Absorbed,
}

/// [`track`]'s answer: the event, the weight on what arrives from it, and
/// the emission gathered before it.
#[derive(Clone, Copy, Debug)]
pub struct Tracked {
    /// What ended the walk.
    pub event: Event,
    /// Multiplies the radiance from the event's point (or the ray's end).
    pub weight: Vec3,
    /// Radiance emitted by the media on the way, already weighted.
    pub emitted: Vec3,
}

/// Where a stream's coefficients come from.
#[derive(Clone, Copy)]
enum Source<'a> {
    /// A medium in a bound.
    Volume(&'a Volume),
    /// The homogeneous medium inside the object the ray is in.
    Interior(&'a Interior),
}

/// One medium's stream of tentative collisions along a ray.
struct Flight<'a> {
    source: Source<'a>,
    segments: Segments<'a>,
    /// The stretch the stream is in: start, end, majorant.
    at: Option<(f32, f32, f32)>,
    /// The last tentative collision (or where the stream begins).
    t: f32,
    /// The next tentative collision, once drawn.
    next: f32,
    /// The majorant there.
    rate: f32,
}

impl<'a> Flight<'a> {
    fn new(v: &'a Volume, ray: &Ray, t_lo: f32, t_hi: f32, emission: bool) -> Option<Flight<'a>> {
        let maj = v.majorant.as_ref()?;
        let (t0, t1) = v.bound.interval(ray)?;
        let (a, b) = (t0.max(t_lo), t1.min(t_hi));
        if a.partial_cmp(&b) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        let (o, d) = v.bound.to_local_ray(ray);
        let mut segments = maj.segments(o, d, a, b, emission);
        let at = segments.next_segment();
        Some(Flight { source: Source::Volume(v), segments, at, t: a, next: f32::INFINITY, rate: 0.0 })
    }

    /// The stream of a homogeneous interior from 0 to `t_hi`.
    fn inside(m: &'a Interior, t_hi: f32) -> Flight<'a> {
        let rate = (m.absorption + m.scattering).max_element();
        let mut segments = Segments::uniform(rate, 0.0, t_hi);
        let at = segments.next_segment();
        Flight { source: Source::Interior(m), segments, at, t: 0.0, next: f32::INFINITY, rate: 0.0 }
    }

    /// Draws the next tentative collision past `self.t` from the uniform
    /// `u`: `f32::INFINITY` once the stream leaves the medium.
    #[inline]
    fn advance(&mut self, u: f32) {
        // Optical depth (in majorant units) to the next collision.
        let mut tau = -(1.0 - u).ln();
        while let Some((s0, s1, rate)) = self.at {
            let t = self.t.max(s0);
            if rate > 0.0 {
                let dt = tau / rate;
                if t + dt < s1 {
                    self.t = t + dt;
                    self.next = self.t;
                    self.rate = rate;
                    return;
                }
                tau -= rate * (s1 - t);
            }
            self.t = s1;
            self.at = self.segments.next_segment();
        }
        self.next = f32::INFINITY;
    }
}

/// The coefficients of a stream's medium at world point `p`: `(σa, σs, ε, g)`.
#[inline]
fn source_coefficients(
    scene: &Scene,
    s: Source,
    p: Vec3,
    probe: &Probe,
    st: &mut PathState,
) -> Option<(Vec3, Vec3, Vec3, f32)> {
    match s {
        Source::Interior(m) => Some((m.absorption, m.scattering, m.emission, m.anisotropy)),
        Source::Volume(v) => {
            let g = match v.kind {
                Kind::Medium { anisotropy, .. } => anisotropy,
                Kind::Surface { .. } => 0.0,
            };
            coefficients(scene, v, p, probe, st).map(|(a, s, e)| (a, s, e, g))
        }
    }
}

/// The coefficients of medium `v` at world point `p`: `(σa, σs, ε)`.
#[inline]
fn coefficients(
    scene: &Scene,
    v: &Volume,
    p: Vec3,
    probe: &Probe,
    st: &mut PathState,
) -> Option<(Vec3, Vec3, Vec3)> {
    let Kind::Medium { absorption, scattering, .. } = v.kind else {
        return Some((Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
    };
    let vols = &scene.volumes;
    match v.density(vols, p, probe).and_then(|rho| Ok((rho, v.emission(vols, p, probe, rho)?))) {
        Ok((rho, e)) => Some((absorption * rho, scattering * rho, e)),
        Err(e) => {
            st.fail(e.with_object(&v.label));
            None
        }
    }
}

/// The mean of the three channels.
#[inline]
fn avg(v: Vec3) -> f32 {
    (v.x + v.y + v.z) * (1.0 / 3.0)
}

/// Delta tracking along `ray` from 0 to `t_max` (a surface, or infinity)
/// through every medium — those in bounds, and `interior` (an index into
/// the scene's interiors), the medium of the object the ray is inside — for
/// a path of throughput `beta`. Without `scatter` a scattering ends the
/// walk like an absorption (the path may not bounce again; emission still
/// counts).
pub fn track(
    scene: &Scene,
    ray: &Ray,
    t_max: f32,
    beta: Vec3,
    scatter: bool,
    interior: Option<u32>,
    st: &mut PathState,
) -> Tracked {
    let vols = &scene.volumes;
    let probe = Probe { time: st.time, dir: ray.d, view: st.view, pixel: st.pixel };
    let mut flights: Vec<Flight> = Vec::new();
    let mut one: Option<Flight> = None;
    let inside = interior.and_then(|i| vols.interiors.get(i as usize)).map(|m| Flight::inside(m, t_max));
    for mut f in
        inside.into_iter().chain(vols.media.iter().filter_map(|v| Flight::new(v, ray, 0.0, t_max, true)))
    {
        f.advance(st.sampler.next_1d());
        if one.is_none() && flights.is_empty() {
            one = Some(f);
        } else {
            flights.extend(one.take());
            flights.push(f);
        }
    }
    let mut weight = Vec3::ONE;
    let mut emitted = Vec3::ZERO;
    let pass = |weight, emitted| Tracked { event: Event::Pass, weight, emitted };
    loop {
        // The nearest tentative collision of any medium.
        let f = match &mut one {
            Some(f) => f,
            None => match flights.iter_mut().min_by(|a, b| a.next.total_cmp(&b.next)) {
                Some(f) => f,
                None => return pass(weight, emitted),
            },
        };
        if !f.next.is_finite() {
            return pass(weight, emitted);
        }
        let (t, rate) = (f.next, f.rate);
        let p = ray.at(t);
        let Some((sa, ss, e, g)) = source_coefficients(scene, f.source, p, &probe, st) else {
            return Tracked { event: Event::Absorbed, weight: Vec3::ZERO, emitted: Vec3::ZERO };
        };
        let inv = 1.0 / rate;
        emitted += weight * e * inv;
        let sn = (Vec3::splat(rate) - sa - ss).max(Vec3::ZERO);
        // The chances, weighted by the path's throughput per channel.
        let bw = beta * weight;
        let (pa, ps, pn) = if scatter {
            (avg(bw * sa), avg(bw * ss), avg(bw * sn))
        } else {
            (avg(bw * (sa + ss)), 0.0, avg(bw * sn))
        };
        let total = pa + ps + pn;
        if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Tracked { event: Event::Absorbed, weight: Vec3::ZERO, emitted };
        }
        let u = st.sampler.next_1d() * total;
        if u < pa {
            return Tracked { event: Event::Absorbed, weight: Vec3::ZERO, emitted };
        }
        if u < pa + ps {
            weight *= ss * (inv * total / ps);
            return Tracked { event: Event::Scatter { t, g }, weight, emitted };
        }
        weight *= sn * (inv * total / pn);
        let u = st.sampler.next_1d();
        f.advance(u);
    }
}

/// An unbiased estimate of the transmittance along `ray` from `t_lo` to
/// `t_hi` through the gridded medium `v` by ratio tracking, with Russian
/// roulette once it is small (a constant density has a closed form,
/// `integrator::media` takes it).
pub fn ratio_tracked(scene: &Scene, v: &Volume, ray: &Ray, t_lo: f32, t_hi: f32, st: &mut PathState) -> Vec3 {
    let Some(mut f) = Flight::new(v, ray, t_lo, t_hi, false) else { return Vec3::ONE };
    let probe = Probe { time: st.time, dir: ray.d, view: st.view, pixel: st.pixel };
    let mut tr = Vec3::ONE;
    loop {
        f.advance(st.sampler.next_1d());
        if !f.next.is_finite() {
            return tr;
        }
        let p = ray.at(f.next);
        let Some((sa, ss, _)) = coefficients(scene, v, p, &probe, st) else { return Vec3::ZERO };
        tr *= (Vec3::ONE - (sa + ss) / f.rate).max(Vec3::ZERO);
        let top = tr.max_element();
        if top < ROULETTE_BELOW {
            // Survive with a chance proportional to what is left.
            let q = (top / ROULETTE_BELOW).max(0.05);
            if st.sampler.next_1d() >= q {
                return Vec3::ZERO;
            }
            tr /= q;
        }
    }
}
