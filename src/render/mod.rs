//! Rendering: the render scene, cameras, the integrator, and the tiled,
//! multi-threaded loop that fills a [`Film`] with linear radiance.

pub mod camera;
pub mod dielectric;
pub mod integrator;
pub mod sampler;
pub mod scene;
pub mod volumes;

pub use scene::{BuildOptions, Scene};

pub use crate::film::Filter;

use crate::film::{Film, Tile};
use crate::math::Vec2;
use crate::shader::ShaderError;
use integrator::{radiance, PathState, RayStats};
use rayon::prelude::*;
use sampler::PixelSampler;
use std::sync::OnceLock;

/// Tile edge in pixels: small enough to balance two to sixty-four threads on
/// an 800×800 image, large enough that per-tile overhead vanishes.
pub const TILE: u32 = 16;

/// The top-left corners of the tiles of a `w`×`h` image, numbered row by
/// row: tile `i` of [`TileSelection`] is the `i`-th of these.
pub fn tile_origins(w: u32, h: u32) -> Vec<(u32, u32)> {
    (0..h.div_ceil(TILE)).flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx * TILE, ty * TILE))).collect()
}

/// Some of an image's tiles (numbered as by [`tile_origins`]): `first`,
/// `first + step`, ... below `end`. A render of a selection leaves the other
/// tiles black; the parts of a cluster render are selections
/// ([`crate::cluster`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileSelection {
    /// The first tile.
    pub first: u32,
    /// The distance between two selected tiles (at least 1).
    pub step: u32,
    /// One past the last tile that may be selected.
    pub end: u32,
}

impl TileSelection {
    /// Whether tile `i` is selected.
    pub fn contains(&self, i: u32) -> bool {
        i >= self.first && i < self.end && (i - self.first) % self.step.max(1) == 0
    }
}

/// A rendered image: the film (linear radiance) and the rays it took. What
/// files it becomes is the film's business ([`crate::film::outputs`]); it
/// dereferences to the [`Film`] for its size and pixels.
pub struct RenderedImage {
    /// The linear image.
    pub film: Film,
    /// Rays traced.
    pub stats: RayStats,
}

impl std::ops::Deref for RenderedImage {
    type Target = Film;
    fn deref(&self) -> &Film {
        &self.film
    }
}

/// Settings of a render beyond the scene's own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Samples per pixel instead of the camera's `NumSamples`.
    pub spp: Option<u32>,
    /// Changes every random choice (and so the noise) without changing the
    /// expected image.
    pub seed: u32,
    /// Reconstruction filter.
    pub filter: Filter,
    /// Only these tiles (`None`: all).
    pub tiles: Option<TileSelection>,
}

/// Renders camera `cam` of `scene` with default options on the current rayon
/// pool. `on_tile` is called with the number of pixels of every finished tile
/// (for progress bars).
pub fn render(scene: &Scene, cam: usize, on_tile: &(dyn Fn(u64) + Sync)) -> RenderedImage {
    render_with(scene, cam, &RenderOptions::default(), on_tile)
}

/// Renders camera `cam` of `scene` on the current rayon pool, ignoring shader
/// failures: a point whose shader fails is black, and the tiles not yet
/// started when it happened stay black. Use [`try_render_with`] to learn of
/// the failure; scenes without shaders cannot fail.
pub fn render_with(
    scene: &Scene,
    cam: usize,
    opts: &RenderOptions,
    on_tile: &(dyn Fn(u64) + Sync),
) -> RenderedImage {
    render_tiles(scene, cam, opts, on_tile, &OnceLock::new())
}

/// Renders camera `cam` of `scene` on the current rayon pool, or reports the
/// first shader failure (naming the shader, the script's `file:line` and the
/// object). After a failure the workers stop taking new tiles, so an error
/// ends the render within a tile's time.
///
/// One sample per pixel goes through the pixel centre (as the course's
/// single-sample images do); more are spread by the [`PixelSampler`]'s
/// stratified pattern. Every sample has its own lens position and shutter
/// time. The image depends only on the scene, the options and the sample
/// count, not on the number of threads.
pub fn try_render_with(
    scene: &Scene,
    cam: usize,
    opts: &RenderOptions,
    on_tile: &(dyn Fn(u64) + Sync),
) -> Result<RenderedImage, Box<ShaderError>> {
    let failed = OnceLock::new();
    let img = render_tiles(scene, cam, opts, on_tile, &failed);
    match failed.into_inner() {
        Some(e) => Err(e),
        None => Ok(img),
    }
}

/// The tiled render loop; the first shader failure goes into `failed`, and
/// from then on tiles are skipped. Checking it costs one atomic load per tile
/// and per row, and nothing per sample unless a path failed.
fn render_tiles(
    scene: &Scene,
    cam: usize,
    opts: &RenderOptions,
    on_tile: &(dyn Fn(u64) + Sync),
    failed: &OnceLock<Box<ShaderError>>,
) -> RenderedImage {
    let camera = &scene.cameras[cam];
    let spp = opts.spp.unwrap_or(camera.num_samples).max(1);
    let (w, h) = (camera.width, camera.height);
    let spread = camera.pixel_spread();
    let view = camera.view();
    let mut tiles = tile_origins(w, h);
    if let Some(sel) = opts.tiles {
        tiles =
            tiles.into_iter().enumerate().filter(|&(i, _)| sel.contains(i as u32)).map(|(_, t)| t).collect();
    }
    let done: Vec<(Tile, RayStats)> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
            let mut stats = RayStats::default();
            let mut tile = Tile::new(x0, y0, x1, y1, opts.filter);
            'rows: for y in y0..y1 {
                if failed.get().is_some() {
                    break;
                }
                for x in x0..x1 {
                    for s in 0..spp {
                        let mut sampler = PixelSampler::new(opts.seed, x, y, s, spp);
                        let (jx, jy) = if spp == 1 { (0.5, 0.5) } else { sampler.next_2d() };
                        let lens = sampler.next_2d();
                        let time = sampler.next_1d();
                        let ray = camera.lens_ray(x as f32 + jx, y as f32 + jy, lens);
                        let screen = Vec2::new((x as f32 + jx) / w as f32, (y as f32 + jy) / h as f32);
                        let mut st = PathState::new(stats, time, sampler).for_pixel(screen, spread);
                        (st.pixel, st.view) = ([x, y], view);
                        st.stats.primary += 1;
                        let l = radiance(scene, &ray, 0, 1.0, &mut st);
                        tile.add_sample(x, y, jx, jy, l);
                        stats = st.stats;
                        if let Some(e) = st.error {
                            let _ = failed.set(e);
                            break 'rows;
                        }
                    }
                }
            }
            on_tile(tile.len() as u64);
            (tile, stats)
        })
        .collect();
    let mut film = Film::new(w, h);
    let mut stats = RayStats::default();
    for (tile, s) in &done {
        film.merge(tile);
        stats.add(s);
    }
    RenderedImage { film, stats }
}
