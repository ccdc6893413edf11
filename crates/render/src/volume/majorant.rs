//! Majorants of a medium's extinction: an upper bound on `σt` along any
//! ray, piecewise constant over coarse blocks of its density grid, so that
//! null-scattering tracking takes few tentative collisions where the medium
//! is thin and none where it is empty.
//!
//! A grid's trilinear interpolation never exceeds the largest of a cell's
//! eight corners, so a block's largest lattice sample bounds the density
//! anywhere in it. Where emission is gathered (camera and bounce rays, not
//! shadow rays), a block whose emission grid glows somewhere gets at least
//! a floor of tentative collisions, since emission is gathered at
//! tentative collisions and a block without any would be skipped.

use super::grid::Grid;
use luster_core::math::{Aabb, Vec3};

/// Lattice cells per block edge: coarse enough that a ray crosses few
/// blocks, fine enough to skip the empty space around a cloud.
pub const BLOCK: usize = 8;

/// Upper bounds on a medium's extinction (per unit length of a unit ray).
#[derive(Clone, Debug)]
pub enum Majorant {
    /// The same bound everywhere in the bound (a constant density).
    Uniform(f32),
    /// One bound per block of a grid.
    Blocks(Blocks),
}

/// The block bounds over a grid's box, in the bound's own space.
#[derive(Clone, Debug)]
pub struct Blocks {
    /// The grid's box.
    bounds: Aabb,
    /// One block's size.
    size: Vec3,
    /// Blocks along x, y and z.
    dims: [usize; 3],
    /// Each block's bound, x fastest.
    rates: Vec<f32>,
    /// Each block's bound where emission is gathered.
    glowing: Vec<f32>,
}

impl Majorant {
    /// Block bounds of `density` (times `scale` and the largest extinction
    /// coefficient at density 1, `sigma_t`); blocks where `glows` says the
    /// emission grid is positive get at least `floor`.
    pub fn of_grid(
        density: &Grid<f32>,
        scale: f32,
        sigma_t: f32,
        glows: Option<&Grid<Vec3>>,
        floor: f32,
    ) -> Majorant {
        let d = density.dims();
        // Density and emission are baked or read on one lattice; a grid on
        // another would make every block glow.
        let (glows, everywhere) = match glows {
            Some(g) if g.dims() == d => (Some(g), false),
            other => (None, other.is_some()),
        };
        let dims = [0, 1, 2].map(|a| (d[a] - 1).div_ceil(BLOCK));
        let bounds = density.bounds();
        let lattice = Vec3::new(d[0] as f32 - 1.0, d[1] as f32 - 1.0, d[2] as f32 - 1.0);
        // The last block along an axis may reach past the box; rays are clipped to the box.
        let size = bounds.extent() / lattice * BLOCK as f32;
        let mut rates = vec![0.0f32; dims[0] * dims[1] * dims[2]];
        let mut glowing = rates.clone();
        for bz in 0..dims[2] {
            for by in 0..dims[1] {
                for bx in 0..dims[0] {
                    let range = |b: usize, a: usize| b * BLOCK..=((b + 1) * BLOCK).min(d[a] - 1);
                    let mut top = 0.0f32;
                    let mut glow = everywhere;
                    for z in range(bz, 2) {
                        for y in range(by, 1) {
                            for x in range(bx, 0) {
                                top = top.max(density.sample(x, y, z));
                                if let Some(g) = glows {
                                    glow |= g.sample(x, y, z).max_element() > 0.0;
                                }
                            }
                        }
                    }
                    let rate = top.max(0.0) * scale * sigma_t;
                    let at = (bz * dims[1] + by) * dims[0] + bx;
                    rates[at] = rate;
                    glowing[at] = if glow { rate.max(floor) } else { rate };
                }
            }
        }
        Majorant::Blocks(Blocks { bounds, size, dims, rates, glowing })
    }

    /// The largest bound anywhere (where emission is gathered).
    pub fn max(&self) -> f32 {
        match self {
            Majorant::Uniform(r) => *r,
            Majorant::Blocks(b) => b.glowing.iter().copied().fold(0.0, f32::max),
        }
    }

    /// The stretches of the ray `o + t d` (in the bound's own space) between
    /// `t0` and `t1`, each with its bound: with the floor where emission
    /// glows when `emission` is gathered along the ray.
    pub fn segments(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, emission: bool) -> Segments<'_> {
        match self {
            Majorant::Uniform(rate) => Segments { t: t0, t_end: t1, walk: Walk::Uniform(*rate) },
            Majorant::Blocks(b) => {
                let rates = if emission { &b.glowing } else { &b.rates };
                Segments { t: t0, t_end: t1, walk: b.walk(rates, o, d, t0, t1) }
            }
        }
    }
}

impl Segments<'static> {
    /// One stretch from `t0` to `t1` with the bound `rate`.
    pub fn uniform(rate: f32, t0: f32, t1: f32) -> Segments<'static> {
        Segments { t: t0, t_end: t1, walk: Walk::Uniform(rate) }
    }
}

/// Stretches of constant bound along a ray ([`Majorant::segments`]).
pub struct Segments<'a> {
    /// Where the next stretch begins.
    t: f32,
    t_end: f32,
    walk: Walk<'a>,
}

enum Walk<'a> {
    Uniform(f32),
    /// A 3D digital differential analyser over the blocks (Amanatides and
    /// Woo): the block, the `t` at which each axis next crosses into
    /// another, the `t` per block along each axis and the step's sign.
    Blocks {
        b: &'a Blocks,
        /// The blocks' bounds this walk reads.
        rates: &'a [f32],
        cell: [i32; 3],
        next: [f32; 3],
        delta: [f32; 3],
        step: [i32; 3],
    },
    Done,
}

