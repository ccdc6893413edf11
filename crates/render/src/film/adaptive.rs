//! Adaptive sampling: pixels stop taking samples once their estimated
//! error is below a threshold (`--noise-threshold`, a camera's
//! `<NoiseThreshold>`).
//!
//! The estimate is Cycles' (after Dammertz et al., "A Hierarchical
//! Automatic Stopping Condition for Monte Carlo Global Illumination", WSCG
//! 2010, section 2.1): the pixel's samples are split into two halves, the
//! even- and odd-numbered ones, whose means `A` and `B` are two independent
//! estimates of the pixel; their difference measures the noise, and
//! dividing by the square root of the pixel's brightness `I` makes it
//! relative to what the eye sees of it:
//!
//! ```text
//! error = (|A_r − B_r| + |A_g − B_g| + |A_b − B_b|) / 2 / (0.0001 + √(I_r + I_g + I_b))
//! ```
//!
//! in display units (film value 255 = 1, the white of an 8-bit image).
//! A pixel converges when the largest error in the 3×3 window around it
//! (within its tile) is below the threshold: a pixel whose two halves agree
//! by chance is kept going by a noisier neighbour (Cycles dilates the
//! unconverged pixels the same way).
//!
//! Decisions are taken between the render's passes only, from the pixel's
//! own tile, once at least the minimum sample count is taken; a pixel that
//! stopped never starts again. So the image depends neither on the threads
//! nor on how a split render shares out the tiles.

use super::{Filter, Tile};
use luster_core::math::Vec3;

/// The settings of adaptive sampling.
#[derive(Clone, Copy, Debug, Default)]
pub struct Adaptive {
    /// The error below which a pixel stops (`None`: the camera's
    /// `<NoiseThreshold>`, if any; 0: adaptive sampling off).
    pub threshold: Option<f32>,
    /// Samples every pixel takes before it may stop (`None`:
    /// [`auto_min_spp`]).
    pub min_spp: Option<u32>,
}

impl PartialEq for Adaptive {
    fn eq(&self, o: &Adaptive) -> bool {
        self.threshold.map(f32::to_bits) == o.threshold.map(f32::to_bits) && self.min_spp == o.min_spp
    }
}

impl Eq for Adaptive {}

/// Cycles' automatic minimum for threshold `t`: `max(4, ⌈16 / t^0.3⌉)`
/// (64 samples at `t` = 0.01), at most `max`.
pub fn auto_min_spp(t: f32, max: u32) -> u32 {
    let n = (16.0 / t.max(1e-6).powf(0.3)).ceil().min(1e6) as u32;
    n.max(4).min(max)
}

/// The display white in film units: the error is measured on values where
/// it is 1.
const WHITE: f32 = 255.0;

/// The relative error of a pixel from its samples' filtered sums: `all`
/// (`[r, g, b, weight]` of every sample) and `odd` (of the odd-numbered
/// samples). Infinite while a half has no weight.
pub fn error(all: [f32; 4], odd: [f32; 4]) -> f32 {
    let even_w = all[3] - odd[3];
    if odd[3] <= 0.0 || even_w <= 0.0 {
        return f32::INFINITY;
    }
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    let b = v(odd) / odd[3];
    let a = (v(all) - v(odd)) / even_w;
    let i = v(all) / all[3] / WHITE;
    let diff = (a - b).abs().element_sum() / WHITE * 0.5;
    diff / (0.0001 + i.element_sum().max(0.0).sqrt())
}

/// A pixel's adaptive state: the filtered sums of its odd-numbered samples
/// and whether it stopped.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelState {
    odd: [f32; 4],
    done: bool,
}

/// The adaptive state of a rectangle of the film, beside its [`Tile`].
pub struct AdaptiveTile<'a> {
    x0: u32,
    y0: u32,
    width: u32,
    px: &'a mut [PixelState],
    filter: Filter,
    /// Pixels still sampled.
    active: usize,
}

