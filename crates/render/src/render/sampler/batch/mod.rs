//! A pixel's CMJ draws computed a run of samples at a time.
//!
//! The render loop takes a pixel's samples of one pass one after another on
//! one thread, and every sample draws the same first dimensions. Drawn one
//! at a time, a CMJ point's three cycle-walked permutations cost a branch
//! that mispredicts often (the walk rejects 22–37% of its candidates at the
//! course's counts) and latency-bound chains of multiplications. Here the
//! second sample of a pass to draw a dimension
//! computes that dimension for the next [`LANES`] samples at once, in AVX2
//! lanes that walk together until every lane is in range, into a small
//! per-thread memo that the following samples read.
//!
//! The memo is keyed by everything a value depends on (the pixel's hash,
//! the count, the dimension, 1D or 2D, the sample), so it is a cache of a
//! pure function: the values are the scalar formula's bit for bit, whatever
//! the thread, the pass or the tile order. Every lane performs the scalar
//! code's integer and `f32` operations in the same order (no FMA), and the
//! divisions by the grid side are exact (their bounds are checked where
//! batching is enabled, [`memo`]). A dimension's first use in a pass is
//! drawn alone: deep dimensions that only some samples reach would
//! otherwise cost a batch per sample.
//!
//! A walk's steps are chains of multiplications, and one batch's lanes
//! leave most of the processor idle waiting on them. The dimensions the
//! pixel before batched and drew are batched again together at the
//! pixel's first batch, two at a time in one loop ([`fill_hot`]): the
//! course's path-traced boxes batch three 2D dimensions a pixel. A walk over
//! at most sixteen values (a grid axis at the course's counts) looks its
//! steps up in a table instead.

use super::PixelSampler;
use std::cell::UnsafeCell;

/// Samples computed by one batch: two vectors of eight, whose walks
/// interleave.
const LANES: usize = 16;

/// Memo entries, indexed by dimension: more than a camera sample's
/// stratified dimensions in the course's scenes.
const SLOTS: usize = 64;

/// Largest count batched: keeps the grid divisions by multiplication exact
/// (`s · m < 2³²` for every `s < n`) and the walk's compares in signed range.
const MAX_COUNT: u32 = 1 << 20;

/// What one memo entry holds: a dimension's values for samples
/// `first..first + len` of a pixel.
#[derive(Clone, Copy)]
struct Tag {
    /// The pixel's hash and count ([`owner`]), compared at once.
    owner: u64,
    /// `2·dim + (1 if 2D)`.
    key: u32,
    first: u32,
    len: u32,
}

/// The memo: tags apart from the values, so a lookup touches the tag's
/// cache line and one value's.
pub(super) struct Memo {
    tags: [Tag; SLOTS],
    /// Whether the entry's dimension was batched in the pixel before: such
    /// a dimension is batched from its first use in the next pixel.
    hot: [bool; SLOTS],
    /// Whether the entry's values were drawn since it was filled: a
    /// dimension filled ahead of its use ([`fill_hot`]) and then not used
    /// is not filled ahead again.
    used: [bool; SLOTS],
    values: [[[f32; 2]; LANES]; SLOTS],
}

const NO_TAG: Tag = Tag { owner: 0, key: 0, first: 0, len: 0 };

thread_local! {
    static MEMO: UnsafeCell<Memo> = const {
        UnsafeCell::new(Memo {
            tags: [NO_TAG; SLOTS],
            hot: [false; SLOTS],
            used: [false; SLOTS],
            values: [[[0.0; 2]; LANES]; SLOTS],
        })
    };
}

/// Shortest run of samples batched: a run of two costs as much either way,
/// and drawing alone skips the memo's bookkeeping.
pub(super) const MIN_RUN: u32 = 3;

/// This thread's memo, for a pixel of `count` samples, where it may be
/// batched on this processor (null otherwise).
///
/// A sampler keeps the pointer: reaching a thread-local costs a call that
/// does not inline, more than the memo's lookup. The pointer makes the
/// sampler neither `Send` nor `Sync`, so it is only ever followed on this
/// thread, whose memo lives as long as the thread (it has nothing to drop).
pub(super) fn memo(count: u32) -> Handle {
    #[cfg(target_arch = "x86_64")]
    if (2..=MAX_COUNT).contains(&count) && std::arch::is_x86_feature_detected!("avx2") {
        return MEMO.with(|m| m as Handle);
    }
    std::ptr::null()
}

/// A pointer to a thread's memo.
pub(super) type Handle = *const UnsafeCell<Memo>;

/// The pixel hash and sample count of a memo entry in one word: a pixel's
/// samples share it ([`PixelSampler::owner`]).
#[inline(always)]
pub(super) fn owner(pixel_hash: u32, count: u32) -> u64 {
    (u64::from(count) << 32) | u64::from(pixel_hash)
}

/// The memo key of a dimension: `2·dim + (1 if 2D)`.
#[inline(always)]
fn key(dim: u32, two_d: bool) -> u32 {
    dim.wrapping_mul(2) | u32::from(two_d)
}

