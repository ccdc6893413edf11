//! The Slurm batch scripts of a split render: a job array with one task per
//! part (`--array=1-N`, so `SLURM_ARRAY_TASK_ID` is K), requeued when
//! preempted or its node fails, each task running
//! `luster render --part K/N --resume`; and a merge job, submitted with
//! `--dependency=afterok:<array job>`, running `luster merge`. A requeued
//! task resumes from its checkpoint (see [`super::part`]).
//!
//! Two readers see the scripts. sbatch reads the `#SBATCH` lines itself, up
//! to the first command: it splits them on white space, takes quotes and
//! backslashes as its own, ends a line at a `#`, and blanks the words
//! `packjob` and `hetjob` (its separators of heterogeneous jobs), and it also
//! scans the whole script for `#PBS` and `#BSUB` lines. Values there cannot be
//! quoted, so they are checked instead ([`check`]): a partition is a name, a
//! time limit one of Slurm's formats, the log folder a path with none of
//! those characters. bash reads the commands: every value there is one
//! single-quoted word ([`quote`]). No value anywhere may hold a control
//! character, so none can start a line of its own.

use super::{ClusterError, MAX_PARTS};
use luster_core::text::{is_unsafe, shown};
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
    /// Slurm partition (several separated by commas).
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

/// Whether `name` is a Slurm partition list: names of letters, digits,
/// `_`, `-` and `.`, not starting with `-`, separated by commas.
pub fn is_partition(name: &str) -> bool {
    name.len() <= 1024
        && name.split(',').all(|p| {
            p.bytes().next().is_some_and(|b| b.is_ascii_alphanumeric() || b == b'_')
                && p.bytes().all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'.'))
        })
}

/// Whether `t` is a time limit in one of sbatch's formats: `M`, `M:S`,
/// `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S`, or `infinite`/`unlimited`.
pub fn is_time_limit(t: &str) -> bool {
    let number = |s: &str| (1..=9).contains(&s.len()) && s.bytes().all(|b| b.is_ascii_digit());
    let clock = |s: &str, most: usize| {
        let parts: Vec<&str> = s.split(':').collect();
        parts.len() <= most && parts.iter().all(|p| number(p))
    };
    if t.eq_ignore_ascii_case("infinite") || t.eq_ignore_ascii_case("unlimited") {
        return true;
    }
    match t.split_once('-') {
        Some((days, rest)) => number(days) && clock(rest, 3),
        None => clock(t, 3),
    }
}

/// Why `s` cannot be a word of the scripts (a path or an option), if it
/// cannot: a control or format character would start a line of its own.
fn word_problem(s: &str) -> Option<&'static str> {
    s.chars().any(is_unsafe).then_some("holds a control character")
}

/// Why the path `p` cannot be in the scripts, if it cannot.
fn path_problem(p: &Path) -> Option<&'static str> {
    match p.to_str() {
        None => Some("is not UTF-8"),
        Some(_) if !p.is_absolute() => Some("is not absolute (the nodes run the scripts elsewhere)"),
        Some(s) => word_problem(s),
    }
}

/// Why the output folder cannot be in the `#SBATCH --output` line, if it
/// cannot (see the module's notes on how sbatch reads the line).
fn sbatch_path_problem(p: &str) -> Option<&'static str> {
    let lower = p.to_ascii_lowercase();
    if p.chars().any(char::is_whitespace) {
        Some("holds white space, which sbatch splits its #SBATCH lines at")
    } else if p.contains(['\'', '"', '\\', '#']) {
        Some("holds a quote, a backslash or a #, which sbatch reads itself in #SBATCH lines")
    } else if p.contains('%') {
        Some("holds a %, which Slurm replaces in log file names")
    } else if lower.contains("packjob") || lower.contains("hetjob") {
        Some("holds the word packjob or hetjob, which sbatch blanks in #SBATCH lines")
    } else {
        None
    }
}

/// Checks every value of `job` against what its script's readers accept;
/// the error is one sentence naming the value.
pub fn check(job: &SlurmJob) -> Result<(), ClusterError> {
    let refuse = |what: &str, value: &str, why: &str| {
        Err(ClusterError(format!("{what} \"{}\" {why}", shown(value, false))))
    };
    if job.tasks == 0 || job.tasks > MAX_PARTS {
        return Err(ClusterError(format!("the number of tasks must be between 1 and {MAX_PARTS}")));
    }
    if let Some(p) = &job.partition {
        if !is_partition(p) {
            return refuse(
                "the partition",
                p,
                "is not a Slurm partition name (letters, digits, '_', '-' and '.'; several separated by commas)",
            );
        }
    }
    if let Some(t) = &job.time {
        if !is_time_limit(t) {
            return refuse(
                "the time limit",
                t,
                "is not in one of Slurm's formats (M, M:S, H:M:S, D-H, D-H:M, D-H:M:S)",
            );
        }
    }
    let outdir = job.outdir.to_string_lossy();
    if let Some(why) = path_problem(&job.outdir).or_else(|| sbatch_path_problem(&outdir)) {
        return refuse("the output folder", &outdir, why);
    }
    if let Some(why) = path_problem(&job.luster) {
        return refuse("the luster binary's path", &job.luster.to_string_lossy(), why);
    }
    for s in &job.scenes {
        if let Some(why) = path_problem(s) {
            return refuse("the scene path", &s.to_string_lossy(), why);
        }
    }
    for a in &job.render_args {
        if let Some(why) = word_problem(a) {
            return refuse("the render option", a, why);
        }
    }
    Ok(())
}

