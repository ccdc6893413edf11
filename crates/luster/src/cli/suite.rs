//! `luster suite`: render a whole course folder, compare every image with the
//! course's expected image, and write an HTML report and `results.json`.
//!
//! Discovery, rendering, thresholds and verdicts are the library's
//! ([`luster::conformance`], the same the golden tests use); the report is
//! [`luster::report`]. This file only parses the choices, prints a progress
//! line per scene and the summary, and picks the exit code: 0 when the suite
//! ran (whatever the verdicts; 1 with `--strict` if any image failed or
//! errored), 2 when the folder is missing or the output cannot be written.

use luster::conformance::runner::{run_cases, RunOptions};
use luster::conformance::{discover, CaseResult};
use luster::report::{self, Report, RunInfo};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// What `luster suite` was asked.
pub struct Args {
    /// The course folder.
    pub dir: PathBuf,
    /// The report folder.
    pub outdir: PathBuf,
    /// Scenes at a time.
    pub jobs: usize,
    /// Substring of the scene label.
    pub only: Option<String>,
    /// Threads per scene.
    pub threads: Option<usize>,
    /// Exit 1 on failures.
    pub strict: bool,
    /// Samples per pixel instead of each camera's.
    pub spp: Option<u32>,
    /// Cap on each camera's samples per pixel.
    pub max_spp: Option<u32>,
}

/// Runs the suite and returns the exit code.
pub fn run(args: &Args) -> ExitCode {
    let fail = |msg: String| {
        super::report("error", &msg);
        ExitCode::from(2)
    };
    if !args.dir.is_dir() {
        return fail(format!("the course folder `{}` does not exist or is not a folder", args.dir.display()));
    }
    let all = discover(&args.dir);
    if all.is_empty() {
        return fail(format!(
            "no scenes found under `{}` (expected hwN/json/*.json or hwN/xml/*.xml)",
            args.dir.display()
        ));
    }
    let matching: Vec<_> =
        all.into_iter().filter(|c| args.only.as_deref().is_none_or(|p| c.label().contains(p))).collect();
    let skipped = matching.iter().filter(|c| !c.mentions_expected_image()).count();
    let cases: Vec<_> = matching.into_iter().filter(|c| c.mentions_expected_image()).collect();
    if cases.is_empty() {
        return fail(match &args.only {
            Some(p) => format!("no scene with an expected image has a label containing `{p}`"),
            None => format!("no scene under `{}` has an expected image", args.dir.display()),
        });
    }
    let renders = args.outdir.join("renders");
    if let Err(e) = std::fs::create_dir_all(&renders) {
        return fail(format!("could not create the report folder `{}`: {e}", renders.display()));
    }
    let mut opts = RunOptions::new(args.jobs, args.threads);
    opts.render.spp = args.spp;
    opts.max_spp = args.max_spp;
    say!(
        "luster suite: {} scene{} from {}{} ({} job{} × {} thread{})",
        cases.len(),
        if cases.len() == 1 { "" } else { "s" },
        args.dir.display(),
        if skipped > 0 { format!(", {skipped} without an expected image skipped") } else { String::new() },
        opts.jobs,
        if opts.jobs == 1 { "" } else { "s" },
        opts.threads,
        if opts.threads == 1 { "" } else { "s" },
    );
    let t0 = Instant::now();
    let width = cases.len().to_string().len();
    let results = match run_cases(&cases, &renders, opts, &|r, n, total| progress(r, n, total, width)) {
        Ok(r) => r,
        Err(e) => return fail(format!("cannot start worker threads: {e}")),
    };
    let info = RunInfo {
        root: args.dir.display().to_string(),
        only: args.only.clone(),
        jobs: opts.jobs,
        threads: opts.threads,
        total_seconds: t0.elapsed().as_secs_f64(),
    };
    let mut report = Report::build(&results, &args.dir, &args.outdir, info);
    // The total includes copying the expected images and making thumbnails.
    report.total_seconds = t0.elapsed().as_secs_f64();
    if let Err(e) = report::write(&report, &args.outdir) {
        return fail(format!("could not write the report into `{}`: {e}", args.outdir.display()));
    }
    summary(&report, &args.outdir);
    if args.strict && !report.all_passed() {
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}

/// One line per finished scene: verdicts of its images and its time.
fn progress(r: &CaseResult, n: usize, total: usize, width: usize) {
    let unsupported = r.unsupported();
    let what = match &r.error {
        Some(e) if !unsupported.is_empty() => {
            format!("UNSUPPORTED ({})  {}", unsupported.join(", "), first_line(e))
        }
        Some(e) => format!("ERROR  {}", first_line(e)),
        None => r
            .images
            .iter()
            .map(|i| {
                let verdict = if i.error.is_some() {
                    "ERROR"
                } else if i.expected.is_none() {
                    "no ref"
                } else if i.pass {
                    "pass"
                } else if !unsupported.is_empty() {
                    "unsupported"
                } else if i.quirk.is_some() {
                    "data quirk"
                } else {
                    "FAIL"
                };
                let pair = match &i.pair {
                    Some(p) => format!("; seed pair FLIP {:.4}, {:.1} dB", p.flip, p.psnr),
                    None => String::new(),
                };
                match &i.comparison {
                    Some(c) => {
                        format!("{} {verdict} (FLIP {:.4}, {:.1} dB{pair})", i.image_name, c.flip, c.psnr)
                    }
                    None => format!("{} {verdict}", i.image_name),
                }
            })
            .collect::<Vec<_>>()
            .join(", "),
    };
    let what = if unsupported.is_empty() || r.error.is_some() {
        what
    } else {
        format!("{what}  [unsupported: {}]", unsupported.join(", "))
    };
    let warn = if r.warnings.is_empty() {
        String::new()
    } else {
        format!("  [{} warning{}]", r.warnings.len(), if r.warnings.len() == 1 { "" } else { "s" })
    };
    let label = r.case.label();
    let (label, what) = (luster::text::shown(&label, false), luster::text::shown(&what, false));
    say!("[{n:>width$}/{total}] {:<44} {:>7.2} s  {what}{warn}", label, r.seconds);
}

fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or(s)
}

