//! Rendering: the render scene, cameras, and the tiled, multi-threaded loop
//! that fills a [`Film`] with linear radiance from the camera's integrator
//! ([`crate::integrator`]).
//!
//! The samples of a pixel are taken in passes: every tile gets the first
//! sample, then the next, then two more, four, ... (at most an eighth of the
//! count at a time), so a long render is refined evenly over the image, its
//! progress gives a fair estimate of the time left, and a time limit
//! ([`RenderOptions::time_limit`]) can stop it between two passes with every
//! pixel at the same sample count. A pixel's samples are summed in the same
//! order whatever the passes and the threads, so the image's bytes depend
//! only on the scene, the options and the samples taken.
//!
//! Render passes ([`RenderOptions::passes`], [`crate::film::aov`]) and
//! adaptive sampling ([`RenderOptions::adaptive`], [`crate::film::adaptive`])
//! each choose another instantiation of the tile loop once per render, so a
//! render without them runs the loop it always ran. Adaptive sampling
//! decides between passes, from each tile's own pixels: a pixel that stops
//! keeps the samples it has, and the others go on with the next pass.

pub mod camera;
pub mod sampler;
pub mod scene;

pub use scene::{BuildOptions, Scene};

pub use crate::film::Filter;

use crate::film::adaptive::{auto_min_spp, Adaptive, AdaptiveTile};
use crate::film::aov::{AovTile, Aovs, Passes};
use crate::film::reserve::FilmMemory;
use crate::film::{Film, FilmReserve, Tile};
use crate::integrator::{Integrator, PathState, RayStats};
use luster_core::math::{Ray, Vec2, Vec3};
use luster_shading::shader::{with_tracer, ShaderError};
use rayon::prelude::*;
use sampler::{PixelSampler, MIN_BATCH_RUN};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Tile edge in pixels of a `w`×`h` image: 16, small enough to balance two
/// to sixty-four threads on an 800×800 image and large enough that per-tile
/// overhead vanishes; 8 where the image has fewer than 256 tiles of 16
/// (below about 256×256), where the last tiles of each pass would leave
/// threads idle (a 64×64 Cornell box: two threads 1.6× one with 16 tiles,
/// 1.9× with 64). It depends on the image alone, never on the threads, so
/// the bytes and a split render's parts do not either.
pub fn tile_size(w: u32, h: u32) -> u32 {
    if u64::from(w.div_ceil(16)) * u64::from(h.div_ceil(16)) >= 256 {
        16
    } else {
        8
    }
}

/// The top-left corners of the tiles of a `w`×`h` image ([`tile_size`]),
/// numbered row by row: tile `i` of [`TileSelection`] is the `i`-th of these.
pub fn tile_origins(w: u32, h: u32) -> Vec<(u32, u32)> {
    let t = tile_size(w, h);
    (0..h.div_ceil(t)).flat_map(|ty| (0..w.div_ceil(t)).map(move |tx| (tx * t, ty * t))).collect()
}

/// The pixels of the tile at `(x0, y0)` of a `w`×`h` image: its corners,
/// the far one excluded.
pub fn tile_rect(w: u32, h: u32, (x0, y0): (u32, u32)) -> (u32, u32, u32, u32) {
    let t = tile_size(w, h);
    (x0, y0, (x0 + t).min(w), (y0 + t).min(h))
}

