//! The film: where the tile loop leaves linear radiance, and what decides,
//! after the render, which files are written from it.
//!
//! - [`Film`]: one linear RGB value per pixel, the reconstruction [`Filter`]'s
//!   weighted mean of the pixel's samples. Tiles accumulate into a [`Tile`]
//!   and are merged when done, so the render loop never sees 8 bits.
//! - [`tonemap`]: the course's photographic operator (hw5), ACES and Filmic,
//!   saturation and gamma; and the course's plain clamp for LDR scenes. Its
//!   whole-image statistics (log-average, burn-out percentile) are in
//!   `stats`, its table-driven gamma and quantization in `quantize`.
//! - [`display`]: the display transform of scenes that opt out of the
//!   course's 8-bit semantics (`<Display>`, `--display`).
//! - [`outputs`]: which files a camera's `ImageName` and `Tonemap`s ask for
//!   (an `.exr`/`.hdr` and its tone-mapped `.png`, or a single PNG/JPEG), and
//!   writing them.
//!
//! Scene parameters read here (through the camera's description):
//! `ImageName` (its extension picks the format) and `Tonemap`; the scene's
//! `Display`.

pub mod display;
pub mod outputs;
mod quantize;
mod stats;
pub mod tonemap;

pub use display::Display;
pub use outputs::{plan_outputs, Output, OutputKind};
pub use tonemap::{Gamma, Operator, Tonemap};

use crate::math::Vec3;

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
/// filter-weighted sum of sample radiance and the sum of weights.
pub struct Tile {
    x0: u32,
    y0: u32,
    width: u32,
    sum: Vec<Vec3>,
    weight: Vec<f32>,
    filter: Filter,
}

impl Tile {
    /// An empty tile covering `x0..x1` × `y0..y1`.
    pub fn new(x0: u32, y0: u32, x1: u32, y1: u32, filter: Filter) -> Tile {
        let n = ((x1 - x0) * (y1 - y0)) as usize;
        Tile { x0, y0, width: x1 - x0, sum: vec![Vec3::ZERO; n], weight: vec![0.0; n], filter }
    }

    /// Adds a sample of radiance `l` taken at `(jx, jy)` inside pixel
    /// `(x, y)` (pixel coordinates, `(0.5, 0.5)` is the centre).
    #[inline]
    pub fn add_sample(&mut self, x: u32, y: u32, jx: f32, jy: f32, l: Vec3) {
        let i = ((y - self.y0) * self.width + (x - self.x0)) as usize;
        let w = self.filter.weight(jx - 0.5, jy - 0.5);
        self.sum[i] += l * w;
        self.weight[i] += w;
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
        for (r, (sums, wts)) in self.sum.chunks_exact(tw).zip(self.weight.chunks_exact(tw)).enumerate() {
            let at = ((self.y0 - rows_y0) as usize + r) * width + self.x0 as usize;
            for ((p, s), &wt) in rows[at..at + tw].iter_mut().zip(sums).zip(wts) {
                if wt > 0.0 {
                    *p = *s / wt;
                }
            }
        }
    }

    /// The pixels it covers: `(x0, y0, x1, y1)`, ends excluded.
    pub fn bounds(&self) -> (u32, u32, u32, u32) {
        let h = (self.sum.len() as u32).checked_div(self.width).unwrap_or(0);
        (self.x0, self.y0, self.x0 + self.width, self.y0 + h)
    }

    /// Pixels of the tile.
    pub fn len(&self) -> usize {
        self.sum.len()
    }

    /// Whether the tile has no pixels.
    pub fn is_empty(&self) -> bool {
        self.sum.is_empty()
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
        let mut t = Tile::new(1, 0, 3, 2, Filter::Box);
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
    fn gaussian_weights_the_centre_more() {
        let mut film = Film::new(1, 1);
        let mut t = Tile::new(0, 0, 1, 1, Filter::Gaussian);
        t.add_sample(0, 0, 0.5, 0.5, Vec3::splat(1.0));
        t.add_sample(0, 0, 0.0, 0.0, Vec3::splat(0.0));
        film.merge(&t);
        let w = (-0.5f32 * 4.5).exp();
        assert!((film.pixels[0].x - 1.0 / (1.0 + w)).abs() < 1e-6);
    }
}