/// One line per homework, then the totals: passes and failures are ours;
/// unsupported features and known data quirks are counted apart.
fn summary(report: &Report, outdir: &Path) {
    let s = &report.summary;
    say!();
    for hw in &report.homeworks {
        say!("{}", homework_line(hw));
    }
    let noref = if s.no_reference > 0 {
        format!(", {} without expected image", s.no_reference)
    } else {
        String::new()
    };
    say!(
        "total: {} scenes, {} images: {} passed, {} failed, {} errored, {} unsupported, {} data quirk{}{noref} \
         in {:.1} s",
        s.scenes,
        s.rows,
        s.passed,
        s.failed,
        s.errored,
        s.unsupported,
        s.known_quirks,
        if s.known_quirks == 1 { "" } else { "s" },
        report.total_seconds
    );
    say!("report: {}", outdir.join("index.html").display());
}

/// One homework at a glance: its verdict, how many images passed, what went
/// wrong and where (the first few names), what was counted apart, the bars
/// the images were judged by, and the time:
/// `hw3  FAILING  12/13 passed; 1 failed: wine_glass.png (fail) · bars: 13 noise-aware at 4 spp · 96.0 s`.
fn homework_line(hw: &report::HomeworkSummary) -> String {
    let c = &hw.counts;
    let verdict = if c.failed + c.errored > 0 {
        "FAILING"
    } else if c.unsupported > 0 && c.passed == 0 {
        "unsupported"
    } else {
        "ok"
    };
    let mut line = format!("{:<5} {verdict:<8} {:>3}/{:<3} passed", hw.hw, c.passed, c.rows);
    if !hw.problems.is_empty() {
        const SHOWN: usize = 3;
        let mut names = hw.problems.iter().take(SHOWN).cloned().collect::<Vec<_>>().join(", ");
        if hw.problems.len() > SHOWN {
            names.push_str(&format!(" and {} more", hw.problems.len() - SHOWN));
        }
        line.push_str(&format!("; {} failed or errored: {names}", c.failed + c.errored));
    }
    for (n, what) in [
        (c.known_quirks, "known data quirk"),
        (c.unsupported, "unsupported"),
        (c.no_reference, "without reference"),
    ] {
        if n > 0 {
            line.push_str(&format!("; {n} {what}"));
        }
    }
    let bars = hw
        .bars
        .iter()
        .map(|(kind, n)| match (kind.as_str(), hw.noise_spp) {
            ("noise-aware", Some([a, b])) if a == b => format!("{n} {kind} at {a} spp"),
            ("noise-aware", Some([a, b])) => format!("{n} {kind} at {a}–{b} spp"),
            _ => format!("{n} {kind}"),
        })
        .collect::<Vec<_>>()
        .join(", ");
    if !bars.is_empty() {
        line.push_str(&format!(" · bars: {bars}"));
    }
    line.push_str(&format!(" · {:.1} s", hw.seconds));
    line
}
