//! Turning linear radiance into 8-bit display values.
//!
//! Two paths:
//! - [`course_rgb8`]: the course's LDR images (hw1–hw4, and any `.png` camera
//!   without a `Tonemap`): each channel clamped to [0, 255] and truncated, no
//!   gamma. Byte for byte what the course's reference images hold.
//! - [`Tonemap::apply`]: hw5's pipeline (`Tonemap` under a camera), for HDR
//!   outputs and for scenes that ask for a display transform:
//!   1. luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B`;
//!   2. scaled luminance `L = key / Ȳ · Y`, with `Ȳ = exp(mean(ln(δ + Y)))`
//!      the log-average (Reinhard et al. 2002, eq. 1–2, δ = 1e-5);
//!   3. the operator's curve `Yo = f(L)` (below); with a burn-out percentage
//!      `p > 0`, `L_white` is the `(100 − p)`th percentile of `L`;
//!   4. colour: `C_o = Yo · (C / Y)^saturation`;
//!   5. clamp to [0, 1], gamma (`C^(1/g)`, or the sRGB curve of
//!      IEC 61966-2-1), times 255, truncated. hw5.txt says "round", but the
//!      course's PNGs truncate: the course's own `cube_point_hdr.exr`,
//!      tone-mapped, matches its `.png` truncated and not rounded (as with
//!      hw1's 8-bit images).
//!
//! The curves `f` (exact formulas and sources are in docs/hdr.md):
//! - `Photographic` (Reinhard et al. 2002, eq. 3 and 4): `L / (1 + L)`, or
//!   `L (1 + L / L_white²) / (1 + L)` with a burn-out percentage.
//! - `ACES`: Narkowicz's fit of the ACES reference rendering transform,
//!   `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)` clamped to [0, 1].
//! - `Filmic`: Hable's Uncharted 2 curve `H(2x) / H(11.2)` with
//!   `H(x) = (x (A x + C B) + D E) / (x (A x + B) + D F) − E / F`,
//!   `A = 0.15, B = 0.50, C = 0.10, D = 0.20, E = 0.02, F = 0.30`.
//!
//! For ACES and Filmic a burn-out percentage rescales `L` so that `L_white`
//! lands on the curve's white point (where `f` first reaches 1).
//!
//! Scene parameters (read by the camera parser): `TMO`, `TMOOptions`
//! (key value, burn-out percentage), `Saturation`, `Gamma`.

pub mod display;
mod quantize;
mod stats;

pub use display::Display;

use self::quantize::Quantizer;
use self::stats::{luminance_batch, nth_luminance, Stats};
use crate::math::Vec3;
use rayon::prelude::*;

pub use self::stats::luminance;
#[cfg(test)]
use self::{
    quantize::{to_byte, BINS, BIN_SHIFT, LOW_BITS},
    stats::ln,
};

/// The input at which the ACES fit reaches 1: the positive root of
/// `0.08 x² − 0.56 x − 0.14 = 0`.
const ACES_WHITE: f32 = 7.241_694;
/// Hable's linear white point, and the exposure bias of his curve.
const FILMIC_W: f32 = 11.2;
const FILMIC_BIAS: f32 = 2.0;

/// A tone-mapping curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Operator {
    /// Reinhard et al. 2002, global (the course's hw5 operator).
    Photographic,
    /// Narkowicz's ACES filmic fit.
    Aces,
    /// Hable's Uncharted 2 filmic curve.
    Filmic,
}

impl Operator {
    /// The name a scene uses (`TMO`), matched without regard to case.
    pub fn parse(name: &str) -> Option<Operator> {
        match name.trim().to_ascii_lowercase().as_str() {
            "photographic" | "reinhard" => Some(Operator::Photographic),
            "aces" => Some(Operator::Aces),
            "filmic" => Some(Operator::Filmic),
            _ => None,
        }
    }

