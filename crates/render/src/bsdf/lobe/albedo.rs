//! Tables of single-scattering GGX directional albedos, built once on first
//! use, that the conductor and dielectric lobes divide by to return the
//! energy single scattering loses between microfacets (Turquin 2019), and
//! that their `albedo` estimates read.
//!
//! Every entry is a deterministic quadrature over the visible normals: for a
//! view `wo` the expectation of `f cos / pdf` under visible-normal sampling
//! is `G2(wo, wi) / G1(wo)` times the Fresnel weight, averaged over a
//! midpoint grid on the sampler's unit square. The integrand is continuous
//! (`G2` vanishes at the horizon), so the grid converges quickly.
//!
//! Axes: `sqrt μ` uniform in 0–1 (`μ = cos θo`; denser towards grazing,
//! where the albedos bend most); `sqrt α` uniform for the widths, up to
//! [`ALPHA_MAX`] (denser for narrow lobes, whose albedo is near 1 but
//! curves); the dielectric's relative index `η` logarithmically in
//! [`ETA_MIN`]–[`ETA_MAX`]. An anisotropic reflector's albedo depends on the
//! view's azimuth and both widths, so it has its own table over `μ`, the
//! azimuth from the wider axis, the wider width and the ratio of the
//! narrower to it. Lookups interpolate linearly and clamp to the axes.
//!
//! The anisotropic table is kept small to build quickly (12 × 12 quadrature
//! points, 5 azimuths, 5 ratios), so an anisotropic white conductor keeps
//! 0.97–1.04 of the light rather than the isotropic 0.995–1.002, and an
//! anisotropic dielectric's compensation, scaled from the isotropic table,
//! is rougher still (`tests.rs` measures both).

use super::dielectric::{fresnel_dielectric, refract};
use super::ggx::{Ggx, MIN_ALPHA};
use crate::bsdf::sampling::reflect_about;
use luster_core::math::Vec3;
use rayon::prelude::*;
use std::sync::OnceLock;

/// The widest isotropic `α` tabulated: an anisotropic lobe at roughness 1
/// is `sqrt 2` wide along its tangent.
pub const ALPHA_MAX: f32 = 1.5;
/// The smallest relative index the dielectric table covers.
pub const ETA_MIN: f32 = 0.2;
/// The largest relative index the dielectric table covers.
pub const ETA_MAX: f32 = 5.0;

/// Points along `μ` in the conductor table.
const C_MU: usize = 24;
/// Points along `α` in the conductor table.
const C_ALPHA: usize = 24;
/// Quadrature points per side of the sampler's square, conductor table.
const C_QUAD: usize = 24;
/// Points along `μ` in the dielectric table.
const D_MU: usize = 24;
/// Points along `α` in the dielectric table.
const D_ALPHA: usize = 16;
/// Points along `ln η` in the dielectric table (even, so no point sits at
/// `η = 1`, where refraction is the identity).
const D_ETA: usize = 24;
/// Quadrature points per side of the sampler's square, dielectric table.
const D_QUAD: usize = 12;
/// Points along `μ` in the anisotropic table.
const A_MU: usize = 20;
/// Points along the azimuth (0–90° from the wider axis).
const A_PHI: usize = 5;
/// Points along the wider width, 0–[`ALPHA_MAX`].
const A_ALPHA: usize = 12;
/// Points along the ratio of the narrower width to the wider, 0–1, uniform
/// in its square root.
const A_RATIO: usize = 5;
/// Quadrature points per side of the sampler's square, anisotropic table.
const A_QUAD: usize = 12;

/// Directional albedos of a GGX reflector, per `(μ, α)`.
pub struct ConductorTable {
    /// `E(μ, α)`: a white (`F = 1`) reflector's albedo.
    e: Vec<f32>,
    /// The same integral weighted by `(1 − wo·h)⁵`, Schlick's term.
    e5: Vec<f32>,
    /// Weighted by `wo·h (1 − wo·h)⁶`, the F82-tint correction's term.
    e6: Vec<f32>,
    /// `E_avg(α) = 2 ∫ E(μ, α) μ dμ`, the cosine-weighted mean.
    e_avg: Vec<f32>,
}