/// `p` as one bash word (checked to be UTF-8 by [`check`]).
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

/// The job array: one task per part. The scenes follow `--`, so none can
/// be read as an option.
pub fn array_script(job: &SlurmJob) -> Result<String, ClusterError> {
    check(job)?;
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
    s += " --";
    for scene in &job.scenes {
        s += &format!(" \\\n  {}", path_word(scene));
    }
    s += "\n";
    Ok(s)
}

/// The merge job, to be submitted with `--dependency=afterok:<array job>`.
pub fn merge_script(job: &SlurmJob) -> Result<String, ClusterError> {
    check(job)?;
    let mut s = header(job, "luster-merge", "merge.log");
    s += "#SBATCH --ntasks=1\n";
    s += "set -euo pipefail\n";
    s += &format!("exec {} merge -- {}\n", path_word(&job.luster), path_word(&job.outdir));
    Ok(s)
}

/// The command that submits the scripts at `array` and `merge`, every word
/// quoted, to paste into a shell.
pub fn submit_command(array: &Path, merge: &Path) -> String {
    format!(
        "jid=$(sbatch --parsable {}) && sbatch --dependency=afterok:\"$jid\" {}",
        path_word(array),
        path_word(merge)
    )
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
        let s = array_script(&job()).unwrap();
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
            "exec '/opt/luster' render --part \"$SLURM_ARRAY_TASK_ID/4\" --resume --threads 8 -o '/out' '--spp' '16' --"
        ));
        assert!(s.contains("'/s/a b.xml'") && s.contains(r"'/s/it'\''s.json'"), "{s}");
    }

    #[test]
    fn the_merge_job_merges_the_folder() {
        let s = merge_script(&job()).unwrap();
        assert!(s.contains("exec '/opt/luster' merge -- '/out'\n") && !s.contains("--array"), "{s}");
    }

    #[test]
    fn partitions_and_time_limits_are_what_sbatch_accepts() {
        for ok in ["short", "gpu,cpu", "a_b-c.d", "_x"] {
            assert!(is_partition(ok), "{ok}");
        }
        for bad in ["", "short\ntouch pwned", "a b", "a,", "-x", "a;b", "$(x)", "a#b", "a\"b", "é"] {
            assert!(!is_partition(bad), "{bad:?}");
        }
        for ok in ["30", "30:00", "01:00:00", "2-12", "2-12:30", "1-0:0:0", "UNLIMITED", "infinite"] {
            assert!(is_time_limit(ok), "{ok}");
        }
        for bad in ["", "1:2:3:4", "1-", "-1", "1h", "01:00:00\n#SBATCH --x", "1 --wrap=x", "1-2-3", ":1"] {
            assert!(!is_time_limit(bad), "{bad:?}");
        }
    }

    #[test]
    fn values_that_would_change_the_scripts_are_refused_by_name() {
        // What the error must start with, and the change to a good job.
        type Case = (&'static str, fn(&mut SlurmJob));
        let cases: [Case; 12] = [
            ("the partition", |j| j.partition = Some("short\ntouch pwned".into())),
            ("the time limit", |j| j.time = Some("1:00 --wrap=id".into())),
            ("the output folder", |j| j.outdir = "/o\n#SBATCH --wrap=id".into()),
            ("the output folder", |j| j.outdir = "/my renders".into()),
            ("the output folder", |j| j.outdir = "/o#x".into()),
            ("the output folder", |j| j.outdir = "/o/%j".into()),
            ("the output folder", |j| j.outdir = "/HetJob".into()),
            ("the output folder", |j| j.outdir = "relative".into()),
            ("the scene path", |j| j.scenes.push("/s/a\n#PBS -o x.xml".into())),
            ("the scene path", |j| j.scenes.push("-x.xml".into())),
            ("the luster binary's path", |j| j.luster = "/opt/\u{1b}]0;x\u{7}".into()),
            ("the render option", |j| j.render_args.push("a\rb".into())),
        ];
        for (what, change) in cases {
            let mut j = job();
            change(&mut j);
            let e = array_script(&j).unwrap_err().0;
            assert!(e.starts_with(what) && !e.contains('\n') && !e.contains('\u{1b}'), "{e}");
            assert!(merge_script(&j).is_err());
        }
    }
}
