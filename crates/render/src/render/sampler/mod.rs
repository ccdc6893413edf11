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
//! A CMJ point costs three hashed permutations (cycle-walked into range)
//! and a jitter. The permutation hash has half of Kensler's
//! multiplications: any bijection keeps the pattern's stratification, and
//! the shorter one integrates edges and discs as well. One hash jitters both
//! axes (16 bits each, inside a cell of `1/n`), and the cells are sized by
//! multiplying by reciprocals. CMJ rather than a Sobol sequence with hashed
//! Owen scrambling (Burley 2020): that is cheaper to draw, but integrates
//! 2D edges with more error at the course's sample counts.
//!
//! A path tracer draws a few dimensions per bounce, and stratifying the deep
//! ones gains little (the paths through them already differ).
//! [`PixelSampler::stratify_first`] keeps CMJ for the first calls (the camera
//! and the first hit) and draws the rest as independent uniforms, one 64-bit
//! hash of (seed, pixel, sample, call) each.
//!
//! The render loop's runs of samples ([`PixelSampler::batched`]) draw their
//! stratified calls from a per-thread memo (`batch`) filled
//! sixteen samples at a time in AVX2 lanes (`batch/lanes.rs`), with the
//! same values bit for bit.
//!
//! A single-sample image has nothing to stratify: its draws are plain hashes
//! of the pixel and the dimension, fixed so that 1-spp images keep their
//! bytes.

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
    /// `1/count` and `1/(cols·rows)`: the cell sizes, multiplied not divided.
    inv_n: f32,
    inv_mk: f32,
    /// Calls drawn from CMJ patterns; later calls are independent uniforms.
    stratified: u32,
    /// Samples below this one are drawn in order on this thread, so their
    /// stratified calls may come from [`batch`] (0: never), whose memo is
    /// `memo` (not null where `batch_end` is not 0).
    batch_end: u32,
    memo: batch::Handle,
    /// [`batch::owner`] of this pixel: a memo entry's hash and count
    /// compared as one word.
    owner: u64,
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
            inv_n: 1.0 / count as f32,
            inv_mk: 1.0 / (cols * rows) as f32,
            stratified: u32::MAX,
            batch_end: 0,
            memo: std::ptr::null(),
            owner: batch::owner(pixel_hash, count),
        }
    }

    /// This pixel's sampler for a run of samples that one thread draws in
    /// order, one after another: their stratified calls are computed
    /// several samples at a time (`batch`), with the same values.
    #[inline]
    pub fn batched(self, run: std::ops::Range<u32>) -> Self {
        let end = run.end.min(self.n.len);
        if end < run.start + batch::MIN_RUN {
            return self;
        }
        let memo = batch::memo(self.n.len);
        let batch_end = if memo.is_null() { 0 } else { end };
        PixelSampler { batch_end, memo, ..self }
    }

    /// Sample `index` of the same pixel and count: what [`new`](Self::new)
    /// gives, without its per-pixel set-up (the pixel's hash, the grid, the
    /// reciprocals), which a pixel's samples share.
    #[inline]
    pub fn at(&self, index: u32) -> Self {
        PixelSampler { index, dim: 0, slot: self.n.rem(index), stratified: u32::MAX, ..*self }
    }

    /// Makes this sampler [`at(index)`](Self::at) in place: a pixel's state
    /// kept across its samples is not copied whole for each.
    #[inline]
    pub fn restart(&mut self, index: u32) {
        self.index = index;
        self.dim = 0;
        self.slot = self.n.rem(index);
        self.stratified = u32::MAX;
    }

    /// Passes over the next call without drawing it, for a value that would
    /// go unused: the later calls keep the values they would have had.
    #[inline]
    pub fn skip(&mut self) {
        self.dim += 1;
    }

    /// Stratifies only the first `calls` calls (counted from the sampler's
    /// creation); the later ones are independent uniform draws, far cheaper.
    #[inline]
    pub fn stratify_first(&mut self, calls: u32) {
        self.stratified = calls;
    }

    /// 64 hashed bits for the independent draw of call `dim`.
    #[inline]
    fn independent(&self, dim: u32) -> u64 {
        let key = (u64::from(self.pixel_hash) << 32) | u64::from(self.index);
        mix64(key.wrapping_add(u64::from(dim + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15)))
    }

    /// The next 2D dimension: a point of `[0, 1)²`. Inlined are a batched
    /// run's memo hit and an independent draw past the stratified calls,
    /// the common cases (a path's deep bounces draw the latter, whose little
    /// work a call would double); the rest is out of line.
    #[inline]
    pub fn next_2d(&mut self) -> (f32, f32) {
        let dim = self.dim;
        if dim < self.stratified {
            if self.index < self.batch_end {
                if let Some([x, y]) = batch::hit(self, dim, true) {
                    self.dim += 1;
                    return (x, y);
                }
            }
        } else if self.n.len != 1 {
            self.dim += 1;
            let h = self.independent(dim);
            return (unit((h >> 32) as u32), unit(h as u32));
        }
        self.next_2d_cold()
    }

    /// [`next_2d`](Self::next_2d) without a memo hit.
    #[inline(never)]
    fn next_2d_cold(&mut self) -> (f32, f32) {
        let dim = self.dim;
        self.dim += 1;
        if self.n.len == 1 {
            return single_2d(self.pixel_hash, self.index, dim, dim >= self.stratified);
        }
        if dim >= self.stratified {
            let h = self.independent(dim);
            return (unit((h >> 32) as u32), unit(h as u32));
        }
        if self.index < self.batch_end {
            if let Some([x, y]) = batch::miss(self, dim, true) {
                return (x, y);
            }
        }
        let p = hash2(self.pixel_hash, dim);
        cmj_grid(self.slot, self.n, self.cols, self.rows, p, (self.inv_n, self.inv_mk))
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

    /// The next 1D dimension: a value in `[0, 1)` stratified over the
    /// samples. Inlined as [`next_2d`](Self::next_2d) is.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let dim = self.dim;
        if dim < self.stratified {
            if self.index < self.batch_end {
                if let Some([v, _]) = batch::hit(self, dim, false) {
                    self.dim += 1;
                    return v;
                }
            }
        } else if self.n.len != 1 {
            self.dim += 1;
            return unit((self.independent(dim) >> 32) as u32);
        }
        self.next_1d_cold()
    }

    /// [`next_1d`](Self::next_1d) without a memo hit.
    #[inline(never)]
    fn next_1d_cold(&mut self) -> f32 {
        let dim = self.dim;
        self.dim += 1;
        if self.n.len == 1 {
            return single_1d(self.pixel_hash, self.index, dim, dim >= self.stratified);
        }
        if dim >= self.stratified {
            return unit((self.independent(dim) >> 32) as u32);
        }
        if self.index < self.batch_end {
            if let Some([v, _]) = batch::miss(self, dim, false) {
                return v;
            }
        }
        let p = hash2(self.pixel_hash, dim);
        let s = permute(self.slot, self.n, p);
        ((s as f32 + rand_float(self.index, p ^ 0x9e37_79b9)) * self.inv_n).min(ONE_MINUS_EPS)
    }
}

