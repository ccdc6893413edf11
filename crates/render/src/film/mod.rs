//! The film: where the tile loop leaves linear radiance, and what decides,
//! after the render, which files are written from it.
//!
//! - [`Film`]: one linear RGB value per pixel, the reconstruction [`Filter`]'s
//!   weighted mean of the pixel's samples. Tiles accumulate into a [`Tile`]
//!   and are merged when done, so the render loop never sees 8 bits.
//! - [`aov`]: render passes (albedo, normal, depth, object id, ...) beside
//!   the beauty image, and their multi-layer EXR.
//! - [`adaptive`]: adaptive sampling's error estimate and stopping rule.
//! - [`reserve`]: the first camera's film memory, written ahead by a worker
//!   that would otherwise wait while the scene loads.
//! - [`write`](mod@write): writing the files a camera's `ImageName` and `Tonemap`s ask
//!   for (planned by `luster_core::image::outputs`, tone-mapped by
//!   `luster_core::tonemap`).
//!
//! Scene parameters read here (through the camera's description):
//! `ImageName` (its extension picks the format) and `Tonemap`; the scene's
//! `Display`.

pub mod adaptive;
pub mod aov;
pub mod reserve;
pub mod write;

pub use aov::{Aovs, Pass, Passes};
pub use reserve::FilmReserve;
pub use write::{rgb8, write_outputs};

use luster_core::math::Vec3;
use luster_core::tonemap;

/// How a pixel's samples are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// The plain average.
    #[default]
    Box,
    /// A Gaussian of σ = 1/3 pixel around the pixel centre weighting the
    /// pixel's own samples (a pixel-sized support: no sample reaches a
    /// neighbour, so tiles stay independent).
    Gaussian,
}

impl Filter {
    /// The weight of a sample at `(dx, dy)` from the pixel centre, in pixels.
    #[inline]
    pub fn weight(self, dx: f32, dy: f32) -> f32 {
        match self {
            Filter::Box => 1.0,
            Filter::Gaussian => (-(dx * dx + dy * dy) * 4.5).exp(),
        }
    }
}

/// A rectangle of the film being filled by one worker: per pixel, the
/// filter-weighted sum of sample radiance and the sum of weights (`[r, g, b,
/// weight]`), in its own part of a buffer that holds every tile's
/// ([`Tile::all_in`]).
pub struct Tile<'a> {
    x0: u32,
    y0: u32,
    width: u32,
    acc: &'a mut [[f32; 4]],
    filter: Filter,
}

