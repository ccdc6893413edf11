//! Rendering one part of one image into its part file, with checkpoints.
//!
//! With `resume`, a finished part file of the same job is kept as it is, and
//! a checkpoint of the same job is continued: the part's tiles are rendered
//! in chunks, in order, and after a chunk that ends at least
//! `checkpoint_every` after the last save the tiles done so far are written
//! (atomically) to `<image>.part-K-of-N.checkpoint`. A render killed at any
//! moment so loses at most that long of work, and since every pixel is
//! deterministic the resumed part file is the one an uninterrupted render
//! writes.

use super::partfile::{tile_rect, PartFile, MAX_FILE};
use super::{checkpoint_path, part_path, selected, ClusterError, JobId, Part};
use luster_core::math::Vec3;
use luster_render::film::Film;
use luster_render::integrator::RayStats;
use luster_render::render::{try_render_with, RenderOptions, Scene, TileSelection};
use std::path::Path;
use std::time::{Duration, Instant};

/// One part of one image of a job.
pub struct PartJob<'a> {
    /// The job.
    pub job: JobId,
    /// Which part.
    pub part: Part,
    /// Images in the job.
    pub images: u32,
    /// This image's number, from 0.
    pub image: u32,
    /// The part's tiles of this image (from [`super::share`]).
    pub tiles: TileSelection,
    /// The output folder.
    pub outdir: &'a Path,
    /// Keep finished part files and continue checkpoints of the same job.
    pub resume: bool,
    /// Least time between two checkpoints (with `resume`).
    pub checkpoint_every: Duration,
}

/// How a part ended.
#[derive(Debug)]
pub enum Outcome {
    /// The part file of this job was already there (with `resume`).
    AlreadyDone,
    /// Rendered: `resumed` of the `tiles` tiles came from a checkpoint.
    Rendered {
        /// Tiles taken from a checkpoint.
        resumed: usize,
        /// Tiles of the part.
        tiles: usize,
        /// Rays traced now.
        stats: RayStats,
    },
}

/// Renders part `pj` of camera `cam` and writes its part file; warnings
/// (a stale checkpoint set aside) go to `warn`.
pub fn render_part(
    scene: &Scene,
    cam: usize,
    opts: &RenderOptions,
    pj: &PartJob,
    on_tile: &(dyn Fn(u64) + Sync),
    warn: &mut dyn FnMut(String),
) -> Result<Outcome, ClusterError> {
    let camera = &scene.cameras[cam];
    let (w, h) = (camera.width, camera.height);
    let mine = selected(pj.tiles);
    let final_path = part_path(pj.outdir, &camera.image_name, pj.part);
    let ckpt_path = checkpoint_path(pj.outdir, &camera.image_name, pj.part);
    let template = PartFile {
        finished: false,
        job: pj.job.0,
        n: pj.part.n,
        k: pj.part.k,
        images: pj.images,
        image: pj.image,
        width: w,
        height: h,
        image_name: camera.image_name.clone(),
        tonemaps: camera.tonemaps.clone(),
        display: camera.display,
        tiles: Vec::new(),
        pixels: Vec::new(),
        passes: opts.passes,
        aov: Vec::new(),
    };
    let same_job = |f: &PartFile| {
        let mut a = f.clone();
        a.finished = false;
        a.tiles.clear();
        a.pixels.clear();
        a.aov.clear();
        a == template
    };
    let mut file = template.clone();
    if pj.resume {
        if present(&final_path)? {
            match PartFile::read(&final_path) {
                Ok(f) if f.finished && same_job(&f) && f.tiles == mine => return Ok(Outcome::AlreadyDone),
                Ok(_) => warn(format!("{} is from another render; rendering it again", final_path.display())),
                Err(e) => warn(format!("{e}; rendering it again")),
            }
        }
        if present(&ckpt_path)? {
            match PartFile::read(&ckpt_path) {
                Ok(f) if !f.finished && same_job(&f) && mine.starts_with(&f.tiles) => file = f,
                Ok(_) => {
                    warn(format!("{} is from another render; starting the part over", ckpt_path.display()))
                }
                Err(e) => warn(format!("{e}; starting the part over")),
            }
        }
    }
    let resumed = file.tiles.len();
    let remaining = &mine[resumed..];
    // Without checkpoints one pass over the part's tiles; with them, chunks
    // big enough to keep every thread busy, and at most 64 of them, since
    // each pass allocates a whole film.
    let chunk = if pj.resume {
        (16 * rayon::current_num_threads()).max(mine.len().div_ceil(64)).max(1)
    } else {
        remaining.len().max(1)
    };
    let mut stats = RayStats::default();
    let mut saved = Instant::now();
    let chunks: Vec<&[u32]> = remaining.chunks(chunk).collect();
    for (ci, c) in chunks.iter().enumerate() {
        let sel = TileSelection { first: c[0], step: pj.tiles.step, end: c[c.len() - 1] + 1 };
        let img = try_render_with(scene, cam, &RenderOptions { tiles: Some(sel), ..*opts }, on_tile)
            .map_err(|e| ClusterError(e.to_string()))?;
        stats.add(&img.stats);
        for &t in c.iter() {
            file.tiles.push(t);
            push_tile(&mut file.pixels, &img.film, tile_rect(t, w, h));
            if let Some(aovs) = &img.aovs {
                aovs.push_rect(&mut file.aov, tile_rect(t, w, h));
            }
        }
        let last = ci + 1 == chunks.len();
        if pj.resume && !last && saved.elapsed() >= pj.checkpoint_every {
            file.write(&ckpt_path)?;
            saved = Instant::now();
        }
    }
    file.finished = true;
    file.write(&final_path)?;
    if ckpt_path.exists() {
        std::fs::remove_file(&ckpt_path).map_err(|e| {
            ClusterError(format!(
                "{}: cannot remove the checkpoint: {}",
                ckpt_path.display(),
                luster_core::file::io_reason(&e)
            ))
        })?;
    }
    Ok(Outcome::Rendered { resumed, tiles: mine.len(), stats })
}

/// Whether a part file or checkpoint to resume from is at `path`. A FIFO, a
/// device or a folder there is an error rather than a file to set aside:
/// luster never makes one, and reading it could block or never end.
fn present(path: &Path) -> Result<bool, ClusterError> {
    match std::fs::metadata(path) {
        // A dangling link too: the new file replaces the link.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        _ => luster_core::file::check_regular(path, MAX_FILE)
            .map(|_| true)
            .map_err(|why| ClusterError(format!("{}: cannot resume from it: {why}", path.display()))),
    }
}

/// Appends the pixels of rectangle `(x0, y0, x1, y1)` of `film`, row by row.
pub fn push_tile(out: &mut Vec<Vec3>, film: &Film, (x0, y0, x1, y1): (u32, u32, u32, u32)) {
    let w = film.width as usize;
    for y in y0..y1 {
        let row = y as usize * w;
        out.extend_from_slice(&film.pixels[row + x0 as usize..row + x1 as usize]);
    }
}

/// Writes pixels taken by [`push_tile`] back into `film`.
pub fn pull_tile(film: &mut Film, pixels: &[Vec3], (x0, y0, x1, y1): (u32, u32, u32, u32)) {
    let w = film.width as usize;
    let tw = (x1 - x0) as usize;
    for (r, y) in (y0..y1).enumerate() {
        let row = y as usize * w + x0 as usize;
        film.pixels[row..row + tw].copy_from_slice(&pixels[r * tw..(r + 1) * tw]);
    }
}