/// Some of an image's tiles (numbered as by [`tile_origins`]): `first`,
/// `first + step`, ... below `end`. A render of a selection leaves the other
/// tiles black; the parts of a cluster render are selections
/// (`luster::cluster`).
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
/// files it becomes is the film's business ([`luster_core::image::outputs`]); it
/// dereferences to the [`Film`] for its size and pixels.
pub struct RenderedImage {
    /// The linear image.
    pub film: Film,
    /// Rays traced.
    pub stats: RayStats,
    /// Samples per pixel taken (fewer than asked when a time limit stopped
    /// the render); with adaptive sampling, by the pixels that took most.
    pub spp: u32,
    /// Samples per pixel taken on average over the pixels rendered.
    pub mean_spp: f64,
    /// The render passes asked for ([`RenderOptions::passes`]).
    pub aovs: Option<Aovs>,
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
    /// Stop after the pass during which this much time has gone by, or before
    /// a pass that would end after it (at least one sample per pixel is taken).
    pub time_limit: Option<Duration>,
    /// Samples per pixel instead of the camera's `NumSamples`.
    pub spp: Option<u32>,
    /// Changes every random choice (and so the noise) without changing the
    /// expected image.
    pub seed: u32,
    /// Reconstruction filter.
    pub filter: Filter,
    /// Only these tiles (`None`: all).
    pub tiles: Option<TileSelection>,
    /// This integrator instead of the one the camera asks for.
    pub integrator: Option<Integrator>,
    /// Render passes to record beside the image (none: no cost).
    pub passes: Passes,
    /// Adaptive sampling; the threshold, when given, replaces the camera's
    /// `<NoiseThreshold>`.
    pub adaptive: Adaptive,
}

impl RenderOptions {
    /// The noise threshold and minimum samples of adaptive sampling of
    /// `camera` at `spp` samples, or `None` when it is off.
    pub fn adaptive_for(&self, camera: &camera::Camera, spp: u32) -> Option<(f32, u32)> {
        let t = self.adaptive.threshold.or(camera.noise_threshold).filter(|&t| t > 0.0)?;
        let min = self.adaptive.min_spp.unwrap_or_else(|| auto_min_spp(t, spp));
        // Two samples at least: the error compares two halves.
        Some((t, min.clamp(2, spp.max(2))))
    }
}

/// Units of work in rendering camera `cam` with `opts`: pixels times samples.
/// `on_tile` callbacks add up to this (for progress bars).
pub fn work(scene: &Scene, cam: usize, opts: &RenderOptions) -> u64 {
    let c = &scene.cameras[cam];
    u64::from(c.width) * u64::from(c.height) * u64::from(opts.spp.unwrap_or(c.num_samples).max(1))
}

/// Renders camera `cam` of `scene` with default options on the current rayon
/// pool. `on_tile` is called with the pixel samples of every finished tile
/// pass (see [`work`]; for progress bars).
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
    render_tiles(scene, cam, opts, on_tile, &OnceLock::new(), None, FilmMemory::default())
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
    try_render_reserved(scene, cam, opts, on_tile, None)
}

/// [`try_render_with`], in the memory `reserve` wrote ahead if it is this
/// camera's size ([`FilmReserve`]).
pub fn try_render_reserved(
    scene: &Scene,
    cam: usize,
    opts: &RenderOptions,
    on_tile: &(dyn Fn(u64) + Sync),
    reserve: Option<&FilmReserve>,
) -> Result<RenderedImage, Box<ShaderError>> {
    let failed = OnceLock::new();
    let camera = &scene.cameras[cam];
    let memory = reserve.map(|r| r.take(camera.width, camera.height, opts.passes)).unwrap_or_default();
    let img = render_tiles(scene, cam, opts, on_tile, &failed, None, memory);
    match failed.into_inner() {
        Some(e) => Err(e),
        None => Ok(img),
    }
}

/// A caller following a render pass by pass (`luster watch`).
pub struct Progress<'a> {
    /// Stops the render, within a row of a tile, once set (by any thread);
    /// the image returned then holds a partial pass and is to be dropped.
    pub cancel: &'a AtomicBool,
    /// Called on the calling thread after every finished pass with the
    /// image so far and the samples per pixel in it.
    pub on_pass: &'a mut dyn FnMut(&Film, u32),
}