    /// The lower-case name, used in output file names.
    pub fn name(self) -> &'static str {
        match self {
            Operator::Photographic => "photographic",
            Operator::Aces => "aces",
            Operator::Filmic => "filmic",
        }
    }

    /// The names accepted by [`Operator::parse`], for error messages.
    pub const NAMES: &'static str = "Photographic, ACES or Filmic";

    #[inline]
    fn curve(self, l: f32, l_white: Option<f32>) -> f32 {
        match self {
            Operator::Photographic => match l_white {
                Some(w) => l * (1.0 + l / (w * w)) / (1.0 + l),
                None => l / (1.0 + l),
            },
            Operator::Aces => aces_fit(l_white.map_or(l, |w| l * ACES_WHITE / w)),
            Operator::Filmic => hable_filmic(l_white.map_or(l, |w| l * (FILMIC_W / FILMIC_BIAS) / w)),
        }
    }
}

/// Narkowicz's ACES fit, clamped to [0, 1].
#[inline]
pub(super) fn aces_fit(x: f32) -> f32 {
    (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// Hable's curve with his exposure bias and white point, clamped to [0, 1].
#[inline]
pub(super) fn hable_filmic(x: f32) -> f32 {
    (hable(FILMIC_BIAS * x) / hable(FILMIC_W)).clamp(0.0, 1.0)
}

fn hable(x: f32) -> f32 {
    const A: f32 = 0.15;
    const B: f32 = 0.50;
    const C: f32 = 0.10;
    const D: f32 = 0.20;
    const E: f32 = 0.02;
    const F: f32 = 0.30;
    (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F
}

/// The gamma of the final encoding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Gamma {
    /// `C^(1/g)`.
    Power(f32),
    /// The sRGB transfer curve (IEC 61966-2-1), as `<Gamma>sRGB</Gamma>`.
    Srgb,
}

impl Gamma {
    #[inline]
    pub(super) fn encode(self, c: f32) -> f32 {
        match self {
            Gamma::Power(g) => c.powf(1.0 / g),
            Gamma::Srgb => crate::image::buffer::linear_to_srgb(c),
        }
    }
}

/// One tone mapping: a camera's `Tonemap` element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tonemap {
    /// The curve.
    pub operator: Operator,
    /// Key value `a`: the scaled luminance the log-average maps to.
    pub key: f32,
    /// Burn-out percentage (0: none).
    pub burn_percent: f32,
    /// Saturation exponent `s`.
    pub saturation: f32,
    /// The final encoding.
    pub gamma: Gamma,
}

impl Tonemap {
    /// hw5's example: photographic, key 0.18, no burn-out, saturation 1, gamma 2.2.
    pub const COURSE_DEFAULT: Tonemap = Tonemap {
        operator: Operator::Photographic,
        key: 0.18,
        burn_percent: 0.0,
        saturation: 1.0,
        gamma: Gamma::Power(2.2),
    };

    /// The display transform of luster's own scenes and OBJ renders: ACES
    /// with key 0.18, sRGB-encoded.
    pub const DISPLAY: Tonemap = Tonemap {
        operator: Operator::Aces,
        key: 0.18,
        burn_percent: 0.0,
        saturation: 1.0,
        gamma: Gamma::Srgb,
    };

    /// 8-bit RGB of `pixels` (linear radiance), row-major.
    pub fn apply(&self, pixels: &[Vec3]) -> Vec<u8> {
        let mut out = vec![0u8; 3 * pixels.len()];
        self.apply_into(pixels, &mut out);
        out
    }

    /// [`Tonemap::apply`] into `out` (`3 · pixels.len()` bytes). Two passes
    /// over the pixels, each on every core: the statistics (log-average and,
    /// for a burn-out, a luminance histogram and the luminances for the
    /// percentile's selection: see `stats`), then the mapping
    /// straight into the 8-bit buffer. The mapping recomputes luminance
    /// rather than reading it back: that is cheaper than keeping it for
    /// every image.
    pub fn apply_into(&self, pixels: &[Vec3], out: &mut [u8]) {
        assert_eq!(out.len(), 3 * pixels.len(), "the 8-bit buffer holds three bytes a pixel");
        if pixels.is_empty() {
            return;
        }
        let t = *self;
        let burn = t.burn_percent > 0.0;
        let (q, stats) = rayon::join(|| Quantizer::shared(t.gamma, false), || Stats::of(pixels, burn));
        let log_avg = (stats.log_sum / pixels.len() as f64).exp();
        let scale = (f64::from(t.key) / log_avg) as f32;
        let l_white = burn.then(|| {
            let n = pixels.len();
            let at = (((1.0 - f64::from(t.burn_percent) / 100.0) * n as f64) as usize).min(n - 1);
            // Multiplying by a positive scale keeps the order (rounding is
            // monotone), so the rank-`at` scaled luminance is the rank-`at`
            // luminance scaled: exactly what sorting `L` would give.
            (nth_luminance(&stats.lum, &stats.hist, at) * scale).max(f32::MIN_POSITIVE)
        });
        let sat = (t.saturation != 1.0).then_some(t.saturation);
        // The operator is matched once, outside the pixel loop, so each
        // curve is inlined into a loop of its own.
        match (t.operator, l_white) {
            (Operator::Photographic, None) => map_pass(pixels, out, scale, sat, &q, |l| l / (1.0 + l)),
            (Operator::Photographic, Some(w)) => {
                map_pass(pixels, out, scale, sat, &q, |l| l * (1.0 + l / (w * w)) / (1.0 + l))
            }
            (op, w) => map_pass(pixels, out, scale, sat, &q, |l| op.curve(l, w)),
        }
    }
}

/// Pixels handled together in the passes over the image: each step runs
/// over the whole batch in a plain loop of its own over one array per
/// channel, which the compiler turns into vector instructions. Each value
/// goes through exactly the arithmetic of the one-pixel formula, so the
/// codes are the same bit for bit. A multiple of the log-average's lanes.
pub(super) const BATCH: usize = 256;

/// Pixels per parallel task of the mapping pass.
const MAP_CHUNK: usize = 4096;

/// The mapping pass: `pixels` to 8-bit codes in `out`, with the luminance
/// scale, the saturation exponent (`None` for 1) and the operator's `curve`.
fn map_pass(
    pixels: &[Vec3],
    out: &mut [u8],
    scale: f32,
    sat: Option<f32>,
    q: &Quantizer,
    curve: impl Fn(f32) -> f32 + Sync,
) {
    let avx2 = vector::avx2();
    out.par_chunks_mut(3 * MAP_CHUNK).zip(pixels.par_chunks(MAP_CHUNK)).for_each(|(out, px)| {
        let mut s = Scratch::new();
        for (o, p) in out.chunks_mut(3 * BATCH).zip(px.chunks(BATCH)) {
            if avx2 {
                // SAFETY: `vector::avx2` found AVX2 on this processor.
                unsafe { map_batch_avx2(p, o, scale, sat, q, &curve, &mut s) }
            } else {
                map_batch(p, o, scale, sat, q, &curve, &mut s, false)
            }
        }
    });
}

/// The arrays a batch of the mapping works in, made once a task rather than
/// once a batch, so they are not zeroed for every few pixels. Every step
/// writes the first `n` values before it reads them.
struct Scratch {
    rgb: [[f32; BATCH]; 3],
    y: [f32; BATCH],
    yo: [f32; BATCH],
    inv: [f32; BATCH],
    bits: [[u32; BATCH]; 3],
}

impl Scratch {
    fn new() -> Scratch {
        Scratch {
            rgb: [[0.0; BATCH]; 3],
            y: [0.0; BATCH],
            yo: [0.0; BATCH],
            inv: [0.0; BATCH],
            bits: [[0; BATCH]; 3],
        }
    }
}

/// Up to [`BATCH`] pixels mapped into `out`: for each, with `Y` its
/// luminance, `max(C / Y, 0)^s · curve(Y · scale)`, quantized; black where
/// `Y` is 0. `avx2`: compiled for AVX2 (the quantizer gathers).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn map_batch(
    px: &[Vec3],
    out: &mut [u8],
    scale: f32,
    sat: Option<f32>,
    q: &Quantizer,
    curve: &impl Fn(f32) -> f32,
    s: &mut Scratch,
    avx2: bool,
) {
    let n = px.len();
    let Scratch { rgb, y, yo, inv, bits } = s;
    split_batch(px, rgb);
    luminance_batch(rgb, &mut y[..n]);
    for ((yo, inv), &y) in yo[..n].iter_mut().zip(&mut inv[..n]).zip(&y[..n]) {
        *yo = curve(y * scale);
        *inv = 1.0 / y;
    }
    for ch in rgb.iter_mut() {
        for (c, &inv) in ch[..n].iter_mut().zip(&inv[..n]) {
            // Channel ratios, NaN (a zero channel over an infinite reciprocal) to 0.
            let r = *c * inv;
            *c = if r > 0.0 { r } else { 0.0 };
        }
    }
    if let Some(s) = sat {
        rgb.iter_mut().for_each(|ch| ch[..n].iter_mut().for_each(|r| *r = r.powf(s)));
    }
    for ch in rgb.iter_mut() {
        for ((c, &yo), &y) in ch[..n].iter_mut().zip(&yo[..n]).zip(&y[..n]) {
            *c = if y > 0.0 { *c * yo } else { 0.0 };
        }
    }
    q.codes_into(rgb, bits, &mut out[..3 * n], avx2);
}

