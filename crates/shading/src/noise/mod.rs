//! Procedural noise: the building blocks of textures and Lua shaders.
//!
//! Every function is a pure, deterministic function of its `f32` arguments: no
//! allocation, no global mutable state (the tables are `static` arrays), safe
//! to call from any thread, and the same input gives the same bits on every
//! run. Non-finite input never panics or indexes out of bounds; the result is
//! then finite or NaN. Octave counts are capped at [`fractal::MAX_OCTAVES`] so
//! a hostile shader cannot make one call loop for long.
//!
//! # Which one to use
//!
//! | need | function | range (measured over 10⁵+ points) |
//! |---|---|---|
//! | smooth noise, the default | [`perlin::noise3`] | about [-1.04, 1.04] |
//! | a bump map or a normal from noise | [`perlin::noise3_grad`], [`simplex::noise3_grad`] | as the value |
//! | a tileable texture | [`perlin::pnoise3`] | as `noise3` |
//! | 1D/2D/4D (animated 3D: w = time) | [`perlin::noise1`], [`perlin::noise2`], [`perlin::noise4`] | [-1, 1] |
//! | fewer axis-aligned artefacts, cheaper in 4D | [`simplex::noise2`] … [`simplex::noise4`] | [-1, 1] |
//! | clouds, terrain (fBm) | [`fractal::fbm3`] | ±1.04·Σ\|gain\|ⁱ |
//! | marble, fire (\|noise\| sums) | [`fractal::turbulence3`] | [0, 1.04·Σ\|gain\|ⁱ] |
//! | mountain ridges | [`fractal::ridged3`] | [0, 1] for gain ≥ 0 |
//! | cells, stones, cracks (F2 − F1) | [`voronoi::voronoi3`], [`voronoi::voronoi2`] | see [`voronoi`] |
//! | the CENG795 `perlin` texture | [`course::noise`] | [-1, 1] (peak ±1.003) |
//!
//! `cargo bench --bench noise` times the common ones. Voronoi is the dearest,
//! and Manhattan Voronoi dearer still: its F2 passes the 3³ block more
//! often, so the 5³ shell is searched.

pub mod course;
pub mod fractal;
mod octaves;
pub mod perlin;
pub mod simplex;
pub mod voronoi;

/// Helpers shared by the noise tests: a tiny LCG (no `rand` needed) and the
/// checks every noise function has to pass.
#[cfg(test)]
pub(crate) mod testutil {
    /// Knuth's MMIX LCG; the high bits are good enough to scatter test points.
    pub struct Lcg(u64);

    impl Lcg {
        pub fn new(seed: u64) -> Self {
            Lcg(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }

        /// Uniform in [0, 1).
        pub fn next_f32(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }

        pub fn point4(&mut self, lo: f32, hi: f32) -> [f32; 4] {
            [(); 4].map(|_| lo + (hi - lo) * self.next_f32())
        }
    }

    /// Checks |f(p + δ) − f(p)| <= lipschitz·|δ| for small random steps δ: a
    /// jump (a lattice crease, a simplex kernel reaching past its simplex)
    /// breaks it, a smooth function with slopes below `lipschitz` does not.
    /// Steps are at most 1e-4 per axis, so with slope bounds up to 12 the
    /// allowed change stays near 2e-3 and a real jump (3D simplex noise with
    /// Gustavson's r² = 0.6 jumps by 1e-3 and more) is caught.
    #[track_caller]
    pub fn assert_lipschitz(f: impl Fn(f32, f32, f32) -> f32, lipschitz: f32) {
        let mut rng = Lcg::new(99);
        for _ in 0..100_000 {
            let p = rng.point4(-20.0, 20.0);
            let d = rng.point4(-1e-4, 1e-4);
            let q = [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
            // The step actually taken, after rounding to f32.
            let step = (0..3).map(|k| (q[k] - p[k]).abs()).fold(0.0, f32::max) * 3f32.sqrt();
            let change = (f(q[0], q[1], q[2]) - f(p[0], p[1], p[2])).abs();
            assert!(change <= lipschitz * step + 1e-6, "jump of {change} over a step of {step} at {p:?}");
        }
    }

    /// Compares an analytic gradient with central differences of its value.
    ///
    /// Error budget of a central difference with step h: truncation h²/6·|f'''|
    /// plus rounding about ε·|f|/h (ε = 6e-8). For h = 1e-3 and the noise in
    /// this module (|f'''| up to a few hundred per octave, |f| ~ 1) both stay
    /// below 1e-4, so a tolerance of a few 1e-3 only fails for a wrong term.
    #[track_caller]
    pub fn assert_grad_matches(f: impl Fn(f32, f32, f32) -> (f32, [f32; 3]), h: f32, tol: f32) {
        let mut rng = Lcg::new(42);
        for _ in 0..20_000 {
            let p = rng.point4(-20.0, 20.0);
            let (_, grad) = f(p[0], p[1], p[2]);
            for axis in 0..3 {
                let (mut lo, mut hi) = ([p[0], p[1], p[2]], [p[0], p[1], p[2]]);
                lo[axis] -= h;
                hi[axis] += h;
                let fd = (f(hi[0], hi[1], hi[2]).0 - f(lo[0], lo[1], lo[2]).0) / (hi[axis] - lo[axis]);
                assert!(
                    (fd - grad[axis]).abs() <= tol * (1.0 + grad[axis].abs()),
                    "axis {axis} at {p:?}: analytic {} vs finite difference {fd}",
                    grad[axis]
                );
            }
        }
    }
}