/// [`try_render_with`], showing every finished pass to `progress` and
/// stopping early when it is cancelled.
pub fn render_progressive(
    scene: &Scene,
    cam: usize,
    opts: &RenderOptions,
    progress: Progress<'_>,
) -> Result<RenderedImage, Box<ShaderError>> {
    let failed = OnceLock::new();
    let img = render_tiles(scene, cam, opts, &|_| {}, &failed, Some(progress), FilmMemory::default());
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
    mut progress: Option<Progress<'_>>,
    memory: FilmMemory,
) -> RenderedImage {
    let cancel = progress.as_ref().map(|p| p.cancel);
    let stop = || failed.get().is_some() || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    let start = Instant::now();
    let camera = &scene.cameras[cam];
    let integrator = opts.integrator.unwrap_or_else(|| Integrator::from_desc(&camera.renderer));
    let spp = opts.spp.unwrap_or(camera.num_samples).max(1);
    let (w, h) = (camera.width, camera.height);
    let spread = camera.pixel_spread();
    let view = camera.view();
    let uses_time = scene.uses_shutter_time();
    let mut origins = tile_origins(w, h);
    if let Some(sel) = opts.tiles {
        origins = origins
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| sel.contains(i as u32))
            .map(|(_, t)| t)
            .collect();
    }
    let rects: Vec<(u32, u32, u32, u32)> = origins.into_iter().map(|o| tile_rect(w, h, o)).collect();
    let (mut store, pixels) = (memory.store.unwrap_or_default(), memory.pixels);
    let mut aov_store = memory.aov.unwrap_or_default();
    let mut adaptive_store = Vec::new();
    let passes = opts.passes;
    let adaptive = opts.adaptive_for(camera, spp);
    let mut aov_tiles = match passes.is_empty() {
        true => Vec::new(),
        false => AovTile::all_in(&mut aov_store, &rects, opts.filter, passes),
    }
    .into_iter();
    let mut adaptive_tiles = match adaptive {
        None => Vec::new(),
        Some(_) => AdaptiveTile::all_in(&mut adaptive_store, &rects, opts.filter),
    }
    .into_iter();
    let mut tiles: Vec<Work> = Tile::all_in(&mut store, &rects, opts.filter)
        .into_iter()
        .map(|tile| Work {
            tile,
            aov: aov_tiles.next(),
            adaptive: adaptive_tiles.next(),
            stats: RayStats::default(),
            samples: 0,
        })
        .collect();
    let pass_floor = if progress.is_some() { 1 } else { BATCH_PASS };
    let mut taken = 0;
    // Tiles with pixels still sampled (without adaptive sampling, all).
    let mut active = usize::MAX;
    while taken < spp && active > 0 && !stop() {
        let n = pass_size(taken, spp, pass_floor);
        if let (Some(limit), true) = (opts.time_limit, taken > 0) {
            // Stop if this pass would end after the limit, at the pace so far.
            let per_sample = start.elapsed().as_secs_f64() / f64::from(taken);
            if start.elapsed().as_secs_f64() + per_sample * f64::from(n) > limit.as_secs_f64() {
                break;
            }
        }
        // One tile per rayon job: with rayon's default splitting a worker
        // runs a run of hundreds of neighbouring tiles as one job, and on a
        // scene whose cost sits in a few rows (one object in the middle of
        // the frame, as in hw4 sphere_perlin_bump) the other worker would
        // idle through that job's tail.
        let pass = Pass {
            scene,
            integrator,
            look: Look { camera, spp, uses_time, w, h },
            seed: opts.seed,
            spread,
            view,
            samples: taken..taken + n,
            failed,
        };
        let run = |work: &mut Work| {
            // The loop for what this render records, chosen once per render;
            // the shaders it calls cast their rays into this scene.
            let done = with_tracer(scene, || match (passes.is_empty(), adaptive.is_some()) {
                (true, false) => pass.tile::<false, false>(work, &stop),
                (false, false) => pass.tile::<true, false>(work, &stop),
                (true, true) => pass.tile::<false, true>(work, &stop),
                (false, true) => pass.tile::<true, true>(work, &stop),
            });
            on_tile(done as u64 * u64::from(n));
        };
        tiles.par_iter_mut().with_max_len(1).for_each(run);
        taken += n;
        if let Some((threshold, min_spp)) = adaptive {
            if taken >= min_spp {
                tiles.par_iter_mut().for_each(|w| {
                    if let Some(a) = &mut w.adaptive {
                        a.converge(&w.tile, threshold);
                    }
                });
            }
            active =
                tiles.iter().filter(|w| w.adaptive.as_ref().is_none_or(|a| a.active_count() > 0)).count();
        }
        if let (Some(p), false) = (progress.as_mut(), stop()) {
            (p.on_pass)(&merged(w, h, &tiles, None), taken);
        }
    }
    let mut stats = RayStats::default();
    let (mut samples, mut rendered) = (0u64, 0u64);
    for t in &tiles {
        stats.add(&t.stats);
        samples += t.samples;
        rendered += t.tile.len() as u64;
    }
    let film = merged(w, h, &tiles, pixels);
    let aovs = (!passes.is_empty()).then(|| {
        let mut out = Aovs::new(w, h, passes);
        for t in &tiles {
            if let Some(a) = &t.aov {
                a.write(&t.tile, &mut out);
            }
        }
        out
    });
    drop(tiles);
    // Unmapping the accumulators would hold up the thread that goes on to
    // encode the image: a free worker does it. On
    // one thread it would wait for the end of the command, every camera's
    // store held till then.
    if rayon::current_num_threads() > 1 {
        rayon::spawn(move || drop((store, aov_store, adaptive_store)));
    }
    let mean_spp = if rendered > 0 { samples as f64 / rendered as f64 } else { 0.0 };
    RenderedImage { film, stats, spp: taken, mean_spp, aovs }
}

