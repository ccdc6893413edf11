//! The conformance report: what `luster suite` writes after rendering a course
//! folder and comparing every image with the course's expected image.
//!
//! [`Report::build`] turns the [`CaseResult`]s of
//! [`conformance`](crate::conformance) into a plain, serialisable summary and
//! makes the output folder self-contained (expected images copied, browser
//! previews of EXR/HDR images, thumbnails); [`write`](fn@write) then writes
//!
//! | file | contents |
//! |---|---|
//! | `index.html` | summary, per-homework table, one row per image ([`html`]) |
//! | `results.json` | the same [`Report`] as JSON ([`json`]) |
//! | `renders/` | our renders and their LDR-FLIP heatmaps |
//! | `expected/` | copies of the expected images, by path under the course folder |
//! | `thumbs/` | small PNG thumbnails shown in the table |
//!
//! Every path inside the report is relative to the output folder, with `/`
//! separators, so the folder can be moved or archived as a whole.
//!
//! # Rows and verdicts
//! A row is one camera's image, or a whole scene when it failed before any
//! image was rendered. Its [`Verdict`] is `pass` (the threshold was met),
//! `fail` (compared, below the threshold), `error` (the scene did not load,
//! build or render, or the comparison itself failed, e.g. different sizes),
//! `no-reference` (the course has no expected image for that camera),
//! `unsupported` (a fail or error of a scene that uses a feature luster does
//! not implement yet, named on the row) or `known-quirk` (a miss explained by
//! a known quirk of the course's data, named on the row). The last two are
//! counted apart: they are neither our passes nor our failures.

mod assets;
pub mod html;
pub mod json;
mod metrics;
mod row;

pub use metrics::Metrics;
pub use row::{HdrEntry, ImageEntry, SceneEntry, ThresholdEntry, Thumbs, Verdict};

use crate::conformance::CaseResult;
use row::scene_entry;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// `luster <version>`.
    pub generator: String,
    /// The course folder that was run.
    pub root: String,
    /// The `--only` pattern, if any.
    pub only: Option<String>,
    /// Scenes rendered at the same time.
    pub jobs: usize,
    /// Worker threads per scene.
    pub threads: usize,
    /// Wall-clock seconds of the whole run.
    pub total_seconds: f64,
    /// Counts over all rows.
    pub summary: Counts,
    /// Counts per homework, in order.
    pub homeworks: Vec<HomeworkSummary>,
    /// One entry per scene, in course order.
    pub scenes: Vec<SceneEntry>,
}

/// Numbers of scenes and rows by verdict.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Scenes run.
    pub scenes: usize,
    /// Rows: images, plus scenes that failed before rendering any.
    pub rows: usize,
    /// Rows that met their threshold.
    pub passed: usize,
    /// Rows compared and below their threshold.
    pub failed: usize,
    /// Rows that could not be rendered or compared.
    pub errored: usize,
    /// Rows without an expected image.
    pub no_reference: usize,
    /// Rows of scenes that need a feature luster does not implement yet.
    pub unsupported: usize,
    /// Rows that miss their bar because of a known quirk of the data.
    pub known_quirks: usize,
}

impl Counts {
    fn add(&mut self, v: Verdict) {
        self.rows += 1;
        match v {
            Verdict::Pass => self.passed += 1,
            Verdict::Fail => self.failed += 1,
            Verdict::Error => self.errored += 1,
            Verdict::NoReference => self.no_reference += 1,
            Verdict::Unsupported => self.unsupported += 1,
            Verdict::KnownQuirk => self.known_quirks += 1,
        }
    }
}

/// One homework's counts.
#[derive(Clone, Debug, Serialize)]
pub struct HomeworkSummary {
    /// `hw1`, ...
    pub hw: String,
    /// Its counts.
    #[serde(flatten)]
    pub counts: Counts,
    /// Seconds spent on its scenes (summed over scenes; with several jobs
    /// this exceeds the wall-clock time).
    pub seconds: f64,
    /// The failed and errored rows, as `image (verdict)` or the scene's
    /// label when it has no image.
    pub problems: Vec<String>,
    /// How many rows each kind of bar judged (`fixed`, `noise-aware`, ...),
    /// in order of first appearance.
    pub bars: Vec<(String, usize)>,
    /// The sample counts the noise-aware rows were rendered at (lowest,
    /// highest), when there were any.
    pub noise_spp: Option<[u32; 2]>,
}

