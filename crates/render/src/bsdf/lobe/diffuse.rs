//! The diffuse lobe: Lambert when smooth, and when rough the energy-preserving
//! Oren–Nayar model EON (Portsmouth, Kutz and Hill 2025; OpenPBR 1.1's
//! diffuse): Fujii's Oren–Nayar plus a multiple-scattering term.

use super::LobeSample;
use crate::bsdf::sampling;
use luster_core::math::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// Fujii's `1/2 − 2/(3π)`: the FON `A = 1 / (1 + C1 σ)`, and the albedo
/// shortfall `1 − E_FON(μ) = A σ (C1 − G(μ)/π)` vanishes at grazing.
const C1: f32 = 0.5 - 2.0 / (3.0 * PI);
/// `2/3 − 28/(15π)`: the cosine-weighted mean of `G/π`, so the average FON
/// albedo is `A (1 + C2 σ)`.
const C2: f32 = 2.0 / 3.0 - 28.0 / (15.0 * PI);

/// A diffuse reflector of colour `albedo`; `roughness` in 0–1 is EON's `σ`
/// (0: Lambert).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {
    albedo: Vec3,
    roughness: f32,
    /// FON's `A`, times `1/π`.
    a_over_pi: f32,
    /// The multiple-scattering albedo `ρ_ms`.
    rho_ms: Vec3,
    /// `f_ms / ((C1 − Go/π)(C1 − Gi/π))`: `ρ_ms A σ / (π (C1 − C2))`.
    ms_scale: Vec3,
}

impl Diffuse {
    /// A lobe of colour `albedo` (each channel in 0–1) and `roughness`
    /// (clamped to 0–1).
    pub fn new(albedo: Vec3, roughness: f32) -> Self {
        let r = if roughness.is_nan() { 0.0 } else { roughness.clamp(0.0, 1.0) };
        let a = 1.0 / (1.0 + C1 * r);
        // The average FON albedo and its shortfall, the latter in a form
        // that keeps its precision as r → 0.
        let e_avg = a * (1.0 + C2 * r);
        let one_minus_e_avg = a * r * (C1 - C2);
        let rho_ms = albedo * albedo * e_avg / (Vec3::ONE - albedo * one_minus_e_avg);
        let ms_scale = rho_ms * (a * r * FRAC_1_PI / (C1 - C2));
        Diffuse { albedo, roughness: r, a_over_pi: a * FRAC_1_PI, rho_ms, ms_scale }
    }

    /// The colour parameter.
    pub fn color(&self) -> Vec3 {
        self.albedo
    }

    /// The roughness, clamped to 0–1.
    pub fn roughness(&self) -> f32 {
        self.roughness
    }

    /// `f(wi, wo) cos θi` and the cosine-weighted density of `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        (self.f(wo, wi) * wi.z, wi.z * FRAC_1_PI)
    }

    /// A cosine-weighted direction (`uc` unused).
    #[inline]
    pub fn sample(&self, wo: Vec3, _uc: f32, u: (f32, f32)) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = sampling::cosine_weighted(u);
        if wi.z <= 0.0 {
            return None;
        }
        Some(LobeSample { wi, f_cos: self.f(wo, wi) * wi.z, pdf: wi.z * FRAC_1_PI })
    }

    /// The directional albedo: the colour for Lambert; for EON
    /// `ρ E_FON(μo) + ρ_ms (1 − E_FON(μo))`, exact for the model.
    #[inline]
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        if wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        if self.roughness == 0.0 {
            return self.albedo;
        }
        let shortfall = self.roughness * (C1 - g_over_pi(wo.z)) * (self.a_over_pi * PI);
        self.albedo * (1.0 - shortfall) + self.rho_ms * shortfall
    }

    /// The BRDF, both cosines positive.
    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if self.roughness == 0.0 {
            return self.albedo * FRAC_1_PI;
        }
        let r = self.roughness;
        // Fujii's s/t: t = max(μi, μo) where s > 0, else 1.
        let s = wo.dot(wi) - wo.z * wi.z;
        let s_over_t = if s > 0.0 { s / wo.z.max(wi.z) } else { s };
        let single = self.albedo * (self.a_over_pi * (1.0 + r * s_over_t));
        let multi = self.ms_scale * ((C1 - g_over_pi(wo.z)) * (C1 - g_over_pi(wi.z)));
        single + multi
    }
}

