//! Piecewise-constant distributions on `[0, 1)` and `[0, 1)²`, for drawing
//! environment-map directions in proportion to their luminance.
//!
//! The 1D distribution keeps a running sum (the CDF) of non-negative cell
//! values; a uniform number is inverted by binary search and placed linearly
//! inside its cell, so the density is exactly `f(cell) / ∫f`. The 2D one is
//! the marginal over rows times the conditional within the row (the model is
//! pbrt-v4's `PiecewiseConstant2D`). A function that is zero everywhere gets a
//! uniform distribution, so sampling is always defined.

use luster_core::math::Vec2;

/// A piecewise-constant density on `[0, 1)` with `n` equal cells.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// `cdf[i]` is the probability of cells `0..i`; `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// `∫f` over `[0, 1)` (before the uniform fallback).
    integral: f32,
}

/// The CDF of non-negative, finite cell values (at least one cell; `n + 1`
/// entries) and `∫f` over `[0, 1)`; uniform for a function that is zero
/// everywhere.
fn cdf_of(func: &[f32]) -> (Vec<f32>, f32) {
    let n = func.len().max(1);
    // Sums in f64: a 4k-wide row of HDR values loses precision in f32.
    let mut running = vec![0.0f64; n + 1];
    for i in 0..n {
        running[i + 1] = running[i] + f64::from(func.get(i).copied().unwrap_or(0.0).max(0.0)) / n as f64;
    }
    let total = running[n];
    let cdf = if total > 0.0 {
        running.iter().map(|c| (c / total) as f32).collect()
    } else {
        (0..=n).map(|i| i as f32 / n as f32).collect()
    };
    (cdf, total as f32)
}

/// Density at cell `i` of `cdf`: the CDF's own step, so sampling and pdf
/// agree after normalization.
#[inline]
fn cell_pdf(cdf: &[f32], i: usize) -> f32 {
    (cdf[i + 1] - cdf[i]) * (cdf.len() - 1) as f32
}

/// Draws `x` in `[0, 1)` from `cdf` for uniform `u`; returns `(x, pdf(x), cell)`.
#[inline]
fn sample_cdf(cdf: &[f32], u: f32) -> (f32, f32, usize) {
    let n = cdf.len() - 1;
    // The last cell whose cdf start is ≤ u, skipping empty cells.
    let i = cdf[1..n].partition_point(|&c| c <= u).min(n - 1);
    let (lo, hi) = (cdf[i], cdf[i + 1]);
    let t = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
    let x = ((i as f32 + t) / n as f32).min(1.0 - f32::EPSILON / 2.0);
    (x, cell_pdf(cdf, i), i)
}

/// Density of `cdf` at `x` in `[0, 1)`.
#[inline]
fn pdf_cdf(cdf: &[f32], x: f32) -> f32 {
    let n = cdf.len() - 1;
    cell_pdf(cdf, ((x * n as f32) as usize).min(n - 1))
}

impl Distribution1D {
    /// From non-negative, finite cell values (at least one cell).
    pub fn new(func: &[f32]) -> Distribution1D {
        let (cdf, integral) = cdf_of(func);
        Distribution1D { cdf, integral }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cdf.len() - 1
    }

    /// Whether there are no cells (never: at least one is made).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `∫f` over `[0, 1)`; zero for a function that is zero everywhere.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Draws `x` in `[0, 1)` for uniform `u`; returns `(x, pdf(x), cell)`.
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        sample_cdf(&self.cdf, u)
    }

    /// Density at `x` in `[0, 1)`.
    pub fn pdf(&self, x: f32) -> f32 {
        pdf_cdf(&self.cdf, x)
    }
}