/// Albedos of a GGX dielectric boundary, per `(μ, α, η)`.
pub struct DielectricTable {
    /// Reflection plus transmission, counted as energy (no `1/η²`).
    total: Vec<f32>,
    /// Reflection alone.
    reflect: Vec<f32>,
    /// A thin sheet's reflection, with the slab's `R' = 2R / (1 + R)`.
    thin_reflect: Vec<f32>,
}

/// Albedos of a white GGX reflector of any anisotropy, per
/// `(μ, φ, α_wide, α_narrow / α_wide)`.
pub struct AnisotropicTable {
    e: Vec<f32>,
}

/// The grid's value along an axis of `n` points from `lo` to `hi`.
fn node(i: usize, n: usize, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * i as f32 / (n - 1) as f32
}

/// The `m`-th of `n` points along `μ`: uniform in `sqrt μ`.
fn mu_node(m: usize, n: usize) -> f32 {
    let x = node(m, n, 0.0, 1.0);
    x * x
}

/// The `a`-th of `n` points along a width axis: uniform in `sqrt α`.
fn alpha_node(a: usize, n: usize) -> f32 {
    let y = node(a, n, 0.0, ALPHA_MAX.sqrt());
    (y * y).max(MIN_ALPHA)
}

/// [`locate`] along a width axis of `n` points.
#[inline]
fn alpha_locate(alpha: f32, n: usize) -> (usize, f32) {
    locate(alpha.max(0.0).sqrt(), n, 0.0, ALPHA_MAX.sqrt())
}

/// [`locate`] along a `μ` axis of `n` points.
#[inline]
fn mu_locate(mu: f32, n: usize) -> (usize, f32) {
    locate(mu.max(0.0).sqrt(), n, 0.0, 1.0)
}

/// `wo` at `μ` (kept off the horizon) in the `xz` plane.
fn view(mu: f32) -> Vec3 {
    let mu = mu.max(1e-3);
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// The visible normals of `ggx` seen from `wo`, one per cell of a `q × q`
/// midpoint grid.
fn visible_normals(ggx: &Ggx, wo: Vec3, q: usize) -> impl Iterator<Item = Vec3> + '_ {
    (0..q * q).map(move |k| {
        let u = ((k / q) as f32 + 0.5) / q as f32;
        let v = ((k % q) as f32 + 0.5) / q as f32;
        ggx.sample_visible(wo, (u, v))
    })
}

/// Fractional position of `x` on an axis of `n` points over `lo`–`hi`:
/// the lower index and the weight of the upper one.
#[inline]
fn locate(x: f32, n: usize, lo: f32, hi: f32) -> (usize, f32) {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0) * (n - 1) as f32;
    let i = (t as usize).min(n - 2);
    (i, t - i as f32)
}

/// Bilinear interpolation in a table laid out `[alpha][mu]`.
#[inline]
fn bilinear(t: &[f32], n_mu: usize, (i, fi): (usize, f32), (j, fj): (usize, f32)) -> f32 {
    let at = |a: usize, m: usize| t[a * n_mu + m];
    let lo = at(j, i) + (at(j, i + 1) - at(j, i)) * fi;
    let hi = at(j + 1, i) + (at(j + 1, i + 1) - at(j + 1, i)) * fi;
    lo + (hi - lo) * fj
}

