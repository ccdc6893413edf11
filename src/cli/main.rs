//! The `luster` command line: a thin layer over the library.

mod render;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

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
    /// Benchmark the BVH on PLY meshes (build time, memory, Mrays/s).
    ///
    /// Prints BVH build time, memory and closest-hit primary-ray throughput
    /// (Mrays/s) for each thread count, with the camera of
    /// shared/bench/embree_rays.py (1920x1080, 45° vertical field of view,
    /// looking along the bounding box's thinnest axis), so the figures line up
    /// with Intel Embree's on the same mesh and rays.
    Bench {
        /// PLY meshes.
        #[arg(required = true)]
        plys: Vec<PathBuf>,
        /// Thread counts to measure, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "1,2")]
        threads: Vec<usize>,
        /// Timed repetitions per thread count (the median is reported).
        #[arg(long, default_value_t = 5)]
        reps: usize,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Render { scenes, outdir, threads, quiet } => render::run(&scenes, &outdir, threads, quiet),
        Command::Bench { plys, threads, reps } => match luster::bench::run(&plys, &threads, reps) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(2)
            }
        },
    }
}

/// A rayon pool of `threads` workers (all cores when `None`).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, ExitCode> {
    rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0)).build().map_err(|e| {
        eprintln!("error: cannot start worker threads: {e}");
        ExitCode::from(2)
    })
}