/// How the run was made, for the report's header.
#[derive(Clone, Debug, Default)]
pub struct RunInfo {
    /// The course folder.
    pub root: String,
    /// The `--only` pattern.
    pub only: Option<String>,
    /// Scenes at a time.
    pub jobs: usize,
    /// Threads per scene.
    pub threads: usize,
    /// Wall-clock seconds.
    pub total_seconds: f64,
}

impl Report {
    /// Summarises `results` (renders and heatmaps already under
    /// `outdir/renders`) and puts the expected images and thumbnails into
    /// `outdir`. Problems copying or thumbnailing an image are noted on its
    /// row and never stop the report.
    pub fn build(results: &[CaseResult], root: &Path, outdir: &Path, info: RunInfo) -> Report {
        let scenes: Vec<SceneEntry> = results.iter().map(|r| scene_entry(r, root, outdir)).collect();
        let mut summary = Counts::default();
        let mut per_hw: BTreeMap<String, HomeworkSummary> = BTreeMap::new();
        for s in &scenes {
            let hw = per_hw.entry(s.hw.clone()).or_insert_with(|| HomeworkSummary {
                hw: s.hw.clone(),
                counts: Counts::default(),
                seconds: 0.0,
                problems: Vec::new(),
                bars: Vec::new(),
                noise_spp: None,
            });
            hw.counts.scenes += 1;
            summary.scenes += 1;
            hw.seconds += s.seconds;
            if let Some(v) = s.verdict() {
                hw.counts.add(v);
                summary.add(v);
                if matches!(v, Verdict::Fail | Verdict::Error) {
                    hw.problems.push(format!("{} ({})", s.label, v.name()));
                }
            }
            for i in &s.images {
                hw.counts.add(i.verdict);
                summary.add(i.verdict);
                if matches!(i.verdict, Verdict::Fail | Verdict::Error) {
                    hw.problems.push(format!("{} ({})", i.image_name, i.verdict.name()));
                }
                match hw.bars.iter_mut().find(|(k, _)| k == i.threshold.kind) {
                    Some((_, n)) => *n += 1,
                    None => hw.bars.push((i.threshold.kind.to_string(), 1)),
                }
                if i.threshold.kind == "noise-aware" {
                    let spp = i.threshold.spp;
                    hw.noise_spp = Some(hw.noise_spp.map_or([spp, spp], |[a, b]| [a.min(spp), b.max(spp)]));
                }
            }
        }
        let mut homeworks: Vec<HomeworkSummary> = per_hw.into_values().collect();
        homeworks.sort_by_key(|h| hw_number(&h.hw));
        Report {
            generator: format!("luster {}", env!("CARGO_PKG_VERSION")),
            root: info.root,
            only: info.only,
            jobs: info.jobs,
            threads: info.threads,
            total_seconds: info.total_seconds,
            summary,
            homeworks,
            scenes,
        }
    }

    /// Whether every row passed or had no reference (unsupported features
    /// and known quirks of the data are not failures of ours).
    pub fn all_passed(&self) -> bool {
        self.summary.failed == 0 && self.summary.errored == 0
    }
}

/// `hw10` sorts after `hw9`.
fn hw_number(hw: &str) -> (u32, String) {
    (hw.trim_start_matches("hw").parse().unwrap_or(u32::MAX), hw.to_string())
}

/// Writes `outdir/index.html` and `outdir/results.json`.
pub fn write(report: &Report, outdir: &Path) -> std::io::Result<()> {
    std::fs::write(outdir.join("results.json"), json::to_json(report))?;
    std::fs::write(outdir.join("index.html"), html::to_html(report))?;
    Ok(())
}
