//! The Slurm batch scripts of a split render: a job array with one task per
//! part (`--array=1-N`, so `SLURM_ARRAY_TASK_ID` is K), requeued when
//! preempted or its node fails, each task running
//! `luster render --part K/N --resume`; and a merge job, submitted with
//! `--dependency=afterok:<array job>`, running `luster merge`. A requeued
//! task resumes from its checkpoint (see [`super::part`]).

use std::path::{Path, PathBuf};

/// What the scripts run.
#[derive(Clone, Debug)]
pub struct SlurmJob {
    /// The luster binary (an absolute path: the nodes run it as is).
    pub luster: PathBuf,
    /// Scene files (absolute).
    pub scenes: Vec<PathBuf>,
    /// The output folder (absolute), shared by the nodes.
    pub outdir: PathBuf,
    /// Number of parts (array tasks).
    pub tasks: u32,
    /// CPUs of each task (also its `--threads`).
    pub cpus_per_task: Option<u32>,
    /// Slurm partition.
    pub partition: Option<String>,
    /// Time limit of each task, in Slurm's notation (`HH:MM:SS`, `D-HH`, ...).
    pub time: Option<String>,
    /// Further `luster render` options (`--spp`, `--seed`, ...), as words.
    pub render_args: Vec<String>,
}

/// The array script's file under the output folder.
pub const ARRAY_SCRIPT: &str = "luster.sbatch";
/// The merge script's file under the output folder.
pub const MERGE_SCRIPT: &str = "luster-merge.sbatch";
/// Where the tasks' logs go, under the output folder.
pub const LOG_DIR: &str = "logs";

/// A word for `bash`, single-quoted.
pub fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

fn path_word(p: &Path) -> String {
    quote(&p.to_string_lossy())
}

fn header(job: &SlurmJob, name: &str, log: &str) -> String {
    let mut s = String::from("#!/bin/bash\n");
    s += &format!("#SBATCH --job-name={name}\n");
    s += &format!("#SBATCH --output={}\n", job.outdir.join(LOG_DIR).join(log).to_string_lossy());
    s += "#SBATCH --open-mode=append\n";
    if let Some(p) = &job.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &job.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s
}

/// The job array: one task per part.
pub fn array_script(job: &SlurmJob) -> String {
    let mut s = header(job, "luster", "part-%a.log");
    s += &format!("#SBATCH --array=1-{}\n", job.tasks);
    s += "#SBATCH --requeue\n";
    s += "#SBATCH --ntasks=1\n";
    if let Some(c) = job.cpus_per_task {
        s += &format!("#SBATCH --cpus-per-task={c}\n");
    }
    s += "# One part of the render; a requeued task resumes from its checkpoint.\n";
    s += "set -euo pipefail\n";
    s += &format!(
        "exec {} render --part \"$SLURM_ARRAY_TASK_ID/{}\" --resume",
        path_word(&job.luster),
        job.tasks
    );
    if let Some(c) = job.cpus_per_task {
        s += &format!(" --threads {c}");
    }
    s += &format!(" -o {}", path_word(&job.outdir));
    for a in &job.render_args {
        s += &format!(" {}", quote(a));
    }
    for scene in &job.scenes {
        s += &format!(" \\\n  {}", path_word(scene));
    }
    s += "\n";
    s
}

/// The merge job, to be submitted with `--dependency=afterok:<array job>`.
pub fn merge_script(job: &SlurmJob) -> String {
    let mut s = header(job, "luster-merge", "merge.log");
    s += "#SBATCH --ntasks=1\n";
    s += "set -euo pipefail\n";
    s += &format!("exec {} merge {}\n", path_word(&job.luster), path_word(&job.outdir));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job() -> SlurmJob {
        SlurmJob {
            luster: "/opt/luster".into(),
            scenes: vec!["/s/a b.xml".into(), "/s/it's.json".into()],
            outdir: "/out".into(),
            tasks: 4,
            cpus_per_task: Some(8),
            partition: Some("short".into()),
            time: Some("01:00:00".into()),
            render_args: vec!["--spp".into(), "16".into()],
        }
    }

    #[test]
    fn the_array_runs_one_resumable_part_per_task() {
        let s = array_script(&job());
        for line in [
            "#SBATCH --array=1-4\n",
            "#SBATCH --requeue\n",
            "#SBATCH --cpus-per-task=8\n",
            "#SBATCH --partition=short\n",
            "#SBATCH --time=01:00:00\n",
            "#SBATCH --output=/out/logs/part-%a.log\n",
        ] {
            assert!(s.contains(line), "{line} missing from\n{s}");
        }
        assert!(s.contains(
            "exec '/opt/luster' render --part \"$SLURM_ARRAY_TASK_ID/4\" --resume --threads 8 -o '/out' '--spp' '16'"
        ));
        assert!(s.contains("'/s/a b.xml'") && s.contains(r"'/s/it'\''s.json'"), "{s}");
    }

    #[test]
    fn the_merge_job_merges_the_folder() {
        let s = merge_script(&job());
        assert!(s.contains("exec '/opt/luster' merge '/out'\n") && !s.contains("--array"), "{s}");
    }
}
