//! A script's density (or emission) baked on a regular grid over the bound's
//! box, looked up trilinearly: the option `GridResolution` trades detail
//! finer than a cell and the bake for a cheap lookup instead of a Lua call
//! and the noise behind it.
//!
//! Samples sit on a lattice of `nx × ny × nz` points spanning the box,
//! corners included, so a field that is linear across a cell is reproduced
//! exactly. Outside the box the nearest face's value holds (lookups outside
//! happen only within rounding of the bound).

use luster_core::math::{Aabb, Vec3};
use rayon::prelude::*;
use std::ops::{Add, Mul};

/// A baked field.
#[derive(Clone, Debug)]
pub struct Grid<T> {
    /// Lattice points along x, y and z (each at least 2).
    dims: [usize; 3],
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
        Ok(Grid { dims: [n; 3], min: b.min, scale: cell.recip(), data })
    }

    /// A grid of given samples over `b`: `data[(z·ny + y)·nx + x]` is the
    /// lattice point `(x, y, z)`. `None` unless every dimension is at least 2,
    /// `data` has one sample per point and `b` has a positive extent.
    pub fn from_samples(b: Aabb, dims: [usize; 3], data: Vec<T>) -> Option<Grid<T>> {
        let count = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d))?;
        if dims.iter().any(|&d| d < 2) || data.len() != count || b.extent().min_element() <= 0.0 {
            return None;
        }
        let cell = b.extent() / Vec3::new(dims[0] as f32 - 1.0, dims[1] as f32 - 1.0, dims[2] as f32 - 1.0);
        Some(Grid { dims, min: b.min, scale: cell.recip(), data })
    }

    /// Lattice points along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The box the lattice spans.
    pub fn bounds(&self) -> Aabb {
        let top = Vec3::new(self.dims[0] as f32 - 1.0, self.dims[1] as f32 - 1.0, self.dims[2] as f32 - 1.0);
        Aabb::new(self.min, self.min + top / self.scale)
    }

    /// The sample at lattice point `(x, y, z)`.
    #[inline]
    pub fn sample(&self, x: usize, y: usize, z: usize) -> T {
        self.data[(z * self.dims[1] + y) * self.dims[0] + x]
    }

    /// The trilinear interpolation of the lattice at `p`.
    #[inline]
    pub fn at(&self, p: Vec3) -> T {
        let top = Vec3::new(self.dims[0] as f32 - 1.0, self.dims[1] as f32 - 1.0, self.dims[2] as f32 - 1.0);
        let g = ((p - self.min) * self.scale).clamp(Vec3::ZERO, top);
        let i = g.floor().min(top - 1.0);
        let f = g - i;
        let (x, y, z) = (i.x as usize, i.y as usize, i.z as usize);
        let [nx, ny, _] = self.dims;
        let at = |dx: usize, dy: usize, dz: usize| self.data[((z + dz) * ny + y + dy) * nx + x + dx];
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
    fn uneven_lattices_index_x_fastest() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 3.0));
        let dims = [3, 2, 4];
        let f = |p: Vec3| p.x + 10.0 * p.y + 100.0 * p.z;
        let mut data = Vec::new();
        for z in 0..4 {
            for y in 0..2 {
                for x in 0..3 {
                    data.push(f(Vec3::new(x as f32, y as f32, z as f32)));
                }
            }
        }
        let g = Grid::from_samples(b, dims, data).unwrap();
        assert_eq!(g.sample(2, 1, 3), f(Vec3::new(2.0, 1.0, 3.0)));
        assert!((g.at(Vec3::new(1.5, 0.25, 2.5)) - f(Vec3::new(1.5, 0.25, 2.5))).abs() < 1e-3);
        assert_eq!(g.bounds().max, b.max);
        assert!(Grid::from_samples(b, [3, 2, 4], vec![0.0f32; 5]).is_none());
        assert!(Grid::from_samples(b, [1, 2, 4], vec![0.0f32; 8]).is_none());
    }

    #[test]
    fn a_failing_sample_fails_the_bake() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let r = Grid::<f32>::bake(b, 3, |p| if p.x > 0.9 { Err("boom") } else { Ok(1.0) });
        assert_eq!(r.err(), Some("boom"));
    }
}
