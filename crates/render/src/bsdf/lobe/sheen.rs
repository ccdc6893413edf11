//! The sheen lobe: Estevez and Kulla's "Charlie" microfacet fuzz (2017),
//! `D(h) = (2 + 1/α) sin^(1/α) θh / 2π` with `α = r²`, shadowed by the
//! height-correlated Smith term of that distribution, whose `Λ` and the
//! lobe's albedo are tabulated numerically at first use.

use super::{ggx, LobeSample};
use crate::bsdf::sampling;
use luster_core::math::Vec3;
use rayon::prelude::*;
use std::f32::consts::{FRAC_1_PI, FRAC_2_PI};
use std::sync::OnceLock;

/// Table rows: roughness, spaced evenly in `ln r` from `√MIN_ALPHA` to 1,
/// since the lobe's shape changes fastest where it is thin.
const N_R: usize = 32;
/// Projected-area columns: `θ` evenly over 0–90°.
const N_THETA: usize = 32;
/// Albedo columns: `√μo` evenly over 0–1, denser at grazing where the
/// albedo changes fastest.
const N_MU: usize = 64;

/// A cloth-like retro- and grazing-reflective fuzz of colour `color`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sheen {
    color: Vec3,
    roughness: f32,
    /// `1/α`, the exponent of `sin θh`.
    inv_alpha: f32,
    /// The distribution's normalisation, `(2 + 1/α) / 2π`.
    d_norm: f32,
    /// The row coordinate in the tables, 0–1.
    row: f32,
    /// `1 / max(r, √MIN_ALPHA)`: the projected-area table holds `r P`.
    inv_r: f32,
}

impl Sheen {
    /// A lobe of colour `color` and `roughness` (clamped to 0–1; `α = r²`
    /// no narrower than [`ggx::MIN_ALPHA`]).
    pub fn new(color: Vec3, roughness: f32) -> Self {
        let r = if roughness.is_nan() { 1.0 } else { roughness.clamp(0.0, 1.0) };
        let rc = r.max(r_min());
        let inv_alpha = 1.0 / (rc * rc);
        Sheen {
            color,
            roughness: r,
            inv_alpha,
            d_norm: (2.0 + inv_alpha) * 0.5 * FRAC_1_PI,
            row: row_of(rc),
            inv_r: 1.0 / rc,
        }
    }

    /// The colour parameter.
    pub fn color(&self) -> Vec3 {
        self.color
    }

    /// The roughness, clamped to 0–1.
    pub fn roughness(&self) -> f32 {
        self.roughness
    }

    /// `f(wi, wo) cos θi` and the (uniform) density of `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        (self.color * self.f_cos(wo, wi), 0.5 * FRAC_1_PI)
    }

    /// A direction uniform over the hemisphere (`uc` unused): the lobe
    /// leans to grazing directions, which cosine sampling would starve.
    #[inline]
    pub fn sample(&self, wo: Vec3, _uc: f32, u: (f32, f32)) -> Option<LobeSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = sampling::power_cosine(0.0, u);
        if wi.z <= 0.0 {
            return None;
        }
        Some(LobeSample { wi, f_cos: self.color * self.f_cos(wo, wi), pdf: 0.5 * FRAC_1_PI })
    }

    /// The directional albedo, from the table (log-interpolated: it falls
    /// off roughly exponentially away from grazing).
    #[inline]
    pub fn albedo(&self, wo: Vec3) -> Vec3 {
        if wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let t = tables();
        let e = lerp2(&t.log_albedo, N_MU, wo.z.min(1.0).sqrt(), self.row).exp();
        self.color * e.min(1.0)
    }

    /// The white lobe's `f cos θi`, both cosines positive.
    #[inline]
    fn f_cos(&self, wo: Vec3, wi: Vec3) -> f32 {
        let t = tables();
        let p_o = projected_area(t, wo.z, self.row, self.inv_r);
        let p_i = projected_area(t, wi.z, self.row, self.inv_r);
        charlie_f_cos(wo, wi, self.inv_alpha, self.d_norm, p_o, p_i)
    }
}