/// One tile of a render: its film accumulators, its passes' and adaptive
/// state where the render has them, the rays it traced and the samples it
/// took.
struct Work<'a> {
    tile: Tile<'a>,
    aov: Option<AovTile<'a>>,
    adaptive: Option<AdaptiveTile<'a>>,
    stats: RayStats,
    samples: u64,
}

/// What the tiles of one pass share: the scene, the integrator, the camera
/// and the range of samples this pass takes of every pixel.
struct Pass<'a> {
    scene: &'a Scene,
    integrator: Integrator,
    look: Look<'a>,
    seed: u32,
    spread: f32,
    view: crate::texture::View,
    samples: std::ops::Range<u32>,
    /// The first shader failure of the render (see [`render_tiles`]).
    failed: &'a OnceLock<Box<ShaderError>>,
}

impl Pass<'_> {
    /// Takes this pass's samples of every pixel of the tile that still
    /// takes samples, adding the rays traced to its count, and, with `AOV`,
    /// its passes' first-hit records; with `ADAPTIVE`, skipping the pixels
    /// that stopped and adding to the odd half of the others. Between rows,
    /// stops once `stop` says so. Returns the pixels sampled.
    fn tile<const AOV: bool, const ADAPTIVE: bool>(
        &self,
        work: &mut Work,
        stop: &impl Fn() -> bool,
    ) -> usize {
        let Work { tile, aov, adaptive, stats, samples: taken } = work;
        let (scene, integrator, look, samples) = (self.scene, self.integrator, &self.look, &self.samples);
        let (seed, spp) = (self.seed, look.spp);
        if samples.start == 0 {
            // Written first: see `Tile::clear`.
            tile.clear();
            if let Some(a) = aov {
                a.clear();
            }
        }
        if ADAPTIVE && adaptive.as_ref().is_some_and(|a| a.active_count() == 0) {
            return 0;
        }
        let mut sampled = 0;
        let (x0, y0, x1, y1) = tile.bounds();
        // One state for the tile, readied per sample: the view, spread
        // and counts carry over.
        let first = PixelSampler::new(seed, x0, y0, 0, spp);
        let mut st = PathState::new(*stats, 0.0, first).for_pixel(Vec2::ZERO, self.spread);
        st.view = self.view;
        // The second of two samples traced together (see
        // `Integrator::radiance_pair`); its counts join the tile's.
        let mut st2 = PathState::new(RayStats::default(), 0.0, first).for_pixel(Vec2::ZERO, self.spread);
        st2.view = self.view;
        let pairs = integrator.pairs();
        'rows: for y in y0..y1 {
            if stop() {
                break;
            }
            for x in x0..x1 {
                if ADAPTIVE && adaptive.as_ref().is_some_and(|a| !a.active(x, y)) {
                    continue;
                }
                sampled += 1;
                st.sampler = PixelSampler::new(seed, x, y, 0, spp).batched(samples.clone());
                st2.sampler = st.sampler;
                let mut s = samples.start;
                // Two samples at a time where the integrator follows
                // two paths in step, added in their order.
                while pairs && s + 1 < samples.end {
                    let (ra, jxa, jya) = look.sample(&mut st, x, y, s);
                    let (rb, jxb, jyb) = look.sample(&mut st2, x, y, s + 1);
                    let [la, lb] = integrator.radiance_pair(scene, [&ra, &rb], &mut st, &mut st2);
                    tile.add_sample(x, y, jxa, jya, la);
                    tile.add_sample(x, y, jxb, jyb, lb);
                    if let (true, Some(a)) = (AOV, aov.as_mut()) {
                        a.add(x, y, jxa, jya, &crate::integrator::aov::first_hit(scene, &ra, &mut st));
                        a.add(x, y, jxb, jyb, &crate::integrator::aov::first_hit(scene, &rb, &mut st2));
                    }
                    if let (true, Some(a)) = (ADAPTIVE, adaptive.as_mut()) {
                        a.add(x, y, s, jxa, jya, la);
                        a.add(x, y, s + 1, jxb, jyb, lb);
                    }
                    if let Some(e) = st.error.take().or_else(|| st2.error.take()) {
                        let _ = self.failed.set(e);
                        break 'rows;
                    }
                    s += 2;
                }
                while s < samples.end {
                    let (ray, jx, jy) = look.sample(&mut st, x, y, s);
                    s += 1;
                    let l = integrator.radiance(scene, &ray, &mut st);
                    tile.add_sample(x, y, jx, jy, l);
                    if let (true, Some(a)) = (AOV, aov.as_mut()) {
                        a.add(x, y, jx, jy, &crate::integrator::aov::first_hit(scene, &ray, &mut st));
                    }
                    if let (true, Some(a)) = (ADAPTIVE, adaptive.as_mut()) {
                        a.add(x, y, s - 1, jx, jy, l);
                    }
                    if let Some(e) = st.error.take() {
                        let _ = self.failed.set(e);
                        break 'rows;
                    }
                }
            }
        }
        st.stats.add(&st2.stats);
        *stats = st.stats;
        *taken += sampled as u64 * (samples.end - samples.start) as u64;
        sampled
    }
}

