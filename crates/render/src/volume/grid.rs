//! A script's density (or emission) baked on a regular grid over the bound's
//! box, looked up trilinearly: the option `GridResolution` trades detail
//! finer than a cell and the bake for a cheap lookup instead of a Lua call
//! and the noise behind it.
//!
//! Samples sit on the `n × n × n` lattice of points spanning the box,
//! corners included, so a field that is linear across a cell is reproduced
//! exactly. Outside the box the nearest face's value holds (lookups outside
//! happen only within rounding of the bound).

use luster_core::math::{Aabb, Vec3};
use rayon::prelude::*;
use std::ops::{Add, Mul};

/// A baked field.
#[derive(Clone, Debug)]
pub struct Grid<T> {
    n: usize,
    min: Vec3,
    /// Lattice steps per unit along each axis.
    scale: Vec3,
    data: Vec<T>,
}

impl<T> Grid<T>
where
    T: Copy + Send + Sync + Add<Output = T> + Mul<f32, Output = T>,
{
    /// Evaluates `f` at the `n³` lattice points of `b` (in parallel), or
    /// returns the first error.
    pub fn bake<E: Send>(b: Aabb, n: u32, f: impl Fn(Vec3) -> Result<T, E> + Sync) -> Result<Grid<T>, E> {
        let n = n.max(2) as usize;
        let cell = b.extent() / (n - 1) as f32;
        let data: Vec<T> = (0..n * n * n)
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
                f(b.min + cell * Vec3::new(x as f32, y as f32, z as f32))
            })
            .collect::<Result<_, E>>()?;
        Ok(Grid { n, min: b.min, scale: cell.recip(), data })
    }

    /// The trilinear interpolation of the lattice at `p`.
    #[inline]
    pub fn at(&self, p: Vec3) -> T {
        let top = (self.n - 1) as f32;
        let g = ((p - self.min) * self.scale).clamp(Vec3::ZERO, Vec3::splat(top));
        let i = g.floor().min(Vec3::splat(top - 1.0));
        let f = g - i;
        let (x, y, z) = (i.x as usize, i.y as usize, i.z as usize);
        let n = self.n;
        let at = |dx: usize, dy: usize, dz: usize| self.data[(z + dz) * n * n + (y + dy) * n + x + dx];
        let lerp = |a: T, b: T, t: f32| a * (1.0 - t) + b * t;
        let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f.x);
        let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f.x);
        let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f.x);
        let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f.x);
        lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z)
    }

    /// Bytes the samples take.
    pub fn bytes(&self) -> usize {
        self.data.len() * std::mem::size_of::<T>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_fields_are_exact_and_corners_are_samples() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 4.0, 3.0));
        let f = |p: Vec3| p.x * 2.0 - p.y + 0.5 * p.z;
        let g = Grid::bake(b, 5, |p| Ok::<f32, ()>(f(p))).unwrap();
        for p in [b.min, b.max, Vec3::new(0.3, 1.7, 2.9), Vec3::new(-0.99, 3.99, 2.01)] {
            assert!((g.at(p) - f(p)).abs() < 1e-4, "{p}: {} vs {}", g.at(p), f(p));
        }
        // Outside, the face value holds.
        assert!((g.at(Vec3::new(5.0, 0.0, 2.0)) - f(Vec3::new(1.0, 0.0, 2.0))).abs() < 1e-4);
        assert_eq!(g.bytes(), 125 * 4);
    }

    #[test]
    fn a_failing_sample_fails_the_bake() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let r = Grid::<f32>::bake(b, 3, |p| if p.x > 0.9 { Err("boom") } else { Ok(1.0) });
        assert_eq!(r.err(), Some("boom"));
    }
}
