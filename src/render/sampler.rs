//! Deterministic, well-stratified sample patterns for distribution ray tracing.
//!
//! Every camera sample needs several independent random dimensions: the
//! position in the pixel, on the lens, in time, on each area light, and for
//! each glossy bounce. Each 2D dimension uses Kensler's correlated
//! multi-jittered pattern ("Correlated Multi-Jittered Sampling", Pixar
//! Technical Memo 13-01, 2013): for `n` samples the points are stratified in
//! both the `n` horizontal and `n` vertical strips and in an `m × ⌈n/m⌉` grid
//! (m = ⌊√n⌋), for any `n`, not only squares. The pattern is chosen by a hash
//! of (seed, pixel, dimension), so dimensions are decorrelated from each other
//! and from neighbouring pixels, and sample `i` of a pixel is the same whatever
//! thread renders it — the image depends only on the scene, the sample count
//! and the seed.
//!
//! A path tracer draws a few dimensions per bounce, and stratifying the deep
//! ones gains little (the paths through them already differ) while a CMJ
//! point costs three hashed permutations. [`PixelSampler::stratify_first`]
//! keeps CMJ for the first calls (the camera and the first hit) and draws
//! the rest as independent hashed uniforms, still a pure function of (seed,
//! pixel, sample, call).

/// The samples of one pixel: pattern seeds come from the pixel, sample
/// `index` of `count` is drawn, and each call moves to the next dimension.
#[derive(Clone, Copy, Debug)]
pub struct PixelSampler {
    pixel_hash: u32,
    index: u32,
    dim: u32,
    /// `index % count`, and the CMJ grid's columns `m = ⌊√count⌋` and rows
    /// `⌈count/m⌉`: the same for every dimension, so worked out once, each
    /// with what [`permute`] needs (its mask and an exact division by
    /// multiplication).
    slot: u32,
    n: Span,
    cols: Span,
    rows: Span,
    /// Calls drawn from CMJ patterns; later calls are independent uniforms.
    stratified: u32,
}

impl PixelSampler {
    /// Sample `index` of `count` for the pixel `(x, y)` under `seed`.
    #[inline]
    pub fn new(seed: u32, x: u32, y: u32, index: u32, count: u32) -> Self {
        let pixel_hash = hash3(seed, x, y);
        let count = count.max(1);
        let cols = ((count as f32).sqrt() as u32).max(1);
        let rows = count.div_ceil(cols);
        PixelSampler {
            pixel_hash,
            index,
            dim: 0,
            slot: index % count,
            n: Span::new(count),
            cols: Span::new(cols),
            rows: Span::new(rows),
            stratified: u32::MAX,
        }
    }

    /// Stratifies only the first `calls` calls (counted from the sampler's
    /// creation); the later ones are independent uniform draws, far cheaper.
    #[inline]
    pub fn stratify_first(&mut self, calls: u32) {
        self.stratified = calls;
    }

    /// The hash of the current call for an independent draw.
    #[inline]
    fn independent(&mut self) -> u32 {
        let h = hash2(hash2(self.pixel_hash, self.dim), self.index);
        self.dim += 1;
        h
    }

    /// The next 2D dimension: a point of `[0, 1)²`.
    #[inline]
    pub fn next_2d(&mut self) -> (f32, f32) {
        if self.dim >= self.stratified {
            let h = self.independent();
            return (unit(h), unit(hash2(h, 0x68bc_21eb)));
        }
        let p = hash2(self.pixel_hash, self.dim);
        self.dim += 1;
        cmj_grid(self.slot, self.n, self.cols, self.rows, p)
    }

    /// Calls drawn so far for this camera sample.
    #[inline]
    pub fn calls(&self) -> u32 {
        self.dim
    }

    /// How many samples the pixel takes.
    #[inline]
    pub fn count(&self) -> u32 {
        self.n.len
    }

    /// The next 1D dimension: a value in `[0, 1)` stratified over the samples.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        if self.dim >= self.stratified {
            return unit(self.independent());
        }
        let p = hash2(self.pixel_hash, self.dim);
        self.dim += 1;
        let s = permute(self.slot, self.n, p);
        ((s as f32 + rand_float(self.index, p ^ 0x9e37_79b9)) / self.n.len as f32).min(ONE_MINUS_EPS)
    }
}

const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