/// `G(μ)/π` of FON's albedo `E_FON(μ) = A (1 + σ G(μ)/π)`:
/// `G = sinθ (θ − sinθ cosθ) + ⅔ (tanθ (1 − sin³θ) − sinθ)`, with
/// `tanθ (1 − sin³θ)` rewritten to avoid cancellation near μ = 0.
#[inline]
fn g_over_pi(mu: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    let tan_term = s * mu * (1.0 + s + s * s) / (1.0 + s);
    let g = s * (mu.acos() - s * mu) + (2.0 / 3.0) * (tan_term - s);
    (g * FRAC_1_PI).min(C1)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    use super::super::tests::{chi_square, gamma_q, Pcg};

    pub(in crate::bsdf::lobe) fn dir(mu: f32, phi: f32) -> Vec3 {
        let s = (1.0 - mu * mu).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), mu)
    }

    /// The p-value of the shared chi-square test ([`chi_square`]) of
    /// `sample`'s directions, drawn from a generator seeded with `seed`,
    /// against `pdf`.
    pub(in crate::bsdf::lobe) fn chi_square_p(
        sample: impl Fn(f32, (f32, f32)) -> Option<Vec3>,
        pdf: impl Fn(Vec3) -> f32,
        seed: u64,
    ) -> f64 {
        let mut rng = Pcg(seed);
        chi_square(
            || {
                let uc = rng.next();
                let u = (rng.next(), rng.next());
                sample(uc, u)
            },
            pdf,
        )
    }

    /// The mean of `f cos / pdf` over `n` draws from `sample`: a Monte-Carlo
    /// estimate of the directional albedo.
    pub(in crate::bsdf::lobe) fn mc_albedo(
        sample: impl Fn(f32, (f32, f32)) -> Option<LobeSample>,
        n: usize,
        seed: u64,
    ) -> Vec3 {
        let mut rng = Pcg(seed);
        let mut sum = [0f64; 3];
        for _ in 0..n {
            let uc = rng.next();
            if let Some(s) = sample(uc, (rng.next(), rng.next())) {
                for (acc, v) in sum.iter_mut().zip((s.f_cos / s.pdf).to_array()) {
                    *acc += v as f64;
                }
            }
        }
        Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32) / n as f32
    }

    const COLOR: Vec3 = Vec3::new(0.8, 0.45, 0.1);

    #[test]
    fn chi_square_checks_itself() {
        // The p-value of a known statistic, and a wrong pdf rejected.
        assert!((gamma_q(5.0, 5.0) - 0.440_493_285_065).abs() < 1e-9);
        assert!((gamma_q(0.5, 2.0) - 0.045_500_263_896).abs() < 1e-9);
        let uniform = |_: f32, u: (f32, f32)| Some(sampling::power_cosine(0.0, u));
        let p = chi_square_p(uniform, |w| w.z.max(0.0) * FRAC_1_PI, 3);
        assert!(p < 1e-6, "uniform draws passed as cosine-weighted: p = {p}");
    }

    #[test]
    fn sampler_follows_pdf() {
        let mut seed = 10;
        for r in [0.0, 0.5, 1.0] {
            let lobe = Diffuse::new(COLOR, r);
            for mu_o in [0.1, 0.6, 1.0] {
                let wo = dir(mu_o, 0.4);
                seed += 1;
                let p = chi_square_p(
                    |uc, u| lobe.sample(wo, uc, u).map(|s| s.wi),
                    |wi| lobe.eval(wo, wi).1,
                    seed,
                );
                assert!(p >= 0.01, "r={r} μo={mu_o}: chi-square p = {p}");
            }
        }
    }

    #[test]
    fn lambert_is_albedo_over_pi() {
        let lobe = Diffuse::new(COLOR, 0.0);
        let mut rng = Pcg(5);
        for _ in 0..1000 {
            let wo = dir(rng.next().max(1e-3), rng.next() * 6.3);
            let wi = dir(rng.next().max(1e-3), rng.next() * 6.3);
            let (f_cos, pdf) = lobe.eval(wo, wi);
            assert_eq!(f_cos, COLOR * FRAC_1_PI * wi.z);
            assert_eq!(pdf, wi.z * FRAC_1_PI);
            assert_eq!(lobe.albedo(wo), COLOR);
        }
    }

    #[test]
    fn fon_albedo_matches_quadrature() {
        // E_FON(μ) of the closed form against midpoint quadrature of f_FON.
        for r in [0.3f64, 1.0] {
            let a = 1.0 / (1.0 + C1 as f64 * r);
            for mu_o in [0.05f64, 0.3, 0.7, 1.0] {
                let so = (1.0 - mu_o * mu_o).sqrt();
                let (n, np) = (400, 400);
                let mut sum = 0.0;
                for i in 0..n {
                    let mi = (i as f64 + 0.5) / n as f64;
                    let si = (1.0 - mi * mi).sqrt();
                    for j in 0..np {
                        let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                        let s = si * so * phi.cos();
                        let sot = if s > 0.0 { s / mi.max(mu_o) } else { s };
                        sum += a * (1.0 + r * sot) / std::f64::consts::PI * mi;
                    }
                }
                let quad = sum * std::f64::consts::TAU / (n * np) as f64;
                let closed = a * (1.0 + r * g_over_pi(mu_o as f32) as f64);
                assert!((quad - closed).abs() < 1e-4, "r={r} μo={mu_o}: {quad} vs {closed}");
            }
        }
    }

    #[test]
    fn white_eon_preserves_energy() {
        // Quadrature of f cos over the hemisphere, white, every roughness.
        let (n, np) = (256, 256);
        for r in [0.0, 0.1, 0.25, 0.5, 0.75, 1.0] {
            let lobe = Diffuse::new(Vec3::ONE, r);
            for mu_o in [0.05, 0.1, 0.3, 0.5, 0.8, 1.0] {
                let wo = dir(mu_o, 0.0);
                let mut sum = 0f64;
                for i in 0..n {
                    for j in 0..np {
                        let mi = (i as f32 + 0.5) / n as f32;
                        let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                        sum += lobe.eval(wo, dir(mi, phi)).0.x as f64;
                    }
                }
                let e = sum * std::f64::consts::TAU / (n * np) as f64;
                assert!((0.99..=1.01).contains(&e), "r={r} μo={mu_o}: furnace {e}");
                assert!((lobe.albedo(wo).x - 1.0).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn albedo_matches_monte_carlo() {
        let mut seed = 100;
        for r in [0.0, 0.2, 0.5, 1.0] {
            let lobe = Diffuse::new(COLOR, r);
            for mu_o in [0.1, 0.5, 1.0] {
                let wo = dir(mu_o, 1.0);
                seed += 1;
                let mc = mc_albedo(|uc, u| lobe.sample(wo, uc, u), 100_000, seed);
                let a = lobe.albedo(wo);
                let rel = ((a - mc) / mc).abs().max_element();
                assert!(rel < 0.02, "r={r} μo={mu_o}: albedo {a} vs Monte Carlo {mc}");
            }
        }
    }

    #[test]
    fn reciprocal_and_eval_matches_sample() {
        let mut rng = Pcg(9);
        for r in [0.0, 0.3, 1.0] {
            let lobe = Diffuse::new(COLOR, r);
            for _ in 0..500 {
                let wo = dir(rng.next().max(1e-3), rng.next() * 6.3);
                let wi = dir(rng.next().max(1e-3), rng.next() * 6.3);
                let f_io = lobe.eval(wo, wi).0 / wi.z;
                let f_oi = lobe.eval(wi, wo).0 / wo.z;
                assert!((f_io - f_oi).abs().max_element() <= 1e-5 * f_io.max_element().max(1.0));
                let s = lobe.sample(wo, rng.next(), (rng.next(), rng.next())).unwrap();
                let (f_cos, pdf) = lobe.eval(wo, s.wi);
                assert_eq!((f_cos, pdf), (s.f_cos, s.pdf));
            }
        }
    }

    #[test]
    fn nothing_below_the_surface() {
        let lobe = Diffuse::new(COLOR, 0.5);
        let up = dir(0.5, 0.2);
        let down = Vec3::new(up.x, up.y, -up.z);
        let flat = Vec3::new(1.0, 0.0, 0.0);
        for (wo, wi) in [(up, down), (down, up), (flat, up), (up, flat)] {
            assert_eq!(lobe.eval(wo, wi), (Vec3::ZERO, 0.0));
        }
        assert!(lobe.sample(down, 0.5, (0.3, 0.7)).is_none());
        assert_eq!(lobe.albedo(down), Vec3::ZERO);
    }
}
