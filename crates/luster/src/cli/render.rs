//! `luster render`: load (a scene, or an OBJ model in a scene made around it),
//! build, render every camera, write its files (see `luster::image::outputs`)
//! atomically.

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use luster::denoise::Denoiser;
use luster::film::aov::{aov_file_name, write_aov_exr, Pass};
use luster::film::write_outputs;
use luster::film::FilmReserve;
use luster::image::outputs::{first_clash, plan_outputs};
use luster::render::{self, BuildOptions, RenderOptions, RenderedImage, Scene};
use luster::scene::hdri::Hdri;
use luster::scene::obj::ModelView;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::Instant;

/// Renders every scene; errors in one scene do not stop the others.
#[allow(clippy::too_many_arguments)] // the command's options, passed through as given
pub fn run(
    scenes: &[PathBuf],
    outdir: &Path,
    threads: Option<usize>,
    quiet: bool,
    denoise: bool,
    opts: &RenderOptions,
    build: &BuildOptions,
    view: &ModelView,
    env: Option<&Hdri>,
    frame: &(Option<(u32, u32)>, super::reframe::FrameArgs),
) -> ExitCode {
    let pool = match super::args::pool(threads) {
        Ok(p) => p,
        Err(code) => return code,
    };
    // Started before any render, so a machine OIDN cannot run on fails at once.
    let denoiser = match denoise.then(|| Denoiser::new(pool.current_num_threads())).transpose() {
        Ok(d) => d.map(Mutex::new),
        Err(e) => {
            super::report("error", &format_args!("--denoise: {e}"));
            return ExitCode::from(2);
        }
    };
    let mut failed = 0;
    for s in scenes {
        let out = Output { dir: outdir, quiet, denoiser: denoiser.as_ref() };
        if let Err(e) = pool.install(|| render_scene(s, &out, opts, build, view, env, frame)) {
            super::report("error", &format_args!("{e:#}"));
            failed += 1;
        }
    }
    if failed > 0 {
        if scenes.len() > 1 {
            eprintln!("{failed} of {} scenes failed", scenes.len());
        }
        return ExitCode::from(2);
    }
    ExitCode::SUCCESS
}

/// Where and how a scene's images are written.
struct Output<'a> {
    dir: &'a Path,
    quiet: bool,
    /// Denoises each image before it is written (`--denoise`).
    denoiser: Option<&'a Mutex<Denoiser>>,
}

