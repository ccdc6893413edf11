//! Clamping, gamma and quantization to 8 bits by table lookup, shared by
//! the tone mapping ([`super::tonemap`]) and the display transforms
//! ([`super::display`]). A [`Quantizer`] costs ten thousand `powf`s to build
//! and depends on the gamma alone, so [`Quantizer::shared`] builds each one
//! once a process.

use super::{Gamma, BATCH};
use std::sync::{Arc, Mutex};

/// Clamping, gamma and truncation to 8 bits as tables, instead of a `powf`
/// per channel: `edges[k - 1]` is the smallest linear value whose code is at
/// least `k` (`edges[255]` is infinite, a sentinel), and `start[i]` the code
/// at the lower end of bin `i`. The bins split each octave of (2⁻²⁴, 1) into
/// 1024 (the top bits of the `f32`), each 0.1% wide: narrower than the gap
/// between two codes' edges for any gamma above 0.3 (≥ 0.4% even for code
/// 254 to 255 at gamma 1), so a value steps past at most one edge and the
/// step is taken without a branch. The display transform's quantizer rounds
/// instead ([`Quantizer::rounding`]): the same tables, edges half a code lower.
///
/// When every bin holds at most one edge, [`Quantizer::packed`] folds both
/// tables into one word a bin, so a channel costs one load instead of two
/// dependent ones, and no branch (this lookup is the mapping pass's inner loop).
pub(super) struct Quantizer {
    pub(super) edges: [f32; 256],
    pub(super) start: Vec<u8>,
    /// The code of 1 and above.
    pub(super) white: u8,
    /// Whether no bin holds two edges (true for every gamma above about 0.3).
    pub(super) one_step: bool,
    /// Per bin, and one more for 1 and above: the code at the bin's lower
    /// end shifted left by 16, plus the mantissa bits (below the bin's) of
    /// the edge inside the bin, or [`NO_EDGE`] when there is none. Empty when
    /// some bin holds two edges or the first edge lies in or below bin 0.
    pub(super) packed: Vec<u32>,
}

/// The smallest value with a bin of its own, as bits (2⁻²⁴); values below it
/// start from code 0.
pub(super) const LOW_BITS: u32 = 0x3380_0000;
/// Mantissa bits below a bin: 2¹⁰ bins an octave.
pub(super) const BIN_SHIFT: u32 = 13;
/// Bins over [2⁻²⁴, 1).
pub(super) const BINS: usize = ((0x3F80_0000 - LOW_BITS) >> BIN_SHIFT) as usize;
/// The bits of a value inside its bin.
const IN_BIN: u32 = (1 << BIN_SHIFT) - 1;
/// A [`Quantizer::packed`] threshold no value inside a bin reaches.
const NO_EDGE: u32 = 1 << BIN_SHIFT;

impl Quantizer {
    /// The truncating quantizer of `gamma` ([`Quantizer::new`]), or the
    /// rounding one ([`Quantizer::rounding`]), built once a process rather
    /// than once an image.
    pub(super) fn shared(gamma: Gamma, rounding: bool) -> Arc<Quantizer> {
        /// Built quantizers; a process meets a handful of gammas, so a list
        /// searched in order, bounded in case one is fed many.
        static BUILT: Mutex<Vec<(Gamma, bool, Arc<Quantizer>)>> = Mutex::new(Vec::new());
        const KEPT: usize = 16;
        let find = |built: &[(Gamma, bool, Arc<Quantizer>)]| {
            built.iter().find(|(g, r, _)| *g == gamma && *r == rounding).map(|(_, _, q)| Arc::clone(q))
        };
        if let Some(q) = find(&BUILT.lock().unwrap_or_else(|p| p.into_inner())) {
            return q;
        }
        // Built outside the lock: two threads meeting a new gamma at once
        // both build it, and the tables they build are the same.
        let q = Arc::new(if rounding { Quantizer::rounding(gamma) } else { Quantizer::new(gamma) });
        let mut built = BUILT.lock().unwrap_or_else(|p| p.into_inner());
        if find(&built).is_none() {
            if built.len() == KEPT {
                built.remove(0);
            }
            built.push((gamma, rounding, Arc::clone(&q)));
        }
        q
    }

    pub(super) fn new(gamma: Gamma) -> Quantizer {
        Quantizer::with(gamma, to_byte)
    }