/// Point `s` of an `n`-point correlated multi-jittered pattern `p`.
#[cfg(test)]
fn cmj(s: u32, n: u32, p: u32) -> (f32, f32) {
    let m = ((n as f32).sqrt() as u32).max(1);
    cmj_grid(s, Span::new(n), Span::new(m), Span::new(n.div_ceil(m)), p)
}

/// [`cmj`] with its `m × k` grid given (`m = ⌊√n⌋`, `k = ⌈n/m⌉`).
#[inline]
fn cmj_grid(s: u32, n: Span, m: Span, k: Span, p: u32) -> (f32, f32) {
    let s = permute(s, n, p.wrapping_mul(0x5163_3e2d));
    let sx = permute(m.rem(s), m, p.wrapping_mul(0x68bc_21eb));
    let sy = permute(m.div(s), k, p.wrapping_mul(0x02e5_be93));
    let jx = rand_float(s, p.wrapping_mul(0x967a_889b));
    let jy = rand_float(s, p.wrapping_mul(0x368c_c8b7));
    let (n, m, k) = (n.len, m.len, k.len);
    let x = (sx as f32 + (sy as f32 + jx) / k as f32) / m as f32;
    let y = (s as f32 + jy) / n as f32;
    (x.min(ONE_MINUS_EPS), y.min(ONE_MINUS_EPS))
}

/// A length `l ≥ 1` the sampler divides by, with what division and
/// [`permute`] need worked out once: the mask of the next power of two, and
/// the constant of an exact 32-bit quotient and remainder by multiplication
/// (Lemire, Kaser and Kurz, "Faster remainder by direct computation", 2019),
/// so a CMJ point costs no hardware division.
#[derive(Clone, Copy, Debug)]
struct Span {
    len: u32,
    mask: u32,
    /// `⌈2⁶⁴ / len⌉` (0 for `len = 1`, where it wraps).
    magic: u64,
}

/// [`Span::magic`] of the lengths up to 256 (every grid side up to 65 536
/// samples): a sampler is made per camera sample, and a 64-bit division
/// costs as much as the ones it saves.
const MAGIC: [u64; 257] = {
    let mut t = [0u64; 257];
    let mut l = 1;
    while l < t.len() {
        t[l] = (u64::MAX / l as u64).wrapping_add(1);
        l += 1;
    }
    t
};

impl Span {
    #[inline]
    fn new(len: u32) -> Span {
        let len = len.max(1);
        let mask = if len == 1 { 0 } else { u32::MAX >> (len - 1).leading_zeros() };
        let magic = match MAGIC.get(len as usize) {
            Some(&m) => m,
            None => (u64::MAX / u64::from(len)).wrapping_add(1),
        };
        Span { len, mask, magic }
    }

    /// `a % len`.
    #[inline]
    fn rem(self, a: u32) -> u32 {
        let low = self.magic.wrapping_mul(u64::from(a));
        ((u128::from(low) * u128::from(self.len)) >> 64) as u32
    }

    /// `a / len`.
    #[inline]
    fn div(self, a: u32) -> u32 {
        if self.len == 1 {
            return a;
        }
        ((u128::from(self.magic) * u128::from(a)) >> 64) as u32
    }
}

/// A pseudo-random permutation of `0..l` selected by `p` (Kensler 2013): a
/// hash that is a bijection on the next power of two, cycle-walked into range.
#[inline]
fn permute(mut i: u32, l: Span, p: u32) -> u32 {
    if l.len <= 1 {
        return 0;
    }
    let w = l.mask;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l.len {
            break;
        }
    }
    l.rem(i.wrapping_add(p))
}