/// `D G₂ / (4 μo)`, where the height-correlated Smith
/// `G₂ = 1 / (1 + Λo + Λi)` with `1 + Λ(μ) = P(μ) / μ` is written with the
/// projected areas `P` so it stays finite at grazing.
#[inline]
fn charlie_f_cos(wo: Vec3, wi: Vec3, inv_alpha: f32, d_norm: f32, p_o: f32, p_i: f32) -> f32 {
    let h = wo + wi;
    let len2 = h.length_squared();
    if len2 <= 0.0 {
        return 0.0;
    }
    // sin² θh without the cancellation of 1 − cos².
    let sin2 = ((h.x * h.x + h.y * h.y) / len2).min(1.0);
    let d = d_norm * sin2.powf(0.5 * inv_alpha);
    let (mo, mi) = (wo.z, wi.z);
    d * mi / (4.0 * (mi * p_o + mo * p_i - mi * mo))
}

fn r_min() -> f32 {
    ggx::MIN_ALPHA.sqrt()
}

/// The table row coordinate (0–1) of a roughness no less than [`r_min`].
fn row_of(r: f32) -> f32 {
    ((r / r_min()).ln() / (1.0 / r_min()).ln()).clamp(0.0, 1.0)
}

/// The numerically built tables, rows by roughness.
struct Tables {
    /// `r P(θ)`, `P(μ) = ∫ max(0, ω·m) D(m) dm` the projected area of the
    /// microfacets facing `ω`, so `1 + Λ = P / μ`; times `r` because `P`
    /// grows like `1/r` as the lobe narrows.
    projected: Vec<f32>,
    /// `ln E(μo)` of the white lobe.
    log_albedo: Vec<f32>,
}

fn tables() -> &'static Tables {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    TABLES.get_or_init(build_tables)
}

/// Bilinear interpolation in a row-major `N_R × n` table at column and row
/// coordinates `x`, `y` in 0–1.
#[inline]
fn lerp2(table: &[f32], n: usize, x: f32, y: f32) -> f32 {
    let fx = x.clamp(0.0, 1.0) * (n - 1) as f32;
    let ix = (fx as usize).min(n - 2);
    let tx = fx - ix as f32;
    let fy = y.clamp(0.0, 1.0) * (N_R - 1) as f32;
    let iy = (fy as usize).min(N_R - 2);
    let ty = fy - iy as f32;
    let at = |j: usize, i: usize| table[j * n + i];
    let lo = at(iy, ix) + tx * (at(iy, ix + 1) - at(iy, ix));
    let hi = at(iy + 1, ix) + tx * (at(iy + 1, ix + 1) - at(iy + 1, ix));
    lo + ty * (hi - lo)
}

/// `P(μ)` from the table, never below `μ` (its flat-surface value and the
/// bound `Λ ≥ 0`).
#[inline]
fn projected_area(t: &Tables, mu: f32, row: f32, inv_r: f32) -> f32 {
    let x = mu.clamp(0.0, 1.0).acos() * FRAC_2_PI;
    (lerp2(&t.projected, N_THETA, x, row) * inv_r).max(mu)
}

/// The roughness of table row `j`.
fn row_roughness(j: usize) -> f64 {
    let r_min = r_min() as f64;
    r_min * (1.0 / r_min).powf(j as f64 / (N_R - 1) as f64)
}