impl ConductorTable {
    /// Computes the table.
    pub(crate) fn build() -> ConductorTable {
        let cells = C_MU * C_ALPHA;
        let (mut e, mut e5, mut e6) = (vec![0.0; cells], vec![0.0; cells], vec![0.0; cells]);
        for a in 0..C_ALPHA {
            let alpha = alpha_node(a, C_ALPHA);
            let ggx = Ggx::new(alpha, alpha);
            for m in 0..C_MU {
                let wo = view(mu_node(m, C_MU));
                let inv_g1 = 1.0 / ggx.g1(wo);
                let mut sum = [0f64; 3];
                for h in visible_normals(&ggx, wo, C_QUAD) {
                    let wi = reflect_about(wo, h);
                    if wi.z <= 0.0 {
                        continue;
                    }
                    let w = f64::from(ggx.g2(wo, wi) * inv_g1);
                    let c = f64::from(wo.dot(h).clamp(0.0, 1.0));
                    let m5 = (1.0 - c).powi(5);
                    sum[0] += w;
                    sum[1] += w * m5;
                    sum[2] += w * c * m5 * (1.0 - c);
                }
                let n = (C_QUAD * C_QUAD) as f64;
                e[a * C_MU + m] = (sum[0] / n) as f32;
                e5[a * C_MU + m] = (sum[1] / n) as f32;
                e6[a * C_MU + m] = (sum[2] / n) as f32;
            }
        }
        // 2 ∫ E μ dμ = 4 ∫ E x³ dx with μ = x², by the trapezoid rule on the
        // table's own points.
        let e_avg = (0..C_ALPHA)
            .map(|a| {
                let f = |m: usize| f64::from(e[a * C_MU + m]) * f64::from(node(m, C_MU, 0.0, 1.0)).powi(3);
                let inner: f64 = (1..C_MU - 1).map(f).sum();
                (4.0 * (inner + 0.5 * (f(0) + f(C_MU - 1))) / (C_MU - 1) as f64) as f32
            })
            .collect();
        ConductorTable { e, e5, e6, e_avg }
    }

    #[inline]
    fn at(&self, t: &[f32], mu: f32, alpha: f32) -> f32 {
        bilinear(t, C_MU, mu_locate(mu, C_MU), alpha_locate(alpha, C_ALPHA))
    }

    /// `E(μ, α)`, the albedo of a white single-scattering GGX reflector.
    #[inline]
    pub fn e(&self, mu: f32, alpha: f32) -> f32 {
        self.at(&self.e, mu, alpha)
    }

    /// `E`, and the Schlick (`(1 − c)⁵`) and F82 (`c (1 − c)⁶`) weighted
    /// albedos: a Fresnel `F0 + (1 − F0)(1 − c)⁵ − b c (1 − c)⁶` reflects
    /// `F0 E + (1 − F0) E5 − b E6`.
    #[inline]
    pub fn moments(&self, mu: f32, alpha: f32) -> (f32, f32, f32) {
        (self.at(&self.e, mu, alpha), self.at(&self.e5, mu, alpha), self.at(&self.e6, mu, alpha))
    }

    /// `E_avg(α)`, the cosine-weighted mean of `E` over the views.
    #[inline]
    pub fn e_avg(&self, alpha: f32) -> f32 {
        let (j, f) = alpha_locate(alpha, C_ALPHA);
        self.e_avg[j] + (self.e_avg[j + 1] - self.e_avg[j]) * f
    }
}