/// A hashed float in `[0, 1)` for index `i` under pattern `p`.
#[inline]
fn rand_float(mut i: u32, p: u32) -> f32 {
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i = i.wrapping_mul(0xb365_34e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i = i.wrapping_mul(0x93fc_4795);
    i ^= 0xdf6e_307f;
    i ^= i >> 17;
    i = i.wrapping_mul(1 | (p >> 18));
    (i >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The top 24 bits of `h` as a float in `[0, 1)`.
#[inline]
fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// A 32-bit mix of two words (the finalizer of MurmurHash3 over a combination).
#[inline]
fn hash2(a: u32, b: u32) -> u32 {
    let mut h = a ^ b.wrapping_mul(0x9e37_79b9).rotate_left(15);
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

#[inline]
fn hash3(a: u32, b: u32, c: u32) -> u32 {
    hash2(hash2(a, b), c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn span_divides_exactly() {
        // The multiplication's quotient and remainder against the hardware's,
        // at the ends of the range and on a spread of numerators.
        let mut a = 0x1234_5678u32;
        for len in (1u32..=1100).chain([4095, 4096, 65_537, 1 << 31, u32::MAX]) {
            let span = Span::new(len);
            let check = |a: u32| {
                assert_eq!(span.rem(a), a % len, "{a} % {len}");
                assert_eq!(span.div(a), a / len, "{a} / {len}");
            };
            for x in [0, 1, len - 1, len, len.wrapping_add(1), u32::MAX - 1, u32::MAX] {
                check(x);
            }
            for _ in 0..200 {
                a ^= a << 13;
                a ^= a >> 17;
                a ^= a << 5;
                check(a);
            }
            // The mask is `len − 1` with every bit below its highest set.
            let mut w = len - 1;
            for shift in [1, 2, 4, 8, 16] {
                w |= w >> shift;
            }
            assert_eq!(span.mask, w, "mask of {len}");
        }
    }

    #[test]
    fn permute_is_a_permutation() {
        for l in [1u32, 2, 3, 7, 16, 100, 400] {
            for p in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, Span::new(l), p) as usize;
                    assert!(!seen[j], "l={l} p={p}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn cmj_stratifies_rows_columns_and_cells() {
        for n in [4u32, 16, 100, 400, 7, 50] {
            let pts: Vec<(f32, f32)> = (0..n).map(|s| cmj(s, n, 1234)).collect();
            // Each of the n horizontal strips holds exactly one point.
            let mut rows: Vec<u32> = pts.iter().map(|p| (p.1 * n as f32) as u32).collect();
            rows.sort_unstable();
            assert_eq!(rows, (0..n).collect::<Vec<_>>(), "n={n}");
            // And each of the m columns holds about n/m points.
            let m = (n as f32).sqrt() as u32;
            let mut cols = vec![0u32; m as usize];
            for p in &pts {
                assert!((0.0..1.0).contains(&p.0) && (0.0..1.0).contains(&p.1));
                cols[(p.0 * m as f32) as usize] += 1;
            }
            assert!(cols.iter().all(|&c| c >= n / m - 1 && c <= n.div_ceil(m)), "n={n}: {cols:?}");
        }
    }

    #[test]
    fn dimensions_differ_and_samples_repeat_exactly() {
        let mut a = PixelSampler::new(7, 3, 4, 5, 16);
        let mut b = PixelSampler::new(7, 3, 4, 5, 16);
        let (p0, p1) = (a.next_2d(), a.next_2d());
        assert_ne!(p0, p1);
        assert_eq!(b.next_2d(), p0);
        assert_eq!(b.next_2d(), p1);
        let mut c = PixelSampler::new(8, 3, 4, 5, 16);
        assert_ne!(c.next_2d(), p0);
    }

    #[test]
    fn calls_past_the_stratified_ones_are_uniform_and_repeatable() {
        // 4096 draws of a late call over samples and pixels: each of 16 bins
        // per axis holds 256 ± 5 standard deviations (√(256·15/16) ≈ 15.5).
        let mut bins = [[0u32; 16]; 3];
        for i in 0..4096u32 {
            let mut s = PixelSampler::new(3, i % 64, i / 64, i % 7, 7);
            s.stratify_first(2);
            let first = s.next_2d();
            let mut again = PixelSampler::new(3, i % 64, i / 64, i % 7, 7);
            assert_eq!(again.next_2d(), first, "stratified calls unchanged");
            for _ in 0..4 {
                s.next_1d();
            }
            let (a, b) = s.next_2d();
            let c = s.next_1d();
            for (k, v) in [a, b, c].into_iter().enumerate() {
                assert!((0.0..1.0).contains(&v));
                bins[k][(v * 16.0) as usize] += 1;
            }
        }
        for (k, axis) in bins.iter().enumerate() {
            assert!(axis.iter().all(|&n| n.abs_diff(256) < 78), "axis {k}: {axis:?}");
        }
        let draw = || {
            let mut s = PixelSampler::new(9, 1, 2, 3, 16);
            s.stratify_first(0);
            (s.next_2d(), s.next_1d())
        };
        assert_eq!(draw(), draw());
    }

    #[test]
    fn one_d_dimension_is_stratified() {
        let n = 64;
        let mut v: Vec<u32> =
            (0..n).map(|i| (PixelSampler::new(1, 2, 3, i, n).next_1d() * n as f32) as u32).collect();
        v.sort_unstable();
        assert_eq!(v, (0..n).collect::<Vec<_>>());
    }
}