/// The red, green and blue values of up to [`BATCH`] pixels, one array each.
#[inline(always)]
pub(super) fn split_batch(px: &[Vec3], rgb: &mut [[f32; BATCH]; 3]) {
    let [r, g, b] = rgb;
    for (((p, r), g), b) in px.iter().zip(r.iter_mut()).zip(g.iter_mut()).zip(b.iter_mut()) {
        (*r, *g, *b) = (p.x, p.y, p.z);
    }
}

/// Running the passes' batches with wider vector instructions where the
/// processor has them: each batch function has an `*_avx2` twin, the same
/// code compiled for AVX2. Only the instruction set differs, and without
/// fused multiply-adds (Rust never contracts `a * b + c`, and FMA is not
/// enabled) every operation rounds as in the portable build, so the results
/// are the same bits. The one difference in code is the quantizer's
/// table lookup, gathered in the twin: integer arithmetic, the same codes.
pub(super) mod vector {
    /// Tests set it to run the portable build on a processor with AVX2.
    #[cfg(test)]
    pub(in crate::tonemap) static PORTABLE_ONLY: std::sync::atomic::AtomicBool =
        std::sync::atomic::AtomicBool::new(false);

    /// Whether the `*_avx2` twins may run: the processor has AVX2.
    #[inline]
    pub(in crate::tonemap) fn avx2() -> bool {
        #[cfg(test)]
        if PORTABLE_ONLY.load(std::sync::atomic::Ordering::Relaxed) {
            return false;
        }
        #[cfg(target_arch = "x86_64")]
        return std::arch::is_x86_feature_detected!("avx2");
        #[cfg(not(target_arch = "x86_64"))]
        false
    }
}