/// The 2D draw of a single-sample pixel (fixed hashes: see the module doc).
#[inline]
fn single_2d(pixel_hash: u32, index: u32, dim: u32, independent: bool) -> (f32, f32) {
    if independent {
        let h = hash2(hash2(pixel_hash, dim), index);
        return (unit(h), unit(hash2(h, 0x68bc_21eb)));
    }
    let p = hash2(pixel_hash, dim);
    (rand_float(0, p.wrapping_mul(0x967a_889b)), rand_float(0, p.wrapping_mul(0x368c_c8b7)))
}

/// The 1D draw of a single-sample pixel (fixed hashes: see the module doc).
#[inline]
fn single_1d(pixel_hash: u32, index: u32, dim: u32, independent: bool) -> f32 {
    if independent {
        return unit(hash2(hash2(pixel_hash, dim), index));
    }
    rand_float(index, hash2(pixel_hash, dim) ^ 0x9e37_79b9)
}

const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

/// Point `s` of an `n`-point correlated multi-jittered pattern `p`.
#[cfg(test)]
fn cmj(s: u32, n: u32, p: u32) -> (f32, f32) {
    let m = ((n as f32).sqrt() as u32).max(1);
    let k = n.div_ceil(m);
    cmj_grid(s, Span::new(n), Span::new(m), Span::new(k), p, (1.0 / n as f32, 1.0 / (m * k) as f32))
}

/// [`cmj`] with its `m × k` grid given (`m = ⌊√n⌋`, `k = ⌈n/m⌉`).
#[inline]
fn cmj_grid(s: u32, n: Span, m: Span, k: Span, p: u32, (inv_n, inv_mk): (f32, f32)) -> (f32, f32) {
    let s = permute(s, n, p.wrapping_mul(0x5163_3e2d));
    let sx = permute(m.rem(s), m, p.wrapping_mul(0x68bc_21eb));
    let sy = permute(m.div(s), k, p.wrapping_mul(0x02e5_be93));
    // One hash jitters both axes: 16 bits each within a cell of 1/n.
    let j = hash2(s, p);
    let jx = (j >> 16) as f32 * (1.0 / 65_536.0);
    let jy = (j & 0xffff) as f32 * (1.0 / 65_536.0);
    let x = (sx as f32 * k.len as f32 + sy as f32 + jx) * inv_mk;
    let y = (s as f32 + jy) * inv_n;
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

/// A pseudo-random permutation of `0..l` selected by `p`: Kensler's (2013)
/// hash, a bijection on the next power of two cycle-walked into range, with
/// four of its eight multiplications. The shifts by 1 and 2 stay: on a few
/// bits they are what keeps the map from being affine.
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
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
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

/// SplitMix64's finalizer.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[inline]
fn hash3(a: u32, b: u32, c: u32) -> u32 {
    hash2(hash2(a, b), c)
}

/// Shortest run of a pixel's samples that [`PixelSampler::batched`] batches.
pub(crate) const MIN_BATCH_RUN: u32 = batch::MIN_RUN;

mod batch;

#[cfg(test)]
mod tests;