/// What a camera sample needs of the camera being rendered.
struct Look<'a> {
    camera: &'a camera::Camera,
    spp: u32,
    uses_time: bool,
    w: u32,
    h: u32,
}

impl Look<'_> {
    /// Draws the camera's dimensions of sample `s` of pixel `(x, y)` and
    /// readies `st` for it: the camera ray and the pixel jitter. Inlined
    /// into the render loop: a call would weigh on scenes whose samples are
    /// cheap (the recursive tracer's hw4 scenes).
    #[inline(always)]
    fn sample(&self, st: &mut PathState, x: u32, y: u32, s: u32) -> (Ray, f32, f32) {
        st.sampler.restart(s);
        let sampler = &mut st.sampler;
        let (jx, jy) = if self.spp == 1 { (0.5, 0.5) } else { sampler.next_2d() };
        // A pinhole ignores the lens: its draw would cost a stratified
        // dimension for nothing.
        let lens = if self.camera.has_lens() { sampler.next_2d() } else { (0.5, 0.5) };
        // A scene where the time changes nothing skips its draw; the later
        // draws keep their dimensions.
        let time = if self.uses_time {
            sampler.next_1d()
        } else {
            sampler.skip();
            0.0
        };
        let ray = self.camera.lens_ray(x as f32 + jx, y as f32 + jy, lens);
        let screen = Vec2::new((x as f32 + jx) / self.w as f32, (y as f32 + jy) / self.h as f32);
        st.next_sample(time, screen, [x, y]);
        st.stats.primary += 1;
        (ray, jx, jy)
    }
}

