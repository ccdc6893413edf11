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
//! The search is exact: it scans the 3³ (3²) nearest cells and, when F2
//! exceeds the distance to the cells beyond them (at least 1 in every metric),
//! those cells of the 5³ (5²) shell that could still hold a nearer point.
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

/// A cell's id and its feature point relative to the cell's lower corner,
/// from one 64-bit hash: 21 bits per coordinate, the high half as the id.
#[inline(always)]
fn feature<const N: usize>(cell: [i32; N], jitter: f32) -> (u32, [f32; N]) {
    // Distinct odd multipliers: two cells collide only if Σ Δcₖ·Mₖ ≡ 0 mod 2⁶⁴.
    const MUL: [u64; 3] = [0x9e37_79b9_7f4a_7c15, 0xc2b2_ae3d_27d4_eb4f, 0x1656_67b1_9e37_79f9];
    let mut h = 0u64;
    for k in 0..N {
        h = h.wrapping_add((cell[k] as u32 as u64).wrapping_mul(MUL[k]));
    }
    // SplitMix64's finaliser spreads every input bit over the whole word.
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    let local = core::array::from_fn(|k| {
        let u = ((h >> (21 * k)) & 0x1f_ffff) as f32 * (1.0 / (1u32 << 21) as f32);
        0.5 + jitter * (u - 0.5)
    });
    ((h >> 32) as u32, local)
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
///
/// With `shell_only`, the inner cells (already scanned) are skipped, and so
/// is any cell whose whole range of possible feature points
/// (`centre ± jitter/2` per axis) is no nearer than the current F2; the
/// metrics are all monotone in each axis distance, so `dist` of the per-axis
/// gaps is a lower bound.
#[inline(always)]
fn scan<const N: usize>(
    cell: [i32; N],
    frac: [f32; N],
    jitter: f32,
    (radius, shell_only): (i32, bool),
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
        if shell_only {
            if step.iter().all(|s| s.abs() < radius) {
                continue;
            }
            let gap = core::array::from_fn(|k| {
                let centre = step[k] as f32 + 0.5;
                ((frac[k] - centre).abs() - 0.5 * jitter).max(0.0)
            });
            if dist(gap) >= best.d2 {
                continue;
            }
        }
        let (id, local) = feature::<N>(core::array::from_fn(|k| cell[k].wrapping_add(step[k])), jitter);
        let offset: [f32; N] = core::array::from_fn(|k| step[k] as f32 + local[k]);
        let d = dist(core::array::from_fn(|k| offset[k] - frac[k]));
        if d < best.d1 {
            best.d2 = best.d1;
            *best = Best { d1: d, id, offset, ..*best };
        } else if d < best.d2 {
            best.d2 = d;
        }
    }
}

/// Runs the exact search with the metric resolved once, outside the loop.
#[inline(always)]
fn search<const N: usize>(p: [f32; N], metric: Metric, jitter: f32) -> ([f32; N], Best<N>) {
    let base = p.map(luster_core::math::floor);
    let cell = base.map(|b| b as i32);
    let frac: [f32; N] = core::array::from_fn(|k| p[k] - base[k]);
    let jitter = if jitter >= 0.0 { jitter.min(1.0) } else { 0.0 };
    let run = |pass: (i32, bool), best: &mut Best<N>| match metric {
        Metric::Euclidean => scan(cell, frac, jitter, pass, |d| d.iter().map(|v| v * v).sum(), best),
        Metric::Manhattan => scan(cell, frac, jitter, pass, |d| d.iter().map(|v| v.abs()).sum(), best),
        Metric::Chebyshev => {
            scan(cell, frac, jitter, pass, |d| d.iter().fold(0.0, |m, v| v.abs().max(m)), best)
        }
    };
    let mut best = Best { d1: f32::INFINITY, d2: f32::INFINITY, id: 0, offset: [0.0; N] };
    run((1, false), &mut best);
    // A point two cells away along axis k lies at least 2.5 − j/2 − f (above)
    // or 1.5 − j/2 + f (below) from the query along that axis alone, so at
    // least that far in every metric: if F2 is within that gap, the 3ⁿ block
    // was enough. With jitter 1 the gap is 1 to 1.5; Manhattan's F2 passes it
    // most often, which is why the shell scan prunes cell by cell.
    let half = 0.5 * jitter;
    let gap = frac.iter().fold(f32::INFINITY, |g, &f| g.min(2.5 - half - f).min(1.5 - half + f));
    let gap = if metric == Metric::Euclidean { gap * gap } else { gap };
    if best.d2 > gap {
        run((2, true), &mut best);
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
mod tests;
