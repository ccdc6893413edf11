//! `luster render --part K/N [--resume]`: one part of a split render (see
//! `luster::cluster` for how images and tiles are shared out), written as
//! part files for `luster merge`.

use luster::cluster::part::{render_part, Outcome, PartJob};
use luster::cluster::{share, JobId, Part, MAX_IMAGES};
use luster::render::{tile_origins, BuildOptions, RenderOptions, Scene};
use luster::scene::hdri::Hdri;
use luster::scene::obj::ModelView;
use luster_core::text::shown;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Which part, and how it survives being killed.
pub struct Split {
    /// The part.
    pub part: Part,
    /// Keep finished part files and continue checkpoints.
    pub resume: bool,
    /// Least time between checkpoints.
    pub checkpoint: Duration,
}

/// The `ImageName`s of a scene's cameras, in order, from its element tree
/// alone: numbering the images must not cost every part a load of every
/// scene (the statue orbit is 360 scenes around a 2 MB mesh). A scene that
/// fails to load fails in the part that renders it.
fn image_names(path: &Path, view: &ModelView) -> anyhow::Result<Vec<String>> {
    if luster::scene::is_model(path) {
        return Ok(luster::scene::load_viewed(path, view)?
            .cameras
            .into_iter()
            .map(|c| c.image_name)
            .collect());
    }
    let root = luster::scene::element_tree(path)?;
    let cameras =
        root.child("Cameras").map(|c| c.children_named("Camera").collect::<Vec<_>>()).unwrap_or_default();
    Ok(cameras
        .iter()
        .map(|c| c.child("ImageName").map(|n| n.text.trim().to_string()).unwrap_or_default())
        .collect())
}

/// Renders this part's share of every image of `scenes`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    scenes: &[PathBuf],
    outdir: &Path,
    threads: Option<usize>,
    quiet: bool,
    opts: &RenderOptions,
    build: &BuildOptions,
    view: &ModelView,
    env: Option<&Hdri>,
    split: &Split,
) -> ExitCode {
    let pool = match super::args::pool(threads) {
        Ok(p) => p,
        Err(code) => return code,
    };
    match pool.install(|| run_in_pool(scenes, outdir, quiet, opts, build, view, env, split)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            super::report("error", &format_args!("{e:#}"));
            ExitCode::from(2)
        }
    }
}

#[allow(clippy::too_many_arguments)] // the command's options, passed through as given
fn run_in_pool(
    scenes: &[PathBuf],
    outdir: &Path,
    quiet: bool,
    opts: &RenderOptions,
    build: &BuildOptions,
    view: &ModelView,
    env: Option<&Hdri>,
    split: &Split,
) -> anyhow::Result<()> {
    let part = split.part;
    // Everything that changes a pixel is in the job id; the shader time limit
    // is not (a render it stops fails instead of writing a part).
    let options = format!(
        "spp={:?} seed={} filter={:?} view={view:?} env={env:?} aov={} adaptive={:?}",
        opts.spp,
        opts.seed,
        opts.filter,
        opts.passes.names(),
        opts.adaptive
    );
    let job = JobId::new(part.n, scenes, &options)?;
    // Every part numbers the images of the job alike, from every scene's
    // cameras; the names must not clash across scenes, since the parts of
    // all images share one folder.
    let mut counts = Vec::with_capacity(scenes.len());
    let mut names = Vec::new();
    for s in scenes {
        let own = image_names(s, view)?;
        counts.push(own.len() as u32);
        names.extend(own.into_iter().map(|n| (n, s.clone())));
    }
    let mut seen = std::collections::HashMap::new();
    for (name, scene) in &names {
        let key = luster::image::outputs::file_key(Path::new(name));
        if let Some(other) = seen.insert(key, scene) {
            anyhow::bail!(
                "{}: its image {name} is also written by {} (the images of one split render need distinct names)",
                scene.display(),
                other.display()
            );
        }
    }
    let images = counts.iter().map(|&c| u64::from(c)).sum::<u64>();
    if images > u64::from(MAX_IMAGES) {
        anyhow::bail!("the scenes hold {images} images; a split render holds at most {MAX_IMAGES}");
    }
    let images = images as u32;
    let mut first = 0u32;
    for (s, &count) in scenes.iter().zip(&counts) {
        let range = first..first + count;
        first += count;
        if images >= part.n && !range.clone().any(|i| i % part.n == part.k - 1) {
            continue;
        }
        let t0 = Instant::now();
        let mut desc = luster::scene::load_viewed(s, view)?;
        if let Some(env) = env {
            env.apply(&mut desc);
        }
        for w in &desc.warnings {
            super::report("warning", &format_args!("{}: {w}", s.display()));
        }
        if desc.cameras.len() as u32 != count {
            anyhow::bail!("{}: the scene changed while it was being rendered", s.display());
        }
        let scene = Scene::build_with(&desc, build)?;
        for w in &scene.warnings {
            super::report("warning", &format_args!("{}: {w}", s.display()));
        }
        let setup = t0.elapsed().as_secs_f64();
        for (cam, image) in range.enumerate() {
            let c = &scene.cameras[cam];
            let tiles = tile_origins(c.width, c.height).len() as u32;
            let Some(sel) = share(images, part, image, tiles) else { continue };
            let pj = PartJob {
                job,
                part,
                images,
                image,
                tiles: sel,
                outdir,
                resume: split.resume,
                checkpoint_every: split.checkpoint,
            };
            let t = Instant::now();
            let outcome = render_part(&scene, cam, opts, &pj, &|_| {}, &mut |w| super::report("warning", &w))
                .map_err(|e| anyhow::anyhow!("{}: {e}", s.display()))?;
            if quiet {
                continue;
            }
            let file = luster::cluster::part_path(outdir, &c.image_name, part).display().to_string();
            let file = shown(&file, false);
            match outcome {
                Outcome::AlreadyDone => println!("{file}  already finished"),
                Outcome::Rendered { resumed, tiles, .. } => println!(
                    "{file}  {tiles} tiles{}  {:.2} s render (+{setup:.2} s load and build)",
                    if resumed > 0 {
                        format!(" ({resumed} resumed from a checkpoint)")
                    } else {
                        String::new()
                    },
                    t.elapsed().as_secs_f64()
                ),
            }
        }
    }
    Ok(())
}
