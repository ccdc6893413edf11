//! The `luster` command line: a thin layer over the library.

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use luster::render::{self, Scene};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// luster — a ray tracer for CENG795 scenes and procedural shaders.
#[derive(Parser)]
#[command(version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render scenes (CENG795 XML or JSON); writes one image per camera.
    ///
    /// Each camera's image goes to OUTDIR/<ImageName>. Errors in one scene are
    /// reported and the others still render; the exit code is 2 if any failed.
    Render {
        /// Scene files (.xml or .json).
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Folder for the images (created if needed).
        #[arg(short, long, default_value = ".")]
        outdir: PathBuf,
        /// Worker threads (default: all cores).
        #[arg(short, long)]
        threads: Option<usize>,
        /// Print no progress bar and no summary, only errors and warnings.
        #[arg(short, long)]
        quiet: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Render { scenes, outdir, threads, quiet } => {
            let pool = match rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0)).build() {
                Ok(p) => p,
                Err(e) => {
                    eprintln!("error: cannot start worker threads: {e}");
                    return ExitCode::from(2);
                }
            };
            let mut failed = 0;
            for s in &scenes {
                if let Err(e) = pool.install(|| render_scene(s, &outdir, quiet)) {
                    eprintln!("error: {e:#}");
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
    }
}

fn render_scene(path: &Path, outdir: &Path, quiet: bool) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let desc = luster::scene::load(path)?;
    for w in &desc.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    let scene = Scene::build(&desc)?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    let setup = t0.elapsed().as_secs_f64();
    for (i, cam) in scene.cameras.iter().enumerate() {
        if cam.num_samples > 1 && !quiet {
            eprintln!(
                "warning: {}: {} asks for {} samples per pixel; multisampling is not supported yet, rendering 1",
                path.display(),
                cam.image_name,
                cam.num_samples
            );
        }
        let pixels = u64::from(cam.width) * u64::from(cam.height);
        let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(pixels) };
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed}<{eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(cam.image_name.clone());
        let t = Instant::now();
        let img = render::render(&scene, i, &|n| bar.inc(n));
        let secs = t.elapsed().as_secs_f64();
        bar.finish_and_clear();
        let out = outdir.join(&cam.image_name);
        luster::image::output::write_rgb8(&out, img.width, img.height, &img.to_rgb8())
            .with_context(|| format!("rendering {}", path.display()))?;
        if !quiet {
            println!(
                "{}  {}x{}  {:.2} s render (+{:.2} s load and build)  {:.1} Mrays/s  {} triangles",
                out.display(),
                img.width,
                img.height,
                secs,
                setup,
                img.stats.total() as f64 / secs.max(1e-9) / 1e6,
                scene.triangle_count()
            );
        }
    }
    Ok(())
}