impl DielectricTable {
    /// Computes the table.
    pub(crate) fn build() -> DielectricTable {
        let etas: Vec<f32> = (0..D_ETA).map(|k| node(k, D_ETA, ETA_MIN.ln(), ETA_MAX.ln()).exp()).collect();
        // One block of `η × μ × 3` sums per width, in parallel.
        let blocks: Vec<Vec<[f64; 3]>> = (0..D_ALPHA)
            .into_par_iter()
            .map(|a| {
                let alpha = alpha_node(a, D_ALPHA);
                let ggx = Ggx::new(alpha, alpha);
                let mut block = vec![[0f64; 3]; D_ETA * D_MU];
                for m in 0..D_MU {
                    let wo = view(mu_node(m, D_MU));
                    let inv_g1 = 1.0 / ggx.g1(wo);
                    // The visible normals and reflections do not depend on η.
                    for h in visible_normals(&ggx, wo, D_QUAD) {
                        let c = wo.dot(h);
                        let wr = reflect_about(wo, h);
                        let gr = if wr.z > 0.0 { ggx.g2(wo, wr) * inv_g1 } else { 0.0 };
                        for (k, &eta) in etas.iter().enumerate() {
                            let r = fresnel_dielectric(c, eta);
                            let gt = match refract(wo, h, eta) {
                                Some(wt) if wt.z < 0.0 => ggx.g2(wo, wt) * inv_g1,
                                _ => 0.0,
                            };
                            let sums = &mut block[k * D_MU + m];
                            sums[0] += f64::from(r * gr + (1.0 - r) * gt);
                            sums[1] += f64::from(r * gr);
                            sums[2] += f64::from(2.0 * r / (1.0 + r) * gr);
                        }
                    }
                }
                block
            })
            .collect();
        let n = (D_QUAD * D_QUAD) as f64;
        // Laid out `[η][α][μ]`.
        let column = |v: usize| {
            let mut out = vec![0f32; D_ETA * D_ALPHA * D_MU];
            for (a, block) in blocks.iter().enumerate() {
                for k in 0..D_ETA {
                    for m in 0..D_MU {
                        out[(k * D_ALPHA + a) * D_MU + m] = (block[k * D_MU + m][v] / n) as f32;
                    }
                }
            }
            out
        };
        DielectricTable { total: column(0), reflect: column(1), thin_reflect: column(2) }
    }

    /// The albedos of a white, non-absorbing GGX boundary of relative index
    /// `eta` seen at `μ`: (reflection plus transmission as energy,
    /// reflection alone, a thin sheet's reflection).
    #[inline]
    pub fn lookup(&self, mu: f32, alpha: f32, eta: f32) -> (f32, f32, f32) {
        let (i, fi) = mu_locate(mu, D_MU);
        let (j, fj) = alpha_locate(alpha, D_ALPHA);
        let (k, fk) = locate(eta.ln(), D_ETA, ETA_MIN.ln(), ETA_MAX.ln());
        let slice = D_MU * D_ALPHA;
        let at = |t: &[f32], k: usize| bilinear(&t[k * slice..(k + 1) * slice], D_MU, (i, fi), (j, fj));
        let lerp = |t: &[f32]| at(t, k) + (at(t, k + 1) - at(t, k)) * fk;
        (lerp(&self.total), lerp(&self.reflect), lerp(&self.thin_reflect))
    }
}

impl AnisotropicTable {
    /// Computes the table, a block of `μ × φ` per pair of widths in
    /// parallel (each cell is independent, so the result is deterministic).
    pub(crate) fn build() -> AnisotropicTable {
        let blocks: Vec<Vec<f32>> = (0..A_RATIO * A_ALPHA)
            .into_par_iter()
            .map(|k| {
                let wide = alpha_node(k % A_ALPHA, A_ALPHA);
                let ratio = node(k / A_ALPHA, A_RATIO, 0.0, 1.0);
                let ggx = Ggx::new(wide, wide * ratio * ratio);
                let mut block = Vec::with_capacity(A_PHI * A_MU);
                for p in 0..A_PHI {
                    let phi = node(p, A_PHI, 0.0, std::f32::consts::FRAC_PI_2);
                    for m in 0..A_MU {
                        let v = view(mu_node(m, A_MU));
                        let wo = Vec3::new(v.x * phi.cos(), v.x * phi.sin(), v.z);
                        let inv_g1 = 1.0 / ggx.g1(wo);
                        let sum: f64 = visible_normals(&ggx, wo, A_QUAD)
                            .map(|h| reflect_about(wo, h))
                            .filter(|wi| wi.z > 0.0)
                            .map(|wi| f64::from(ggx.g2(wo, wi) * inv_g1))
                            .sum();
                        block.push((sum / (A_QUAD * A_QUAD) as f64) as f32);
                    }
                }
                block
            })
            .collect();
        AnisotropicTable { e: blocks.concat() }
    }

