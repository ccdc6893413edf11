//! `luster slurm SCENE... -o OUTDIR --tasks N [--submit]`: writes the Slurm
//! scripts of a split render (see `luster::cluster::slurm`) and optionally
//! submits them; `luster slurm status OUTDIR` reports its progress.

use luster::cluster::slurm::{
    array_script, merge_script, quote, submit_command, SlurmJob, ARRAY_SCRIPT, LOG_DIR, MERGE_SCRIPT,
};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `luster slurm`'s arguments.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Cli {
    #[command(subcommand)]
    status: Option<Sub>,
    #[command(flatten)]
    job: JobArgs,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// Progress of a split render, from the part files and checkpoints in OUTDIR.
    Status {
        /// The render's output folder.
        outdir: PathBuf,
    },
}

#[derive(clap::Args)]
struct JobArgs {
    /// Scene files (.xml, .json or .obj).
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// Output folder, on a file system every node shares (created if needed).
    #[arg(short, long, required = true)]
    outdir: Option<PathBuf>,
    /// Number of parts: array tasks.
    #[arg(long, required = true, value_parser = clap::value_parser!(u32).range(1..=i64::from(luster::cluster::MAX_PARTS)))]
    tasks: Option<u32>,
    /// CPUs per task (also each render's --threads).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    cpus_per_task: Option<u32>,
    /// Slurm partition.
    #[arg(long)]
    partition: Option<String>,
    /// Time limit per task, as Slurm writes it (e.g. 02:00:00).
    #[arg(long)]
    time: Option<String>,
    /// Samples per pixel, overriding each camera's NumSamples.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    spp: Option<u32>,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Reconstruction filter.
    #[arg(long, value_enum, default_value_t = super::args::FilterArg::Box)]
    filter: super::args::FilterArg,
    /// Display transform of the 8-bit images (see `luster render --help`).
    #[arg(long, value_name = "MODE", value_parser = super::args::parse_display)]
    display: Option<luster::tonemap::Display>,
    /// Time limit of one shader call, in seconds (passed on to every task).
    #[arg(long, value_name = "SECONDS", value_parser = super::args::parse_timeout)]
    shader_timeout: Option<f64>,
    /// A folder shaders' `require` searches (repeatable; passed on to every
    /// task as an absolute path).
    #[arg(long = "shader-lib", value_name = "DIR", value_parser = super::args::parse_shader_lib)]
    shader_lib: Vec<PathBuf>,
    /// Least time between two checkpoints of a task, in seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 60)]
    checkpoint: u64,
    /// Submit both scripts with sbatch (the merge job after the array succeeds).
    #[arg(long)]
    submit: bool,
}

/// Runs `luster slurm`.
pub fn run(cli: Cli) -> ExitCode {
    let result = match cli.status {
        Some(Sub::Status { outdir }) => status(&outdir),
        None => write(&cli.job),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            super::report("error", &format_args!("{e:#}"));
            ExitCode::from(2)
        }
    }
}

fn status(outdir: &Path) -> anyhow::Result<()> {
    // The lines come escaped for the terminal.
    for line in luster::cluster::merge::status(outdir)? {
        say!("{line}");
    }
    Ok(())
}

fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(p).map_err(|e| anyhow::anyhow!("{}: cannot make the path absolute: {e}", p.display()))
}

fn write(a: &JobArgs) -> anyhow::Result<()> {
    let (Some(outdir), Some(tasks)) = (&a.outdir, a.tasks) else {
        anyhow::bail!("luster slurm needs --outdir and --tasks");
    };
    let mut scenes = Vec::with_capacity(a.scenes.len());
    for s in &a.scenes {
        if !s.is_file() {
            anyhow::bail!("{}: no such scene file", s.display());
        }
        scenes.push(absolute(s)?);
    }
    let outdir = absolute(outdir)?;
    let luster =
        std::env::current_exe().map_err(|e| anyhow::anyhow!("cannot find the luster binary: {e}"))?;
    let mut render_args = Vec::new();
    if let Some(spp) = a.spp {
        render_args.extend(["--spp".to_string(), spp.to_string()]);
    }
    if a.seed != 0 {
        render_args.extend(["--seed".to_string(), a.seed.to_string()]);
    }
    if matches!(a.filter, super::args::FilterArg::Gaussian) {
        render_args.extend(["--filter".to_string(), "gaussian".to_string()]);
    }
    if let Some(d) = a.display {
        render_args.extend(["--display".to_string(), d.name().to_string()]);
    }
    if let Some(t) = a.shader_timeout {
        render_args.extend(["--shader-timeout".to_string(), t.to_string()]);
    }
    for dir in &a.shader_lib {
        let dir = dir.canonicalize().unwrap_or_else(|_| dir.clone());
        render_args.extend(["--shader-lib".to_string(), dir.to_string_lossy().into_owned()]);
    }
    render_args.extend(["--checkpoint".to_string(), a.checkpoint.to_string()]);
    let job = SlurmJob {
        luster,
        scenes,
        outdir: outdir.clone(),
        tasks,
        cpus_per_task: a.cpus_per_task,
        partition: a.partition.clone(),
        time: a.time.clone(),
        render_args,
    };
    // Both scripts are made, so every value is checked, before anything is written.
    let (array_text, merge_text) = (array_script(&job)?, merge_script(&job)?);
    std::fs::create_dir_all(outdir.join(LOG_DIR))
        .map_err(|e| anyhow::anyhow!("{}: cannot create the folder: {e}", outdir.display()))?;
    let (array, merge) = (outdir.join(ARRAY_SCRIPT), outdir.join(MERGE_SCRIPT));
    for (path, text) in [(&array, array_text), (&merge, merge_text)] {
        std::fs::write(path, text).map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
    }
    // The paths were checked to hold no control character; quoted, they
    // paste back into a shell as the same words.
    let word = |p: &Path| quote(&p.to_string_lossy());
    if !a.submit {
        say!("wrote {} and {}", word(&array), word(&merge));
        say!("submit with: {}", submit_command(&array, &merge));
        return Ok(());
    }
    let array_id = sbatch(&[array.as_os_str().to_string_lossy().into_owned()])?;
    let merge_id =
        sbatch(&[format!("--dependency=afterok:{array_id}"), merge.to_string_lossy().into_owned()])?;
    say!("submitted array job {array_id} ({tasks} tasks) and merge job {merge_id}");
    say!("follow with: luster slurm status {}  (or squeue -j {array_id},{merge_id})", word(&outdir));
    Ok(())
}

/// Runs `sbatch --parsable ARGS`; returns the job id.
fn sbatch(args: &[String]) -> anyhow::Result<String> {
    let out = std::process::Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .output()
        .map_err(|e| anyhow::anyhow!("cannot run sbatch (is Slurm installed and on PATH?): {e}"))?;
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr);
        anyhow::bail!("sbatch failed: {}", why.trim());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        anyhow::bail!("sbatch gave no job id");
    }
    Ok(id)
}