fn build_tables() -> Tables {
    let mut projected = vec![0f32; N_R * N_THETA];
    projected.par_chunks_mut(N_THETA).enumerate().for_each(|(j, row)| {
        let r = row_roughness(j);
        let d = distribution_samples(1.0 / (r * r));
        for (i, v) in row.iter_mut().enumerate() {
            let theta = i as f64 / (N_THETA - 1) as f64 * std::f64::consts::FRAC_PI_2;
            *v = (r * projected_area_quadrature(theta.cos(), &d)) as f32;
        }
    });
    let mut t = Tables { projected, log_albedo: vec![0f32; N_R * N_MU] };
    let mut log_albedo = vec![0f32; N_R * N_MU];
    log_albedo.par_chunks_mut(N_MU).enumerate().for_each(|(j, row)| {
        let r = row_roughness(j);
        let row_coord = j as f32 / (N_R - 1) as f32;
        for (i, v) in row.iter_mut().enumerate() {
            let x = i as f64 / (N_MU - 1) as f64;
            let e = albedo_quadrature(&t, x * x, r, row_coord);
            *v = e.max(1e-30).ln() as f32;
        }
    });
    t.log_albedo = log_albedo;
    t
}

/// Midpoint steps over `cos θm` for [`projected_area_quadrature`]: 512
/// resolve the narrowest distribution, about 0.05 wide in `cos θm`.
const N_COS_M: usize = 512;

/// `D` at the midpoints of [`N_COS_M`] steps over `cos θm`.
fn distribution_samples(inv_alpha: f64) -> Vec<f64> {
    let norm = (2.0 + inv_alpha) / (2.0 * std::f64::consts::PI);
    (0..N_COS_M)
        .map(|k| {
            let c = (k as f64 + 0.5) / N_COS_M as f64;
            norm * (1.0 - c * c).powf(0.5 * inv_alpha)
        })
        .collect()
}

/// `P(μ) = ∫ max(0, ω·m) D(m) dm` by midpoint quadrature over `cos θm`
/// (`d` from [`distribution_samples`]), the azimuth integrated in closed
/// form: `∫ max(0, a cos φ + b) dφ`.
fn projected_area_quadrature(mu: f64, d: &[f64]) -> f64 {
    use std::f64::consts::PI as PI64;
    let so = (1.0 - mu * mu).max(0.0).sqrt();
    let mut sum = 0.0;
    for (k, d) in d.iter().enumerate() {
        let c = (k as f64 + 0.5) / N_COS_M as f64;
        let (a, b) = (so * (1.0 - c * c).sqrt(), mu * c);
        let azimuth = if b >= a {
            2.0 * PI64 * b
        } else {
            let phi0 = (-b / a).acos();
            2.0 * (a * phi0.sin() + b * phi0)
        };
        sum += d * azimuth;
    }
    sum / N_COS_M as f64
}