impl<'a> Tile<'a> {
    /// Empty tiles covering `rects` (`(x0, y0, x1, y1)`, ends excluded), in
    /// order, in consecutive parts of `store`, which is replaced by a zeroed
    /// buffer of their size unless it has that size (memory written ahead,
    /// [`reserve`]; [`Tile::clear`] zeroes a tile before its first sample
    /// either way). One allocation for all the tiles, zeroed by the
    /// allocator: fresh pages that the worker rendering a tile faults in.
    /// Two small vectors per tile, zeroed as they were made, would grow the
    /// workers' malloc arenas a page at a time, an `mprotect` call each, the
    /// workers queueing for the kernel's lock.
    pub fn all_in(
        store: &'a mut Vec<[f32; 4]>,
        rects: &[(u32, u32, u32, u32)],
        filter: Filter,
    ) -> Vec<Tile<'a>> {
        let area = |&(x0, y0, x1, y1): &(u32, u32, u32, u32)| (x1 - x0) as usize * (y1 - y0) as usize;
        let n = rects.iter().map(area).sum();
        if store.len() != n {
            *store = vec![[0.0; 4]; n];
        }
        let mut rest = store.as_mut_slice();
        let mut tiles = Vec::with_capacity(rects.len());
        for r @ &(x0, y0, x1, _) in rects {
            let (acc, tail) = std::mem::take(&mut rest).split_at_mut(area(r));
            rest = tail;
            tiles.push(Tile { x0, y0, width: x1 - x0, acc, filter });
        }
        tiles
    }

    /// Forgets its samples. Called on a tile fresh from [`Tile::all_in`]
    /// before its first sample, it makes the store's pages be written before
    /// they are read: a fresh page read first is mapped to the shared zero
    /// page and faults again when written.
    pub fn clear(&mut self) {
        self.acc.fill([0.0; 4]);
    }

    /// Adds a sample of radiance `l` taken at `(jx, jy)` inside pixel
    /// `(x, y)` (pixel coordinates, `(0.5, 0.5)` is the centre).
    #[inline]
    pub fn add_sample(&mut self, x: u32, y: u32, jx: f32, jy: f32, l: Vec3) {
        let i = ((y - self.y0) * self.width + (x - self.x0)) as usize;
        let w = self.filter.weight(jx - 0.5, jy - 0.5);
        let (lw, a) = (l * w, &mut self.acc[i]);
        a[0] += lw.x;
        a[1] += lw.y;
        a[2] += lw.z;
        a[3] += w;
    }

    /// Writes the filtered values into `rows`, the rows from `rows_y0` on of
    /// a film `width` pixels wide (row-major), so that bands of a film can be
    /// filled in parallel. A pixel that got no sample (a render stopped by a
    /// shader failure) is left as it is.
    pub fn write_rows(&self, rows: &mut [Vec3], width: usize, rows_y0: u32) {
        let tw = self.width as usize;
        if tw == 0 {
            return;
        }
        // Row by row: a division and a remainder per pixel cost more than
        // the copy.
        for (r, accs) in self.acc.chunks_exact(tw).enumerate() {
            let at = ((self.y0 - rows_y0) as usize + r) * width + self.x0 as usize;
            for (p, &[r, g, b, wt]) in rows[at..at + tw].iter_mut().zip(accs) {
                if wt > 0.0 {
                    *p = Vec3::new(r, g, b) / wt;
                }
            }
        }
    }

    /// The pixels' sums, `[r, g, b, weight]`, row by row.
    pub fn sums(&self) -> &[[f32; 4]] {
        self.acc
    }

    /// The pixels it covers: `(x0, y0, x1, y1)`, ends excluded.
    pub fn bounds(&self) -> (u32, u32, u32, u32) {
        let h = (self.acc.len() as u32).checked_div(self.width).unwrap_or(0);
        (self.x0, self.y0, self.x0 + self.width, self.y0 + h)
    }

    /// Pixels of the tile.
    pub fn len(&self) -> usize {
        self.acc.len()
    }

    /// Whether the tile has no pixels.
    pub fn is_empty(&self) -> bool {
        self.acc.is_empty()
    }
}

/// Bytes per pixel of the files written from a film beside it: an 8-bit
/// copy and its encoder's buffers, or a float copy for an HDR file.
const OUTPUT_BYTES_PER_PIXEL: u64 = 16;

/// Bytes a render of cameras of these sizes needs beyond the scene itself:
/// every finished [`Film`] (kept until all are written) and, for the largest
/// camera, its tiles' sums and the files written from it. What a render
/// checks against the memory it may use before it starts.
pub fn memory_needed(sizes: impl IntoIterator<Item = (u32, u32)>) -> u64 {
    memory_needed_with(sizes, Passes::NONE, false)
}

/// [`memory_needed`] of a render with `passes` (kept with every film) and,
/// if `adaptive`, adaptive sampling's state (for the largest camera).
pub fn memory_needed_with(
    sizes: impl IntoIterator<Item = (u32, u32)>,
    passes: Passes,
    adaptive: bool,
) -> u64 {
    let (mut films, mut largest) = (0u64, 0u64);
    let aov = passes.bytes_per_pixel();
    for (w, h) in sizes {
        let n = u64::from(w) * u64::from(h);
        films += n * (std::mem::size_of::<Vec3>() as u64 + aov);
        largest = largest.max(n);
    }
    let state = if adaptive { std::mem::size_of::<adaptive::PixelState>() as u64 } else { 0 };
    films + largest * (std::mem::size_of::<[f32; 4]>() as u64 + OUTPUT_BYTES_PER_PIXEL + state)
}

/// Refuses, in a sentence, a render of cameras of these sizes whose
/// [`memory_needed`] is beyond what the process may still take
/// ([`luster_core::memory::headroom`]): an allocation failing midway would
/// abort it.
pub fn check_memory(sizes: impl IntoIterator<Item = (u32, u32)> + Clone) -> Result<(), String> {
    check_memory_with(sizes, Passes::NONE, false)
}