/// The `w`×`h` film of `tiles`, which are in the row-major order of
/// [`tile_origins`]. Filled in parallel, a band of tile rows per job: done
/// serially, zeroing the film (faulting its pages in) and copying the tiles
/// into it after the render had ended would be the largest serial part of
/// a small render. Each pixel is written by its one
/// tile, so the bytes are those of a serial merge. `zeroed`, of the film's
/// size, is used instead of a new buffer (memory written ahead,
/// [`FilmReserve`]).
fn merged(w: u32, h: u32, tiles: &[Work], zeroed: Option<Vec<Vec3>>) -> Film {
    let tile = tile_size(w, h);
    let band = (w as usize * tile as usize).max(1);
    let n = w as usize * h as usize;
    let mut pixels: Vec<Vec3> = match zeroed {
        Some(p) if p.len() == n => p,
        _ => (0..n).into_par_iter().with_min_len(band).map(|_| Vec3::ZERO).collect(),
    };
    pixels.par_chunks_mut(band).enumerate().for_each(|(b, rows)| {
        let y0 = b as u32 * tile;
        let first = tiles.partition_point(|t| t.tile.bounds().1 < y0);
        let end = tiles.partition_point(|t| t.tile.bounds().1 < y0 + tile);
        for t in &tiles[first..end] {
            t.tile.write_rows(rows, w as usize, y0);
        }
    });
    Film { width: w, height: h, pixels }
}

/// Samples per pixel of the pass after `taken` of `spp`: 1, 1, 2, 4, ...,
/// at most an eighth of `spp` (or `floor`, where that is more), never past
/// it. A plain render (`floor` above 1) leaves no last pass too short for
/// the sampler to batch ([`MIN_BATCH_RUN`]) after its first: 4 samples
/// make passes of 1 and 3, not 1, 1 and 2, none of which would be batched.
fn pass_size(taken: u32, spp: u32, floor: u32) -> u32 {
    let cap = spp.div_ceil(8).max(floor);
    let n = taken.max(1).min(cap).min(spp - taken);
    let rest = spp - taken - n;
    if floor == 1 || taken == 0 || rest == 0 || rest >= MIN_BATCH_RUN {
        return n;
    }
    let left = spp - taken;
    if left <= cap {
        left
    } else {
        left - MIN_BATCH_RUN
    }
}

/// How long a pass may always grow when nobody watches the passes (only
/// `--time` and the ETA use them): a pixel's samples of one pass are what
/// the sampler batches (sixteen lanes, runs of three or more), and an
/// eighth of 16 or 100 samples (passes of 2 or 13) would leave its lanes idle. A
/// preview (`luster watch`) keeps its finer steps.
const BATCH_PASS: u32 = 16;

#[cfg(test)]
mod tests {
    use super::*;

