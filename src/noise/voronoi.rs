//! Worley's cellular ("Voronoi") noise: distances to the nearest feature
//! points of a jittered grid (Worley, "A Cellular Texture Basis Function",
//! SIGGRAPH 1996, with one point per unit cell instead of a Poisson count).
//!
//! Each integer cell holds one feature point at `centre + jitter·(u − ½)`,
//! `u` uniform in [0, 1)³ from a hash of the cell, so `jitter = 0` gives a
//! regular grid of cell centres and `jitter = 1` (the usual choice) points
//! anywhere in the cell. `jitter` is clamped to [0, 1] (NaN counts as 0).
//!
//! The result, [`Cell`], holds F1 and F2 (the nearest and second-nearest
//! distances, so `f2 − f1` draws cell borders), an `id` hashed from the
//! nearest point's cell (for a per-cell random colour) and that point, `p1`.
//! The search is exact: it scans the 3³ (3²) nearest cells and, in the rare
//! case that F2 exceeds the distance to the cells beyond them (at least 1 in
//! every metric), the 5³ (5²) block.
//!
//! | | Euclidean | Manhattan | Chebyshev |
//! |---|---|---|---|
//! | F1 at most (3D, 2D) | √3, √2 | 3, 2 | 1, 1 |
//! | F2 at most (3D, 2D) | √6, √5 | 4, 3 | 2, 2 |
//!
//! (F1 is at most the distance to the cell's own point, F2 to the nearer of
//! that and a neighbour's; typical values with jitter 1 are well below:
//! F1 averages 0.52 and F2 0.72 in 3D Euclidean.)

/// The distance used to compare feature points.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Straight-line distance: round cells.
    Euclidean = 0,
    /// Sum of the axis distances: diamond-shaped, faceted cells.
    Manhattan = 1,
    /// Largest axis distance: square, blocky cells.
    Chebyshev = 2,
}

impl Metric {
    /// The metric with this discriminant (0, 1, 2), for callers across FFI.
    pub fn from_u32(v: u32) -> Option<Metric> {
        match v {
            0 => Some(Metric::Euclidean),
            1 => Some(Metric::Manhattan),
            2 => Some(Metric::Chebyshev),
            _ => None,
        }
    }
}

/// The result of a Voronoi lookup; `#[repr(C)]` so it crosses FFI as is.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Distance to the nearest feature point (F1).
    pub f1: f32,
    /// Distance to the second-nearest feature point (F2), `>= f1`.
    pub f2: f32,
    /// A hash of the nearest point's cell: the same everywhere in one cell.
    pub id: u32,
    /// The nearest feature point itself (in 2D, `p1[2]` is 0).
    pub p1: [f32; 3],
}