/// [`map_batch`] compiled for AVX2.
///
/// # Safety
/// The processor must have AVX2 ([`vector::avx2`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn map_batch_avx2(
    px: &[Vec3],
    out: &mut [u8],
    scale: f32,
    sat: Option<f32>,
    q: &Quantizer,
    curve: &impl Fn(f32) -> f32,
    s: &mut Scratch,
) {
    map_batch(px, out, scale, sat, q, curve, s, true);
}

/// 8-bit RGB as the course's reference images are written: clamped to
/// [0, 255] and truncated. The hw2 text says "rounded", but the references
/// truncate: truncation matches them far more closely on every hw1/hw2
/// scene, where rounding leaves the mean level half a step too bright. On
/// rayon's pool, so that after the render no core waits on one thread.
pub fn course_rgb8(pixels: &[Vec3]) -> Vec<u8> {
    let mut out = vec![0u8; 3 * pixels.len()];
    out.par_chunks_mut(3 * MAP_CHUNK).zip(pixels.par_chunks(MAP_CHUNK)).for_each(|(out, px)| {
        for (o, p) in out.chunks_exact_mut(3).zip(px) {
            // `as` clamps to [0, 255], truncates, and makes NaN 0.
            o.copy_from_slice(&p.to_array().map(|c| c as u8));
        }
    });
    out
}

#[cfg(test)]
mod tests;