/// [`check_memory`] with [`memory_needed_with`].
pub fn check_memory_with(
    sizes: impl IntoIterator<Item = (u32, u32)> + Clone,
    passes: Passes,
    adaptive: bool,
) -> Result<(), String> {
    let needed = memory_needed_with(sizes.clone(), passes, adaptive);
    match luster_core::memory::headroom() {
        Some(left) if needed > left => {
            let (w, h) =
                sizes.into_iter().max_by_key(|&(w, h)| u64::from(w) * u64::from(h)).unwrap_or((0, 0));
            Err(format!(
                "its images (the largest {w}x{h}) need about {} of memory, more than the {} this process may still use (its ulimit -v or cgroup limit)",
                luster_core::memory::describe(needed),
                luster_core::memory::describe(left)
            ))
        }
        _ => Ok(()),
    }
}

/// A finished image in linear radiance, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// One linear RGB value per pixel (the course's units: 255 is the white
    /// of an 8-bit image that is not tone-mapped).
    pub pixels: Vec<Vec3>,
}

impl Film {
    /// A black film.
    pub fn new(width: u32, height: u32) -> Film {
        Film { width, height, pixels: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// Writes a finished tile's filtered values into the film. A pixel that
    /// got no sample (a render stopped by a shader failure) stays black.
    pub fn merge(&mut self, tile: &Tile) {
        tile.write_rows(&mut self.pixels, self.width as usize, 0);
    }

    /// 8-bit RGB with the course's semantics for images that are not tone
    /// mapped: see [`tonemap::course_rgb8`].
    pub fn to_rgb8(&self) -> Vec<u8> {
        tonemap::course_rgb8(&self.pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_land_where_they_belong_and_average_by_the_filter() {
        let mut film = Film::new(3, 2);
        let mut store = Vec::new();
        let mut t = Tile::all_in(&mut store, &[(1, 0, 3, 2)], Filter::Box).remove(0);
        t.add_sample(2, 1, 0.5, 0.5, Vec3::new(2.0, 4.0, 6.0));
        t.add_sample(2, 1, 0.1, 0.9, Vec3::new(4.0, 0.0, 0.0));
        t.add_sample(1, 0, 0.5, 0.5, Vec3::ONE);
        film.merge(&t);
        assert_eq!(film.pixels[5], Vec3::new(3.0, 2.0, 3.0));
        assert_eq!(film.pixels[1], Vec3::ONE);
        assert_eq!(film.pixels[0], Vec3::ZERO, "outside the tile");
        assert_eq!(film.pixels[2], Vec3::ZERO, "no sample");
    }

    #[test]
    fn tiles_take_consecutive_zeroed_parts_of_the_store() {
        let rects = [(0, 0, 2, 2), (2, 0, 3, 2), (0, 2, 3, 3)];
        let mut store = vec![[1.0; 4]; 2];
        let mut tiles = Tile::all_in(&mut store, &rects, Filter::Box);
        assert_eq!(tiles.iter().map(Tile::bounds).collect::<Vec<_>>(), rects);
        assert_eq!(tiles.iter().map(Tile::len).collect::<Vec<_>>(), [4, 2, 3]);
        tiles[1].add_sample(2, 1, 0.5, 0.5, Vec3::splat(2.0));
        drop(tiles);
        assert_eq!(store.len(), 9);
        assert_eq!(store[5], [2.0, 2.0, 2.0, 1.0], "the second tile's second pixel");
        assert_eq!(store.iter().filter(|a| **a != [0.0; 4]).count(), 1);
    }

    #[test]
    fn gaussian_weights_the_centre_more() {
        let mut film = Film::new(1, 1);
        let mut store = vec![[1.0; 4]; 7];
        let mut t = Tile::all_in(&mut store, &[(0, 0, 1, 1)], Filter::Gaussian).remove(0);
        t.add_sample(0, 0, 0.5, 0.5, Vec3::splat(1.0));
        t.add_sample(0, 0, 0.0, 0.0, Vec3::splat(0.0));
        film.merge(&t);
        let w = (-0.5f32 * 4.5).exp();
        assert!((film.pixels[0].x - 1.0 / (1.0 + w)).abs() < 1e-6);
    }
}