/// Murmur3's finaliser: every input bit flips about half the output bits.
#[inline(always)]
fn fmix32(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

/// Hashes cell coordinates; the odd multipliers keep axes from cancelling.
#[inline(always)]
fn hash_cell<const N: usize>(c: [i32; N]) -> u32 {
    const MUL: [u32; 3] = [0x8da6_b343, 0xd816_3841, 0xcb1a_b31f];
    let mut h = 0u32;
    for k in 0..N {
        h ^= (c[k] as u32).wrapping_mul(MUL[k]);
    }
    fmix32(h)
}

/// A cell's id and its feature point, relative to the cell's lower corner.
#[inline(always)]
fn feature<const N: usize>(cell: [i32; N], jitter: f32) -> (u32, [f32; N]) {
    let h = hash_cell(cell);
    // A fresh mix per axis gives independent coordinates from one hash.
    let local = core::array::from_fn(|k| {
        let u = (fmix32(h ^ (k as u32 + 1).wrapping_mul(0x9e37_79b9)) >> 8) as f32 / (1u32 << 24) as f32;
        0.5 + jitter * (u - 0.5)
    });
    (h, local)
}

/// The nearest and second-nearest points found so far, in the metric's own
/// units (squared for Euclidean, so no square root inside the loop).
struct Best<const N: usize> {
    d1: f32,
    d2: f32,
    id: u32,
    offset: [f32; N],
}

/// Scans the cells within `radius` of the query's cell, updating `best`.
#[inline(always)]
fn scan<const N: usize>(
    cell: [i32; N],
    frac: [f32; N],
    jitter: f32,
    radius: i32,
    dist: impl Fn([f32; N]) -> f32,
    best: &mut Best<N>,
) {
    let side = 2 * radius + 1;
    for n in 0..side.pow(N as u32) {
        let mut step = [0i32; N];
        let mut rest = n;
        for s in step.iter_mut() {
            *s = rest % side - radius;
            rest /= side;
        }
        let (h, local) = feature::<N>(core::array::from_fn(|k| cell[k].wrapping_add(step[k])), jitter);
        let offset: [f32; N] = core::array::from_fn(|k| step[k] as f32 + local[k]);
        let d = dist(core::array::from_fn(|k| offset[k] - frac[k]));
        if d < best.d1 {
            best.d2 = best.d1;
            *best = Best { d1: d, id: h, offset, ..*best };
        } else if d < best.d2 {
            best.d2 = d;
        }
    }
}

/// Runs the exact search with the metric resolved once, outside the loop.
#[inline(always)]
fn search<const N: usize>(p: [f32; N], metric: Metric, jitter: f32) -> ([f32; N], Best<N>) {
    let base = p.map(f32::floor);
    let cell = base.map(|b| b as i32);
    let frac: [f32; N] = core::array::from_fn(|k| p[k] - base[k]);
    let jitter = if jitter >= 0.0 { jitter.min(1.0) } else { 0.0 };
    let run = |radius: i32, best: &mut Best<N>| match metric {
        Metric::Euclidean => scan(cell, frac, jitter, radius, |d| d.iter().map(|v| v * v).sum(), best),
        Metric::Manhattan => scan(cell, frac, jitter, radius, |d| d.iter().map(|v| v.abs()).sum(), best),
        Metric::Chebyshev => {
            scan(cell, frac, jitter, radius, |d| d.iter().fold(0.0, |m, v| v.abs().max(m)), best)
        }
    };
    let mut best = Best { d1: f32::INFINITY, d2: f32::INFINITY, id: 0, offset: [0.0; N] };
    run(1, &mut best);
    // A point two cells away along axis k lies at least 2.5 − j/2 − f (above)
    // or 1.5 − j/2 + f (below) from the query along that axis alone, so at
    // least that far in every metric: if F2 is within that gap, the 3ⁿ block
    // was enough. With jitter 1 the gap is 1 to 1.5.
    let half = 0.5 * jitter;
    let gap = frac.iter().fold(f32::INFINITY, |g, &f| g.min(2.5 - half - f).min(1.5 - half + f));
    let gap = if metric == Metric::Euclidean { gap * gap } else { gap };
    if best.d2 > gap {
        best = Best { d1: f32::INFINITY, d2: f32::INFINITY, id: 0, offset: [0.0; N] };
        run(2, &mut best);
    }
    if best.d1 == f32::INFINITY {
        // Only a NaN coordinate leaves nothing compared: report NaN, not ∞.
        best.d1 = f32::NAN;
        best.d2 = f32::NAN;
    } else if metric == Metric::Euclidean {
        best.d1 = best.d1.sqrt();
        best.d2 = best.d2.sqrt();
    }
    (base, best)
}

/// 3D cellular noise at (x, y, z); see the module doc for the ranges.
#[inline]
pub fn voronoi3(x: f32, y: f32, z: f32, metric: Metric, jitter: f32) -> Cell {
    let (base, best) = search([x, y, z], metric, jitter);
    Cell { f1: best.d1, f2: best.d2, id: best.id, p1: core::array::from_fn(|k| base[k] + best.offset[k]) }
}

/// 2D cellular noise at (x, y); `p1[2]` is 0.
#[inline]
pub fn voronoi2(x: f32, y: f32, metric: Metric, jitter: f32) -> Cell {
    let (base, best) = search([x, y], metric, jitter);
    Cell {
        f1: best.d1,
        f2: best.d2,
        id: best.id,
        p1: [base[0] + best.offset[0], base[1] + best.offset[1], 0.0],
    }
}

#[cfg(test)]
#[path = "voronoi_tests.rs"]
mod tests;