/// A piecewise-constant density on `[0, 1)²` over a `width × height` grid,
/// rows along `v`.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    /// Every row's CDF (`width + 1` entries each), one after another: a
    /// draw finds its row's by arithmetic, not through a pointer of its own
    /// (one cache miss fewer on a large map).
    rows: Vec<f32>,
    width: usize,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// From row-major non-negative cell values.
    pub fn new(func: &[f32], width: usize, height: usize) -> Distribution2D {
        let (width, height) = (width.max(1), height.max(1));
        let mut rows = Vec::with_capacity(height * (width + 1));
        let mut integrals = Vec::with_capacity(height);
        for y in 0..height {
            let (cdf, integral) = cdf_of(func.get(y * width..(y + 1) * width).unwrap_or(&[]));
            rows.extend_from_slice(&cdf);
            integrals.push(integral);
        }
        Distribution2D { rows, width, marginal: Distribution1D::new(&integrals) }
    }

    /// The CDF of row `y`.
    #[inline]
    fn row(&self, y: usize) -> &[f32] {
        let len = self.width + 1;
        &self.rows[y * len..(y + 1) * len]
    }

    /// Draws `(u, v)` for uniform `(u0, u1)`; returns the point and its density.
    pub fn sample(&self, (u0, u1): (f32, f32)) -> (Vec2, f32) {
        let (v, pv, row) = self.marginal.sample(u1);
        let (u, pu, _) = sample_cdf(self.row(row), u0);
        (Vec2::new(u, v), pu * pv)
    }

    /// Density at `uv`.
    pub fn pdf(&self, uv: Vec2) -> f32 {
        let h = self.marginal.len();
        let row = ((uv.y * h as f32) as usize).min(h - 1);
        self.marginal.pdf(uv.y) * pdf_cdf(self.row(row), uv.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::light::test_rng::Rng;

    #[test]
    fn pdf_integrates_to_one_and_follows_the_function() {
        let f = [0.0, 1.0, 3.0, 0.0, 6.0];
        let d = Distribution1D::new(&f);
        assert!((d.integral() - 10.0 / 5.0).abs() < 1e-6);
        let integral: f32 = (0..5).map(|i| d.pdf((i as f32 + 0.5) / 5.0) / 5.0).sum();
        assert!((integral - 1.0).abs() < 1e-6, "{integral}");
        // Density ∝ f: cell 4 is six times cell 1; empty cells have none.
        assert!((d.pdf(0.9) / d.pdf(0.3) - 6.0).abs() < 1e-5);
        assert_eq!(d.pdf(0.1), 0.0);
        assert_eq!(d.pdf(0.7), 0.0);
    }

    #[test]
    fn samples_never_land_in_empty_cells() {
        let d = Distribution1D::new(&[0.0, 2.0, 0.0, 0.0, 1.0, 0.0]);
        let mut rng = Rng(7);
        for _ in 0..10_000 {
            let (x, pdf, i) = d.sample(rng.next());
            assert!(i == 1 || i == 4, "cell {i}");
            assert!((0.0..1.0).contains(&x) && pdf > 0.0);
        }
        for u in [0.0, 1.0 - f32::EPSILON] {
            let (_, _, i) = d.sample(u);
            assert!(i == 1 || i == 4, "cell {i} for u = {u}");
        }
    }

    #[test]
    fn zero_function_samples_uniformly() {
        let d = Distribution1D::new(&[0.0; 4]);
        assert_eq!(d.integral(), 0.0);
        assert!((d.pdf(0.3) - 1.0).abs() < 1e-6);
        let (x, pdf, _) = d.sample(0.6);
        assert!((x - 0.6).abs() < 1e-6 && (pdf - 1.0).abs() < 1e-6);
    }

    #[test]
    fn pdf_2d_integrates_to_one() {
        let (w, h) = (7, 5);
        let f: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32).collect();
        let d = Distribution2D::new(&f, w, h);
        // Midpoint rule on a finer grid than the cells: exact for a
        // piecewise-constant density.
        let n = 70;
        let mut sum = 0.0f64;
        for y in 0..n {
            for x in 0..n {
                let uv = Vec2::new((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
                sum += d.pdf(uv) as f64;
            }
        }
        let integral = sum / (n * n) as f64;
        assert!((integral - 1.0).abs() < 1e-5, "{integral}");
    }

    /// Pearson's chi-square over the cells: the sampled histogram against
    /// the pdf's prediction. 34 non-empty cells, so 33 degrees of freedom;
    /// the 99.9% point of χ²(33) is 63.9.
    #[test]
    fn sampling_2d_matches_pdf_chi_square() {
        let (w, h) = (8, 5);
        let f: Vec<f32> = (0..w * h).map(|i| if i % 7 == 3 { 0.0 } else { 1.0 + (i % 5) as f32 }).collect();
        let d = Distribution2D::new(&f, w, h);
        let n = 200_000;
        let mut counts = vec![0u32; w * h];
        let mut rng = Rng(42);
        for _ in 0..n {
            let (uv, pdf) = d.sample((rng.next(), rng.next()));
            assert!((pdf - d.pdf(uv)).abs() <= 1e-4 * pdf, "sample pdf {pdf} vs pdf() {}", d.pdf(uv));
            let (x, y) = ((uv.x * w as f32) as usize, (uv.y * h as f32) as usize);
            counts[y * w + x] += 1;
        }
        let mut chi2 = 0.0f64;
        let mut cells = 0;
        for y in 0..h {
            for x in 0..w {
                let centre = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                let expected = d.pdf(centre) as f64 / (w * h) as f64 * n as f64;
                let observed = counts[y * w + x] as f64;
                if expected == 0.0 {
                    assert_eq!(observed, 0.0, "a sample in an empty cell");
                    continue;
                }
                chi2 += (observed - expected).powi(2) / expected;
                cells += 1;
            }
        }
        assert_eq!(cells, 34);
        assert!(chi2 < 63.9, "chi-square {chi2} over {cells} cells");
    }
}