    /// `E(wo)`, the albedo of a white single-scattering reflector `ggx`.
    #[inline]
    pub fn e(&self, ggx: &Ggx, wo: Vec3) -> f32 {
        // The azimuth from the wider axis, folded into the first quadrant.
        let (wide, narrow, along, across) = if ggx.ax >= ggx.ay {
            (ggx.ax, ggx.ay, wo.x.abs(), wo.y.abs())
        } else {
            (ggx.ay, ggx.ax, wo.y.abs(), wo.x.abs())
        };
        let phi = if along + across > 0.0 { across.atan2(along) } else { 0.0 };
        let (i, fi) = mu_locate(wo.z, A_MU);
        let (p, fp) = locate(phi, A_PHI, 0.0, std::f32::consts::FRAC_PI_2);
        let (j, fj) = alpha_locate(wide, A_ALPHA);
        let (k, fk) = locate((narrow / wide).sqrt(), A_RATIO, 0.0, 1.0);
        let at = |k: usize, j: usize, p: usize| {
            let row = &self.e[((k * A_ALPHA + j) * A_PHI + p) * A_MU..][..A_MU];
            row[i] + (row[i + 1] - row[i]) * fi
        };
        let in_phi = |k: usize, j: usize| at(k, j, p) + (at(k, j, p + 1) - at(k, j, p)) * fp;
        let in_alpha = |k: usize| in_phi(k, j) + (in_phi(k, j + 1) - in_phi(k, j)) * fj;
        in_alpha(k) + (in_alpha(k + 1) - in_alpha(k)) * fk
    }
}

/// `E(wo)` of a white single-scattering GGX reflector of any anisotropy:
/// from the isotropic table where the widths are equal, so that isotropic
/// lobes never build the anisotropic one.
#[inline]
pub fn reflector(ggx: &Ggx, wo: Vec3) -> f32 {
    if ggx.ax == ggx.ay {
        conductor().e(wo.z, ggx.ax)
    } else {
        anisotropic().e(ggx, wo)
    }
}

/// The energy albedos of a white, non-absorbing GGX boundary of relative
/// index `eta` seen from `wo`: (reflection plus transmission, reflection,
/// a thin sheet's reflection). Tabulated for isotropic widths; an
/// anisotropic boundary takes the isotropic one's at its RMS width, with
/// the energy lost scaled as a reflector's is by the anisotropy.
#[inline]
pub fn boundary(ggx: &Ggx, wo: Vec3, eta: f32) -> (f32, f32, f32) {
    let alpha = ggx.alpha_rms();
    let (total, reflect, thin) = dielectric().lookup(wo.z, alpha, eta);
    if ggx.ax == ggx.ay {
        return (total, reflect, thin);
    }
    let table = anisotropic();
    let iso_loss = 1.0 - table.e(&Ggx::new(alpha, alpha), wo);
    if iso_loss < 1e-3 {
        return (total, reflect, thin);
    }
    let loss = (1.0 - total) * (1.0 - table.e(ggx, wo)) / iso_loss;
    let scale = (1.0 - loss).max(1e-3) / total.max(1e-3);
    (total * scale, reflect * scale, thin * scale)
}

/// The anisotropic reflector table, built on first use.
pub fn anisotropic() -> &'static AnisotropicTable {
    static TABLE: OnceLock<AnisotropicTable> = OnceLock::new();
    TABLE.get_or_init(AnisotropicTable::build)
}

/// The conductor table, built on first use.
pub fn conductor() -> &'static ConductorTable {
    static TABLE: OnceLock<ConductorTable> = OnceLock::new();
    TABLE.get_or_init(ConductorTable::build)
}

/// The dielectric table, built on first use.
pub fn dielectric() -> &'static DielectricTable {
    static TABLE: OnceLock<DielectricTable> = OnceLock::new();
    TABLE.get_or_init(DielectricTable::build)
}