    /// The parallel merge puts every sampled pixel of every tile given where
    /// it belongs, leaves unsampled pixels and missing tiles black, and
    /// handles sizes that are not multiples of the tile edge.
    #[test]
    fn merged_film_holds_each_tiles_pixels() {
        let (w, h) = (37, 45);
        let value = |x: u32, y: u32| Vec3::new(x as f32, y as f32, (x * 7 + y) as f32 * 0.25);
        let sel = TileSelection { first: 1, step: 2, end: 100 };
        let rects: Vec<_> = tile_origins(w, h)
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| sel.contains(i as u32))
            .map(|(_, o)| tile_rect(w, h, o))
            .collect();
        let mut store = Vec::new();
        let mut tiles = Vec::new();
        for mut t in Tile::all_in(&mut store, &rects, Filter::Box) {
            let (x0, y0, x1, y1) = t.bounds();
            for y in y0..y1 {
                for x in x0..x1 {
                    if (x + y) % 5 != 0 {
                        // Two samples: the pixel is their average.
                        t.add_sample(x, y, 0.5, 0.5, value(x, y) * 0.5);
                        t.add_sample(x, y, 0.5, 0.5, value(x, y) * 1.5);
                    }
                }
            }
            tiles.push(Work { tile: t, aov: None, adaptive: None, stats: RayStats::default(), samples: 0 });
        }
        let film = merged(w, h, &tiles, None);
        assert_eq!((film.width, film.height, film.pixels.len()), (w, h, (w * h) as usize));
        // In memory written ahead (zeroed), or in a buffer of the wrong size
        // (replaced): the same film.
        for zeroed in [vec![Vec3::ZERO; (w * h) as usize], vec![Vec3::ONE; 3]] {
            assert_eq!(merged(w, h, &tiles, Some(zeroed)).pixels, film.pixels);
        }
        let t = tile_size(w, h);
        let per_row = w.div_ceil(t);
        for y in 0..h {
            for x in 0..w {
                let tile = (y / t) * per_row + x / t;
                let want = if sel.contains(tile) && (x + y) % 5 != 0 { value(x, y) } else { Vec3::ZERO };
                assert_eq!(film.pixels[(y * w + x) as usize], want, "pixel ({x}, {y})");
            }
        }
        assert!(merged(0, 0, &[], None).pixels.is_empty());
    }

    /// Passes cover the samples exactly; a preview grows to an eighth of
    /// them, a plain render to a sampler batch at least.
    #[test]
    fn passes_cover_the_samples_and_grow_to_their_cap() {
        let passes = |spp: u32, floor: u32| {
            let (mut taken, mut out) = (0, Vec::new());
            while taken < spp {
                let n = pass_size(taken, spp, floor);
                out.push(n);
                taken += n;
            }
            out
        };
        assert_eq!(passes(16, 1), [1, 1, 2, 2, 2, 2, 2, 2, 2]);
        assert_eq!(passes(16, BATCH_PASS), [1, 1, 2, 4, 8]);
        assert_eq!(passes(100, BATCH_PASS), [1, 1, 2, 4, 8, 16, 16, 16, 16, 16, 4]);
        assert_eq!(passes(900, BATCH_PASS)[..8], [1, 1, 2, 4, 8, 16, 32, 64]);
        assert_eq!(passes(4, BATCH_PASS), [1, 3]);
        assert_eq!(passes(4, 1), [1, 1, 1, 1]);
        assert_eq!(passes(50, BATCH_PASS), [1, 1, 2, 4, 8, 16, 15, 3]);
        for spp in 1..300 {
            for floor in [1, BATCH_PASS] {
                let p = passes(spp, floor);
                assert_eq!(p.iter().sum::<u32>(), spp);
                assert!(p.iter().all(|&n| n >= 1 && n <= spp.div_ceil(8).max(floor)));
                assert_eq!(p[0], 1);
            }
            // A plain render's last pass batches, unless the first pass left too few.
            let last = *passes(spp, BATCH_PASS).last().unwrap();
            assert!(last >= MIN_BATCH_RUN.min(spp - 1).max(1), "{spp}: {:?}", passes(spp, BATCH_PASS));
        }
    }
}
