//! A path's vertex inside a medium, where [`tracking::track`] found a real
//! scattering: light samples weighed by the Henyey–Greenstein phase
//! function (and, under MIS, against the chance that the phase function
//! would have drawn their direction), and the next direction drawn from the
//! phase function itself, whose weight `p / pdf` is exactly 1.
//!
//! [`tracking::track`]: crate::integrator::tracking::track

use super::next_event::{hittable, lights_to_sample, power_heuristic, shaded_sample};
use super::{past_limit, Bounce, Came, PathParams};
use crate::bsdf::frame::Frame;
use crate::integrator::media::{henyey_greenstein, shadow};
use crate::integrator::{is_black, shadow_reach, PathState};
use crate::light::Light;
use crate::render::scene::Scene;
use luster_core::math::{Ray, Vec3};
use std::f32::consts::PI;

/// The light that the lights send from `x` towards `-d` (`d` the direction
/// the path arrived along), scattered by a medium of asymmetry `g`: one
/// sample of each light (or of one chosen by the light tree), shadowed by surfaces
/// and attenuated by media.
pub(super) fn next_event_phase(
    scene: &Scene,
    x: Vec3,
    d: Vec3,
    g: f32,
    depth: u32,
    p: PathParams,
    st: &mut PathState,
) -> Vec3 {
    let mut color = Vec3::ZERO;
    let Some((lights, scale)) = lights_to_sample(scene, p, x, None, st) else { return Vec3::ZERO };
    let phase = |wi: Vec3| {
        let f = henyey_greenstein(wi.dot(d), g);
        Some((Vec3::splat(f), f))
    };
    for light in lights {
        if let Light::Shaded(l) = light {
            color += shaded_sample(scene, l, x, &phase, x, depth, scale, p, st);
            continue;
        }
        let Some(ls) = light.sample(x, None, st.time, &mut st.sampler) else { continue };
        if is_black(ls.e) {
            continue;
        }
        let tr = shadow(scene, &Ray::new(x, ls.wi), shadow_reach(&ls, scene.offset(x, x)), st);
        if is_black(tr) {
            continue;
        }
        let f = henyey_greenstein(ls.wi.dot(d), g);
        let w = if p.mis && hittable(light) { power_heuristic(ls.pdf / scale, f) * scale } else { scale };
        color += tr * ls.e * (f * w);
    }
    color
}

/// A direction drawn from the Henyey–Greenstein phase function of
/// asymmetry `g` about `d` (forward scattering keeps near `d`), and its
/// density.
pub fn sample_henyey_greenstein(d: Vec3, g: f32, (u1, u2): (f32, f32)) -> (Vec3, f32) {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u1
    } else {
        let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u1);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    let local = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
    let wi = Frame::new(d).to_world(local).normalize();
    (wi, henyey_greenstein(cos, g))
}

/// The bounce from a scattering at `x`: a direction drawn from the phase
/// function, with Russian roulette when asked for; `None` where the path
/// ends there.
#[allow(clippy::too_many_arguments)]
pub(super) fn scatter_bounce(
    scene: &Scene,
    x: Vec3,
    d: Vec3,
    g: f32,
    depth: u32,
    beta: Vec3,
    p: PathParams,
    st: &mut PathState,
) -> Option<Bounce> {
    let (wi, pdf) = sample_henyey_greenstein(d, g, st.sampler.next_2d());
    let mut q = 1.0;
    if p.russian_roulette {
        q = beta.max_element().min(1.0);
        if st.sampler.next_1d() >= q {
            return None;
        }
    }
    let ray = Ray::new(x, wi);
    if past_limit(scene, depth + 1, p) && !scene.may_find_emission(&ray) && !has_glow(scene) {
        return None;
    }
    if !st.spawn(beta.max_element()) {
        return None;
    }
    Some(Bounce { ray, weight: Vec3::ONE, q, next: beta, came: Came::Scatter { pdf } })
}

/// Whether a medium of the scene emits (then a ray past the depth limit
/// may still find light in it).
fn has_glow(scene: &Scene) -> bool {
    scene.volumes.media.iter().any(|v| v.glows())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampled directions follow the density the sampler reports: a
    /// chi-square test over bins of cos θ, for several asymmetries.
    #[test]
    fn henyey_greenstein_samples_follow_their_density() {
        let d = Vec3::new(0.3, -0.5, 0.8).normalize();
        for g in [-0.7f32, -0.2, 0.0, 0.4, 0.9] {
            const BINS: usize = 40;
            const N: usize = 200_000;
            let mut counts = [0u32; BINS];
            let mut state = 99u64 + (g * 1000.0) as i64 as u64;
            let mut rnd = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 40) as f32 / (1u64 << 24) as f32
            };
            for _ in 0..N {
                let (wi, pdf) = sample_henyey_greenstein(d, g, (rnd(), rnd()));
                assert!((wi.length() - 1.0).abs() < 1e-4);
                let c = wi.dot(d);
                assert!((pdf - henyey_greenstein(c, g)).abs() <= 1e-3 * pdf.max(1.0), "pdf {pdf} at cos {c}");
                let b = (((c + 1.0) * 0.5) * BINS as f32).min(BINS as f32 - 1.0) as usize;
                counts[b] += 1;
            }
            // Expected counts from the closed-form distribution of cos θ.
            let cdf = |c: f64| {
                let g = g as f64;
                if g.abs() < 1e-3 {
                    return (c + 1.0) / 2.0;
                }
                (1.0 - g * g) / (2.0 * g) * (1.0 / (1.0 + g * g - 2.0 * g * c).sqrt() - 1.0 / (1.0 + g))
            };
            let mut chi2 = 0.0f64;
            for (b, &count) in counts.iter().enumerate() {
                let (a, z) = (-1.0 + 2.0 * b as f64 / BINS as f64, -1.0 + 2.0 * (b + 1) as f64 / BINS as f64);
                let mass = cdf(z) - cdf(a);
                let want = mass * N as f64;
                chi2 += (count as f64 - want).powi(2) / want;
            }
            // 39 degrees of freedom: the 99.9% quantile is about 72.
            assert!(chi2 < 72.0, "g = {g}: chi-square {chi2}");
        }
    }
}