/// Renders every camera of one scene, then writes the images: a shader that
/// fails in any camera leaves no image of the scene behind.
#[allow(clippy::too_many_arguments)] // the command's options, passed through as given
fn render_scene(
    path: &Path,
    out: &Output,
    opts: &RenderOptions,
    build: &BuildOptions,
    view: &ModelView,
    env: Option<&Hdri>,
    frame: &(Option<(u32, u32)>, super::reframe::FrameArgs),
) -> anyhow::Result<()> {
    let (outdir, quiet) = (out.dir, out.quiet);
    // The denoiser reads the albedo and normal passes, whether or not
    // `--aov` asks to write them.
    let asked = opts.passes;
    let with_aux = RenderOptions { passes: asked.with(Pass::Albedo).with(Pass::Normal), ..*opts };
    let opts = if out.denoiser.is_some() { &with_aux } else { opts };
    let t0 = Instant::now();
    let obj = luster::scene::is_model(path);
    let mut desc = luster::scene::load_viewed(path, view)?;
    if let Some(env) = env {
        env.apply(&mut desc);
    }
    // A model's --size already made its camera; --scale and --crop apply to both.
    super::reframe::apply(&mut desc, if obj { None } else { frame.0 }, &frame.1)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let adaptive = opts.adaptive.threshold.or_else(|| desc.cameras.iter().find_map(|c| c.noise_threshold));
    let adaptive = adaptive.is_some_and(|t| t > 0.0);
    luster::film::check_memory_with(desc.cameras.iter().map(|c| c.resolution), opts.passes, adaptive)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    for w in &desc.warnings {
        super::report("warning", &format_args!("{}: {w}", path.display()));
    }
    // While the scene loads (an image decoding alone, say), a free worker
    // writes the first camera's film memory.
    let reserve =
        desc.cameras.first().map(|c| FilmReserve::start_with(c.resolution.0, c.resolution.1, opts.passes));
    let scene = Scene::build_with(&desc, build)?;
    for w in &scene.warnings {
        super::report("warning", &format_args!("{}: {w}", path.display()));
    }
    let plans = scene
        .cameras
        .iter()
        .map(|c| plan_outputs(&c.image_name, &c.tonemaps, c.display))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    // The passes' file of each camera, when passes are asked for.
    let aov_names: Vec<PathBuf> = match asked.is_empty() {
        true => Vec::new(),
        false => scene.cameras.iter().map(|c| aov_file_name(&c.image_name)).collect(),
    };
    let names =
        plans.iter().flatten().map(|o| o.name.as_path()).chain(aov_names.iter().map(PathBuf::as_path));
    if let Some(clash) = first_clash(names) {
        anyhow::bail!("{}: two outputs would be written to {}", path.display(), clash.display());
    }
    let setup = t0.elapsed().as_secs_f64();
    let mut done = Vec::with_capacity(scene.cameras.len());
    for (i, cam) in scene.cameras.iter().enumerate() {
        // Pixel samples, which passes finish evenly: the ETA holds from the first pass.
        let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(render::work(&scene, i, opts)) };
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed}<{eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(luster::text::shown(&cam.image_name, false).into_owned());
        let t = Instant::now();
        let reserve = if i == 0 { reserve.as_ref() } else { None };
        let img = render::try_render_reserved(&scene, i, opts, &|n| bar.inc(n), reserve);
        bar.finish_and_clear();
        let mut img = img.map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        let secs = t.elapsed().as_secs_f64();
        let denoised = match out.denoiser {
            Some(d) => Some(denoise(d, &mut img).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?),
            None => None,
        };
        done.push((img, secs, denoised));
    }
    let triangles = scene.triangle_count();
    // Freed by a free worker while the images are encoded, not after them
    // on the thread that ends the process (textures, meshes, trees).
    if rayon::current_num_threads() > 1 {
        rayon::spawn(move || drop((scene, desc)));
    }
    for (i, ((img, secs, denoised), plan)) in done.iter().zip(&plans).enumerate() {
        let mut written = write_outputs(&img.film, outdir, plan)
            .with_context(|| format!("rendering {}", path.display()))?;
        if let (Some(aovs), Some(aov_name)) = (&img.aovs, aov_names.get(i)) {
            let name = outdir.join(aov_name);
            write_aov_exr(&name, &img.film, aovs).with_context(|| format!("rendering {}", path.display()))?;
            written.push(name);
        }
        if !quiet {
            let names: Vec<String> = written
                .iter()
                .map(|p| luster::text::shown(&p.display().to_string(), false).into_owned())
                .collect();
            // Adaptive sampling's pixels took different counts: the mean, and the most.
            let spp = match img.mean_spp < f64::from(img.spp) {
                true => format!("{:.1} spp mean (max {})", img.mean_spp, img.spp),
                false => format!("{} spp", img.spp),
            };
            let denoised = denoised.map(|s| format!(" (+{s:.2} s denoise)")).unwrap_or_default();
            println!(
                "{}  {}x{}  {spp}  {:.2} s render{} (+{:.2} s load and build)  {:.1} Mrays/s  {} triangles",
                names.join(" + "),
                img.width,
                img.height,
                secs,
                denoised,
                setup,
                img.stats.total() as f64 / secs.max(1e-9) / 1e6,
                triangles
            );
        }
    }
    Ok(())
}

/// Replaces the image's beauty with its denoised version, guided by its
/// albedo and normal passes; returns the seconds it took.
fn denoise(denoiser: &Mutex<Denoiser>, img: &mut RenderedImage) -> Result<f64, String> {
    let t = Instant::now();
    // A poisoned lock only means another scene's denoise panicked; the device is still usable.
    let d = denoiser.lock().unwrap_or_else(|e| e.into_inner());
    let albedo = img.aovs.as_ref().and_then(|a| a.albedo());
    let normal = img.aovs.as_ref().and_then(|a| a.normal());
    let film = &img.film;
    let pixels = d.denoise(film.width, film.height, &film.pixels, albedo, normal)?;
    img.film.pixels = pixels;
    Ok(t.elapsed().as_secs_f64())
}