impl<'a> AdaptiveTile<'a> {
    /// Fresh states covering `rects` (as [`Tile::all_in`]) in consecutive
    /// parts of `store`.
    pub fn all_in(
        store: &'a mut Vec<PixelState>,
        rects: &[(u32, u32, u32, u32)],
        filter: Filter,
    ) -> Vec<AdaptiveTile<'a>> {
        let area = |&(x0, y0, x1, y1): &(u32, u32, u32, u32)| (x1 - x0) as usize * (y1 - y0) as usize;
        let n = rects.iter().map(area).sum();
        store.clear();
        store.resize(n, PixelState::default());
        let mut rest = store.as_mut_slice();
        let mut tiles = Vec::with_capacity(rects.len());
        for r @ &(x0, y0, x1, _) in rects {
            let (px, tail) = std::mem::take(&mut rest).split_at_mut(area(r));
            rest = tail;
            let active = px.len();
            tiles.push(AdaptiveTile { x0, y0, width: x1 - x0, px, filter, active });
        }
        tiles
    }

    #[inline]
    fn index(&self, x: u32, y: u32) -> usize {
        ((y - self.y0) * self.width + (x - self.x0)) as usize
    }

    /// Whether pixel `(x, y)` still takes samples.
    #[inline]
    pub fn active(&self, x: u32, y: u32) -> bool {
        !self.px[self.index(x, y)].done
    }

    /// Pixels of the tile still taking samples.
    pub fn active_count(&self) -> usize {
        self.active
    }

    /// Adds sample `s` (radiance `l` at `(jx, jy)` in pixel `(x, y)`) to the
    /// odd half if it is odd.
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, s: u32, jx: f32, jy: f32, l: Vec3) {
        if s & 1 == 1 {
            let w = self.filter.weight(jx - 0.5, jy - 0.5);
            let i = self.index(x, y);
            let o = &mut self.px[i].odd;
            o[0] += l.x * w;
            o[1] += l.y * w;
            o[2] += l.z * w;
            o[3] += w;
        }
    }

    /// Stops every pixel whose 3×3 window's largest error ([`error`] of
    /// `beauty`'s sums, this rectangle's [`Tile`]) is below `threshold`.
    pub fn converge(&mut self, beauty: &Tile, threshold: f32) {
        let tw = self.width as usize;
        if tw == 0 {
            return;
        }
        let errors: Vec<f32> = self.px.iter().zip(beauty.sums()).map(|(p, a)| error(*a, p.odd)).collect();
        let th = errors.len() / tw;
        let mut active = 0;
        for y in 0..th {
            for x in 0..tw {
                let i = y * tw + x;
                if self.px[i].done {
                    continue;
                }
                let mut worst = 0.0f32;
                for wy in y.saturating_sub(1)..(y + 2).min(th) {
                    for wx in x.saturating_sub(1)..(x + 2).min(tw) {
                        worst = worst.max(errors[wy * tw + wx]);
                    }
                }
                // A NaN error (a NaN sample) never converges.
                if worst < threshold {
                    self.px[i].done = true;
                } else {
                    active += 1;
                }
            }
        }
        self.active = active;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_of_agreeing_halves_is_zero_and_scales_with_their_difference() {
        // Halves of 255 and 255: no difference.
        assert_eq!(error([510.0, 510.0, 510.0, 2.0], [255.0, 255.0, 255.0, 1.0]), 0.0);
        // Halves 0.5 and 1.5 (display units) in every channel: mean 1, so
        // (3 · 1) / 2 / √3.
        let e = error([WHITE, WHITE, WHITE, 1.0], [0.0; 4]);
        assert!(e.is_infinite(), "no odd sample yet");
        let all = [2.0 * WHITE, 2.0 * WHITE, 2.0 * WHITE, 2.0];
        let odd = [1.5 * WHITE, 1.5 * WHITE, 1.5 * WHITE, 1.0];
        let want = 1.5 / (0.0001 + 3f32.sqrt());
        assert!((error(all, odd) - want).abs() < 1e-5, "{}", error(all, odd));
        assert_eq!(auto_min_spp(0.01, 1024), 64);
        assert_eq!(auto_min_spp(0.01, 32), 32);
        assert_eq!(auto_min_spp(1.0, 1024), 16);
    }

    #[test]
    fn a_noisy_pixel_keeps_its_neighbours_going() {
        let rects = [(0, 0, 4, 1)];
        let (mut bs, mut st) = (Vec::new(), Vec::new());
        let mut beauty = Tile::all_in(&mut bs, &rects, Filter::Box).remove(0);
        let mut ad = AdaptiveTile::all_in(&mut st, &rects, Filter::Box).remove(0);
        for x in 0..4 {
            for s in 0..8 {
                // Pixel 3 alternates between 0 and 2 (display units); the others are flat.
                let v = if x == 3 { (s % 2) as f32 * 2.0 * WHITE } else { WHITE };
                beauty.add_sample(x, 0, 0.5, 0.5, Vec3::splat(v));
                ad.add(x, 0, s, 0.5, 0.5, Vec3::splat(v));
            }
        }
        ad.converge(&beauty, 0.01);
        assert_eq!([0, 1, 2, 3].map(|x| ad.active(x, 0)), [false, false, true, true]);
        assert_eq!(ad.active_count(), 2);
    }
}
