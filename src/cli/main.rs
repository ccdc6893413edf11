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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Render { scenes, outdir, threads, quiet } => render::run(&scenes, &outdir, threads, quiet),
    }
}

/// A rayon pool of `threads` workers (all cores when `None`).
pub fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, ExitCode> {
    rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0)).build().map_err(|e| {
        eprintln!("error: cannot start worker threads: {e}");
        ExitCode::from(2)
    })
}