    /// Clamping, `gamma` and rounding to the nearest code.
    pub(super) fn rounding(gamma: Gamma) -> Quantizer {
        Quantizer::with(gamma, |v| if v.is_nan() { 0 } else { (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8 })
    }

    fn with(gamma: Gamma, to_byte: fn(f32) -> u8) -> Quantizer {
        let mut edges = [f32::INFINITY; 256];
        for (k, e) in edges[..255].iter_mut().enumerate() {
            // Bisect on the linear value, so the table agrees with
            // `to_byte(encode(clamp(c)))` up to the last bit of the bisection.
            let code = (k + 1) as u8;
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if to_byte(gamma.encode(mid)) >= code {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            *e = hi;
        }
        // The edges rise with the code, so one sweep finds every bin's code.
        let count = |k: &mut usize, v: f32| {
            while *k < 255 && edges[*k] <= v {
                *k += 1;
            }
            *k as u8
        };
        let mut k = 0usize;
        let start: Vec<u8> =
            (0..BINS).map(|i| count(&mut k, f32::from_bits(LOW_BITS + ((i as u32) << BIN_SHIFT)))).collect();
        let white = count(&mut k, 1.0);
        // One step is enough when no two edges share a bin (nor both lie
        // below the bins, where the count starts at 0).
        let bin = |v: f32| v.to_bits().saturating_sub(LOW_BITS) >> BIN_SHIFT;
        let one_step = edges[..255]
            .windows(2)
            .all(|e| e[1] >= 1.0 || (e[0] < e[1] && e[1].to_bits() >= LOW_BITS && bin(e[0]) != bin(e[1])));
        let packed = Quantizer::pack(&edges, &start, white);
        Quantizer { edges, start, white, one_step, packed }
    }

    /// The one-word-a-bin table (see [`Quantizer::packed`]), or an empty one
    /// when some bin holds two edges.
    fn pack(edges: &[f32; 256], start: &[u8], white: u8) -> Vec<u32> {
        let mut packed: Vec<u32> = start.iter().map(|&k| (u32::from(k) << 16) | NO_EDGE).collect();
        packed.push((u32::from(white) << 16) | NO_EDGE);
        for &e in edges.iter().take_while(|&&e| e < 1.0) {
            // An edge at or below 2⁻²⁴ would be passed by values that the
            // fast path lifts to 2⁻²⁴ (bin 0, offset 0).
            if e.to_bits() <= LOW_BITS {
                return Vec::new();
            }
            let bits = e.to_bits() - LOW_BITS;
            let slot = &mut packed[(bits >> BIN_SHIFT) as usize];
            if *slot & 0xFFFF != NO_EDGE {
                return Vec::new();
            }
            *slot = (*slot & !0xFFFF) | (bits & IN_BIN);
        }
        packed
    }

    /// The codes of `rgb`'s first `out.len() / 3` values per channel, into
    /// `out` as RGB triples: with the packed table, the clamp and bin
    /// arithmetic run over the batch at once and only the table loads go
    /// one value at a time.
    /// `bits` is scratch space, kept by the caller across batches.
    ///
    /// `avx2` (where the processor has it: [`super::vector`]) looks
    /// eight values up at once with a gather ([`Quantizer::codes_gathered`])
    /// instead of a scalar load and byte stores per value.
    #[inline(always)]
    pub(super) fn codes_into(
        &self,
        rgb: &[[f32; BATCH]; 3],
        bits: &mut [[u32; BATCH]; 3],
        out: &mut [u8],
        avx2: bool,
    ) {
        let n = out.len() / 3;
        #[cfg(target_arch = "x86_64")]
        if avx2 && self.packed.len() == BINS + 1 {
            // SAFETY: the caller found AVX2, and the table has a slot for
            // every bin and for 1.
            let done = unsafe { self.codes_gathered(rgb, out) };
            // The last few values of an image (fewer than 8) one at a time.
            for (k, o) in out.chunks_exact_mut(3).enumerate().skip(done) {
                o.copy_from_slice(&[self.code(rgb[0][k]), self.code(rgb[1][k]), self.code(rgb[2][k])]);
            }
            return;
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = avx2;
        self.codes_scalar(rgb, bits, out, n)
    }

    /// [`Quantizer::codes_into`] one table load at a time.
    #[inline(always)]
    fn codes_scalar(&self, rgb: &[[f32; BATCH]; 3], bits: &mut [[u32; BATCH]; 3], out: &mut [u8], n: usize) {
        if self.packed.is_empty() {
            for (k, o) in out.chunks_exact_mut(3).enumerate() {
                o.copy_from_slice(&[self.code(rgb[0][k]), self.code(rgb[1][k]), self.code(rgb[2][k])]);
            }
            return;
        }
        for (bits, c) in bits.iter_mut().zip(rgb) {
            for (b, &c) in bits[..n].iter_mut().zip(&c[..n]) {
                *b = c.max(f32::from_bits(LOW_BITS)).min(1.0).to_bits() - LOW_BITS;
            }
        }
        let code = |b: u32| {
            let e = self.packed[(b >> BIN_SHIFT) as usize];
            ((e >> 16) + u32::from((b & IN_BIN) >= (e & 0xFFFF))) as u8
        };
        for (k, o) in out.chunks_exact_mut(3).enumerate() {
            o.copy_from_slice(&[code(bits[0][k]), code(bits[1][k]), code(bits[2][k])]);
        }
    }

    /// The packed table's codes of the values of `rgb` eight at a time, as
    /// far as whole groups of eight fill `out`, with [`Quantizer::code`]'s
    /// arithmetic lane for lane: the clamp (`max` then `min`, NaN to the
    /// low end), the bin's word gathered, its code plus one where the value
    /// reaches the bin's edge. Returns the pixels done (a multiple of 8).
    ///
    /// # Safety
    /// The processor must have AVX2, and `packed` must hold `BINS + 1` words.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn codes_gathered(&self, rgb: &[[f32; BATCH]; 3], out: &mut [u8]) -> usize {
        use std::arch::x86_64::*;
        let n = (out.len() / 3).min(BATCH) / 8 * 8;
        let table = self.packed.as_ptr().cast::<i32>();
        let low = _mm256_set1_ps(f32::from_bits(LOW_BITS));
        let one = _mm256_set1_ps(1.0);
        let low_bits = _mm256_set1_epi32(LOW_BITS as i32);
        let in_bin = _mm256_set1_epi32(IN_BIN as i32);
        let edge_bits = _mm256_set1_epi32(0xFFFF);
        let byte = _mm256_set1_epi32(0xFF);
        // Each 128-bit half holds four pixels as `r | g << 8 | b << 16`;
        // their first three bytes, packed, then the two halves side by side.
        let pack = _mm256_setr_epi8(
            0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1, //
            0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1,
        );
        let halves = _mm256_setr_epi32(0, 1, 2, 4, 5, 6, 3, 7);
        for k in (0..n).step_by(8) {
            let code = |c: &[f32; BATCH]| {
                // `_mm256_max_ps` answers its second operand where either
                // is NaN: NaN becomes 2⁻²⁴, as `f32::max` makes it.
                let x = _mm256_min_ps(_mm256_max_ps(_mm256_loadu_ps(c.as_ptr().add(k)), low), one);
                let bits = _mm256_sub_epi32(_mm256_castps_si256(x), low_bits);
                let e = _mm256_i32gather_epi32::<4>(table, _mm256_srli_epi32::<{ BIN_SHIFT as i32 }>(bits));
                // Both sides are below 2¹⁶, so the signed comparison is the
                // unsigned one: -1 where the value is below the edge.
                let below =
                    _mm256_cmpgt_epi32(_mm256_and_si256(e, edge_bits), _mm256_and_si256(bits, in_bin));
                let k = _mm256_add_epi32(
                    _mm256_srli_epi32::<16>(e),
                    _mm256_add_epi32(below, _mm256_set1_epi32(1)),
                );
                _mm256_and_si256(k, byte)
            };
            let (r, g, b) = (code(&rgb[0]), code(&rgb[1]), code(&rgb[2]));
            let px =
                _mm256_or_si256(r, _mm256_or_si256(_mm256_slli_epi32::<8>(g), _mm256_slli_epi32::<16>(b)));
            let packed = _mm256_permutevar8x32_epi32(_mm256_shuffle_epi8(px, pack), halves);
            let at = out.as_mut_ptr().add(3 * k);
            // 24 bytes: pixels k..k + 8 of `out`, which holds at least n.
            _mm_storeu_si128(at.cast(), _mm256_castsi256_si128(packed));
            _mm_storel_epi64(at.add(16).cast(), _mm256_extracti128_si256::<1>(packed));
        }
        n
    }

    #[inline]
    pub(super) fn code(&self, c: f32) -> u8 {
        if !self.packed.is_empty() {
            // NaN, negatives and anything below 2⁻²⁴ become 2⁻²⁴ (code 0:
            // `pack` saw to it), anything from 1 up becomes 1 (the last slot).
            let x = c.max(f32::from_bits(LOW_BITS)).min(1.0);
            let bits = x.to_bits() - LOW_BITS;
            let e = self.packed[(bits >> BIN_SHIFT) as usize];
            return ((e >> 16) + u32::from((bits & IN_BIN) >= (e & 0xFFFF))) as u8;
        }
        if c.is_nan() || c <= 0.0 {
            return 0;
        }
        if c >= 1.0 {
            return self.white;
        }
        let bin = (c.to_bits().saturating_sub(LOW_BITS) >> BIN_SHIFT) as usize;
        let mut k = if c.to_bits() < LOW_BITS { 0 } else { self.start[bin] as usize };
        k += usize::from(c >= self.edges[k]);
        if !self.one_step {
            while c >= self.edges[k] {
                k += 1;
            }
        }
        k as u8
    }
}

/// `v` in [0, 1] to an 8-bit code, truncated as the course does (NaN to 0).
#[inline]
pub(super) fn to_byte(v: f32) -> u8 {
    if v.is_nan() {
        0
    } else {
        (v * 255.0).clamp(0.0, 255.0) as u8
    }
}