impl Blocks {
    fn walk<'a>(&'a self, rates: &'a [f32], o: Vec3, d: Vec3, t0: f32, t1: f32) -> Walk<'a> {
        // Clip to the grid's box: outside it there is no density.
        let inv = d.recip();
        let a = (self.bounds.min - o) * inv;
        let b = (self.bounds.max - o) * inv;
        let (lo, hi) = (a.min(b).max_element().max(t0), a.max(b).min_element().min(t1));
        if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
            return Walk::Done;
        }
        let mid = o + d * lo;
        let g = (mid - self.bounds.min) / self.size;
        let mut cell = [0i32; 3];
        let mut next = [f32::INFINITY; 3];
        let mut delta = [f32::INFINITY; 3];
        let mut step = [0i32; 3];
        for axis in 0..3 {
            let top = self.dims[axis] as i32 - 1;
            cell[axis] = (g[axis].floor() as i32).clamp(0, top);
            if d[axis] > 0.0 {
                step[axis] = 1;
                let edge = self.bounds.min[axis] + (cell[axis] + 1) as f32 * self.size[axis];
                next[axis] = (edge - o[axis]) * inv[axis];
                delta[axis] = self.size[axis] * inv[axis];
            } else if d[axis] < 0.0 {
                step[axis] = -1;
                let edge = self.bounds.min[axis] + cell[axis] as f32 * self.size[axis];
                next[axis] = (edge - o[axis]) * inv[axis];
                delta[axis] = -self.size[axis] * inv[axis];
            }
        }
        Walk::Blocks { b: self, rates, cell, next, delta, step }
    }
}

impl Segments<'_> {
    /// The next stretch `(t_start, t_end, bound)`, or `None` past the end.
    #[inline]
    pub fn next_segment(&mut self) -> Option<(f32, f32, f32)> {
        if self.t >= self.t_end {
            return None;
        }
        match &mut self.walk {
            Walk::Done => None,
            Walk::Uniform(rate) => {
                let s = (self.t, self.t_end, *rate);
                self.t = self.t_end;
                Some(s)
            }
            Walk::Blocks { b, rates, cell, next, delta, step } => {
                let axis = if next[0] < next[1] {
                    if next[0] < next[2] {
                        0
                    } else {
                        2
                    }
                } else if next[1] < next[2] {
                    1
                } else {
                    2
                };
                let end = next[axis].min(self.t_end);
                let rate =
                    rates[(cell[2] as usize * b.dims[1] + cell[1] as usize) * b.dims[0] + cell[0] as usize];
                let s = (self.t, end, rate);
                self.t = end;
                cell[axis] += step[axis];
                next[axis] += delta[axis];
                if cell[axis] < 0 || cell[axis] >= b.dims[axis] as i32 {
                    self.t_end = self.t_end.min(end);
                    self.walk = Walk::Done;
                }
                Some(s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blob(n: u32) -> Grid<f32> {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        Grid::bake(b, n, |p| Ok::<f32, ()>((1.0 - p.length()).max(0.0) * (2.0 + p.x))).unwrap()
    }

    /// Along random rays, every point's density times the coefficient is
    /// within the bound of the stretch it lies in, and the stretches tile
    /// the part of the ray inside the box without gaps.
    #[test]
    fn segments_bound_the_density_and_tile_the_ray() {
        let g = blob(37);
        let m = Majorant::of_grid(&g, 1.5, 2.0, None, 0.0);
        let mut state = 12345u64;
        let mut rnd = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        for _ in 0..200 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 3.0;
            let d = Vec3::new(rnd(), rnd(), rnd()).normalize();
            let mut s = m.segments(o, d, -10.0, 10.0, true);
            let mut last: Option<f32> = None;
            while let Some((a, b, rate)) = s.next_segment() {
                assert!(a <= b);
                if let Some(l) = last {
                    assert!((a - l).abs() < 1e-5, "gap between stretches: {l} then {a}");
                }
                last = Some(b);
                for k in 0..16 {
                    let t = a + (b - a) * (k as f32 + 0.5) / 16.0;
                    let v = g.at(o + d * t) * 1.5 * 2.0;
                    assert!(v <= rate * (1.0 + 1e-5) + 1e-6, "density {v} above its bound {rate}");
                }
            }
        }
    }

    #[test]
    fn empty_blocks_have_no_bound_and_glowing_ones_a_floor() {
        let b = Aabb::new(Vec3::ZERO, Vec3::splat(4.0));
        let g = Grid::bake(b, 33, |p| Ok::<f32, ()>(if p.x < 1.0 { 1.0 } else { 0.0 })).unwrap();
        let glow =
            Grid::bake(b, 33, |p| Ok::<Vec3, ()>(if p.z > 3.0 { Vec3::ONE } else { Vec3::ZERO })).unwrap();
        let m = Majorant::of_grid(&g, 1.0, 1.0, Some(&glow), 7.0);
        let Majorant::Blocks(bl) = &m else { panic!("a grid has blocks") };
        assert_eq!(bl.dims, [4, 4, 4]);
        // x blocks 2..3, z blocks 0..2: far from both.
        assert_eq!(bl.glowing[(4 + 1) * 4 + 2], 0.0);
        assert_eq!(bl.glowing[(3 * 4 + 1) * 4 + 2], 7.0);
        assert_eq!(bl.rates[(3 * 4 + 1) * 4 + 2], 0.0);
        assert_eq!(bl.glowing[(4 + 1) * 4], 1.0);
        assert_eq!(m.max(), 7.0);
    }
}