/// Stratified dimension `dim` of sample `s.index` (below `s.batch_end`, so
/// `s.memo` is not null) where the memo holds it, or `None`, after which
/// the caller calls [`miss`]. Only this lookup is inlined into the
/// sampler's draws: the rest would make every caller's draw slower.
#[inline(always)]
pub(super) fn hit(s: &PixelSampler, dim: u32, two_d: bool) -> Option<[f32; 2]> {
    let key = key(dim, two_d);
    let slot = key as usize % SLOTS;
    // SAFETY: `memo` set `s.memo` on this thread (see there), and a sampler
    // with samples to batch has a non-null one. The one reference lives
    // only in this function, which calls nothing that reaches the memo.
    let memo = unsafe { &mut *(*s.memo).get() };
    let tag = &memo.tags[slot];
    let off = s.index.wrapping_sub(tag.first);
    if tag.owner == s.owner && tag.key == key && off < tag.len {
        memo.used[slot] = true;
        return Some(memo.values[slot][off as usize % LANES]);
    }
    None
}

/// [`hit`] found nothing: the dimension's first use in this pixel is drawn
/// alone (`None`), unless the pixel before batched it; a later use batches
/// the samples from this one on. The first batch of a pixel also fills the
/// other dimensions the pixel before batched and drew ([`fill_hot`]).
#[inline(never)]
pub(super) fn miss(s: &PixelSampler, dim: u32, two_d: bool) -> Option<[f32; 2]> {
    let key = key(dim, two_d);
    let slot = key as usize % SLOTS;
    // SAFETY: as in `hit`, the memo is this thread's; the one reference to
    // it lives in this call, which is not re-entered (`lanes` only computes
    // values), so it is exclusive.
    let memo = unsafe { &mut *(*s.memo).get() };
    let tag = &mut memo.tags[slot];
    let this_pixel = tag.owner == s.owner;
    if tag.key != key || !(this_pixel || memo.hot[slot]) {
        memo.hot[slot] = false;
        *tag = Tag { owner: s.owner, key, first: s.index, len: 0 };
        return None;
    }
    let len = (s.batch_end - s.index).min(LANES as u32);
    if len < 2 || cfg!(not(target_arch = "x86_64")) {
        memo.tags[slot] = Tag { owner: s.owner, key, first: s.index, len: 0 };
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    {
        if this_pixel {
            // SAFETY: `batch_end` is set only where `memo` found AVX2.
            let [values, _] = unsafe { lanes::fill_group(s, [dim, 0], 1, two_d, len as usize) };
            store(memo, slot, key, s, len, values, true);
        } else {
            fill_hot(memo, slot, key, s, len);
        }
    }
    Some(memo.values[slot][0])
}

/// Puts the `len` values of dimension `key` from sample `s.index` into
/// entry `slot`; `used` if one of them is being drawn.
fn store(memo: &mut Memo, slot: usize, key: u32, s: &PixelSampler, len: u32, values: Values, used: bool) {
    memo.tags[slot] = Tag { owner: s.owner, key, first: s.index, len };
    memo.hot[slot] = true;
    memo.used[slot] = used;
    memo.values[slot] = values;
}

/// The first batch of a pixel: dimension `key` (entry `slot`) and every
/// other dimension the pixel before batched and drew, all from sample
/// `s.index`, two of a kind at a time so that their walks overlap. A
/// dimension's values depend only on the pixel, the dimension and the
/// sample, so filling one ahead of its first use in this pixel changes
/// none; a pass's dimensions are much the same from pixel to pixel.
#[cfg(target_arch = "x86_64")]
fn fill_hot(memo: &mut Memo, slot: usize, key: u32, s: &PixelSampler, len: u32) {
    let mut keys = [0u32; SLOTS];
    keys[0] = key;
    let mut n = 1;
    // The candidates as a mask first, eight entries to a word: a loop
    // testing each tag would eat into the fills it saves.
    let (hot, used) = (memo.hot.map(u8::from), memo.used.map(u8::from));
    let mut cand = 0u64;
    for (c, (h, u)) in hot.chunks_exact(8).zip(used.chunks_exact(8)).enumerate() {
        let (mut hb, mut ub) = ([0u8; 8], [0u8; 8]);
        hb.copy_from_slice(h);
        ub.copy_from_slice(u);
        // Bytes of 0 or 1: the multiplication gathers byte i's bit into
        // bit 56 + i, with no carries.
        let both = u64::from_le_bytes(hb) & u64::from_le_bytes(ub);
        cand |= (both.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * c);
    }
    cand &= !(1 << slot);
    while cand != 0 {
        let j = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        let t = &memo.tags[j];
        if t.owner != s.owner && t.len > 0 {
            keys[n] = t.key;
            n += 1;
        }
    }
    let keys = &mut keys[..n];
    // Grouped by kind, each group filled at once.
    keys.sort_unstable_by_key(|&k| (k & 1, k));
    for kind in keys.chunk_by(|a, b| a & 1 == b & 1) {
        for group in kind.chunks(GROUP) {
            let mut dims = [0; GROUP];
            for (d, k) in dims.iter_mut().zip(group) {
                *d = k / 2;
            }
            // SAFETY: `batch_end` is set only where `memo` found AVX2.
            let values = unsafe { lanes::fill_group(s, dims, group.len(), kind[0] & 1 == 1, len as usize) };
            for (&k, v) in group.iter().zip(values) {
                store(memo, k as usize % SLOTS, k, s, len, v, k == key);
            }
        }
    }
}

/// Dimensions filled at once by [`fill_hot`]. The course's path-traced
/// boxes batch three 2D dimensions (the pixel position, the light sample,
/// the bounce): two at a time overlap their walks, where three at a time
/// (twelve walks) would spill registers.
const GROUP: usize = 2;

/// A memo entry's values.
type Values = [[f32; 2]; LANES];

#[cfg(target_arch = "x86_64")]
mod lanes;

#[cfg(all(test, target_arch = "x86_64"))]
mod tests;