/// The white lobe's albedo `∫ f cos θi dωi` at `μo`, by midpoint
/// quadrature in `√μi` (the lobe crowds grazing directions) and in the
/// azimuth over half the circle (the lobe is symmetric about `wo`'s plane).
/// Uses the tabulated `P`, as `eval` does, so the albedo is the model's.
fn albedo_quadrature(t: &Tables, mu_o: f64, r: f64, row: f32) -> f64 {
    const N_MU_I: usize = 32;
    const N_PHI: usize = 16;
    use std::f64::consts::PI as PI64;
    let inv_alpha = 1.0 / (r * r);
    let norm = (2.0 + inv_alpha) / (2.0 * PI64);
    let inv_r = (1.0 / r) as f32;
    let p_o = projected_area(t, mu_o as f32, row, inv_r) as f64;
    let so = (1.0 - mu_o * mu_o).max(0.0).sqrt();
    let mut sum = 0.0;
    for i in 0..N_MU_I {
        let s = (i as f64 + 0.5) / N_MU_I as f64;
        let mu_i = s * s;
        let si = (1.0 - mu_i * mu_i).sqrt();
        let p_i = projected_area(t, mu_i as f32, row, inv_r) as f64;
        let shadow = mu_i / (4.0 * (mu_i * p_o + mu_o * p_i - mu_i * mu_o));
        let mut d_sum = 0.0;
        for k in 0..N_PHI {
            let c = ((k as f64 + 0.5) / N_PHI as f64 * PI64).cos();
            let len2 = 2.0 + 2.0 * (mu_i * mu_o + si * so * c);
            let horizontal2 = (si * si + so * so + 2.0 * si * so * c).max(0.0);
            d_sum += (horizontal2 / len2).min(1.0).powf(0.5 * inv_alpha);
        }
        // dμi = 2s ds; the half-circle sum stands for the whole one.
        sum += shadow * norm * d_sum * (2.0 * PI64 / N_PHI as f64) * (2.0 * s / N_MU_I as f64);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::super::diffuse::tests::{chi_square_p, dir, mc_albedo};
    use super::super::tests::Pcg;
    use super::*;

    const COLOR: Vec3 = Vec3::new(0.9, 0.6, 0.3);

    #[test]
    fn tables_are_sound() {
        // Built in tens of milliseconds; the bound leaves room for a loaded machine.
        let t0 = std::time::Instant::now();
        let t = build_tables();
        assert!(t0.elapsed().as_secs_f64() < 1.0, "sheen tables took {:?}", t0.elapsed());
        assert!(t.projected.iter().chain(&t.log_albedo).all(|v| v.is_finite()));
        // Facing the normal every microfacet is seen: P(1) = ∫ cos θm D = 1.
        for j in 0..N_R {
            let p = t.projected[j * N_THETA] as f64 / row_roughness(j);
            assert!((p - 1.0).abs() < 2e-3, "row {j}: P(1) = {p}");
        }
    }

    #[test]
    fn sampler_follows_pdf() {
        let mut seed = 20;
        for r in [0.1, 0.5, 1.0] {
            let lobe = Sheen::new(COLOR, r);
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
    fn albedo_matches_monte_carlo() {
        // Within 2%, or 0.002 absolute where the albedo is tiny (a thin
        // lobe seen from above reflects almost nothing).
        let mut seed = 200;
        for r in [0.1, 0.3, 0.5, 0.75, 1.0] {
            let lobe = Sheen::new(COLOR, r);
            for mu_o in [0.1, 0.5, 1.0] {
                let wo = dir(mu_o, 1.0);
                seed += 1;
                let mc = mc_albedo(|uc, u| lobe.sample(wo, uc, u), 200_000, seed);
                let a = lobe.albedo(wo);
                let err = (a - mc).abs().max_element();
                assert!(
                    err <= 0.02 * mc.max_element() || err <= 2e-3,
                    "r={r} μo={mu_o}: albedo {a} vs Monte Carlo {mc}"
                );
            }
        }
    }

    #[test]
    fn white_albedo_at_most_one() {
        for j in 0..=40 {
            let lobe = Sheen::new(Vec3::ONE, j as f32 / 40.0);
            for i in 1..=100 {
                let e = lobe.albedo(dir(i as f32 / 100.0, 0.0)).x;
                assert!((0.0..=1.0).contains(&e));
            }
        }
    }

    #[test]
    fn reciprocal_and_eval_matches_sample() {
        let mut rng = Pcg(11);
        for r in [0.05, 0.3, 1.0] {
            let lobe = Sheen::new(COLOR, r);
            for _ in 0..500 {
                let wo = dir(rng.next().max(1e-3), rng.next() * 6.3);
                let wi = dir(rng.next().max(1e-3), rng.next() * 6.3);
                let f_io = lobe.eval(wo, wi).0 / wi.z;
                let f_oi = lobe.eval(wi, wo).0 / wo.z;
                assert!((f_io - f_oi).abs().max_element() <= 1e-4 * f_io.max_element().max(1e-3));
                let s = lobe.sample(wo, rng.next(), (rng.next(), rng.next())).unwrap();
                let (f_cos, pdf) = lobe.eval(wo, s.wi);
                assert_eq!((f_cos, pdf), (s.f_cos, s.pdf));
            }
        }
    }

    #[test]
    fn nothing_below_the_surface() {
        let lobe = Sheen::new(COLOR, 0.5);
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
