//! The conformance report: what `luster suite` writes after rendering a course
//! folder and comparing every image with the course's expected image.
//!
//! [`Report::build`] turns the [`CaseResult`]s of
//! [`conformance`](crate::conformance) into a plain, serialisable summary and
//! makes the output folder self-contained (expected images copied, browser
//! previews of EXR/HDR images, thumbnails); [`write`] then writes
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

use crate::conformance::thresholds::{BlockZ, StatsPair};
use crate::conformance::{Bar, CaseResult, HdrResult, ImageResult, Rule};
use crate::image::{Comparison, MetricSpace};
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

/// The verdict of a row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Met the threshold.
    Pass,
    /// Compared and missed the threshold.
    Fail,
    /// Not rendered or not comparable.
    Error,
    /// No expected image to compare with.
    NoReference,
    /// Failed or errored, in a scene that needs a feature luster lacks.
    Unsupported,
    /// Missed its bar because of a known quirk of the data.
    KnownQuirk,
}

impl Verdict {
    /// `pass`, `fail`, `error`, `no-reference`, `unsupported` or `known-quirk`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Error => "error",
            Verdict::NoReference => "no-reference",
            Verdict::Unsupported => "unsupported",
            Verdict::KnownQuirk => "known-quirk",
        }
    }
}

/// One scene.
#[derive(Clone, Debug, Serialize)]
pub struct SceneEntry {
    /// `hw2/xml/ellipsoids.xml`.
    pub label: String,
    /// `hw2`.
    pub hw: String,
    /// `json` or `xml`.
    pub encoding: String,
    /// The scene file.
    pub scene: String,
    /// Why the scene failed before rendering (load, build, crash).
    pub error: Option<String>,
    /// The loader's and builder's warnings.
    pub warnings: Vec<String>,
    /// Seconds to load and build.
    pub setup_seconds: f64,
    /// Seconds for the whole scene.
    pub seconds: f64,
    /// One entry per camera.
    pub images: Vec<ImageEntry>,
    /// Features the scene uses that luster does not implement yet.
    pub unsupported: Vec<String>,
}

impl SceneEntry {
    /// The scene's own verdict when it has no images (it failed early):
    /// unsupported when it needs a feature luster lacks, else an error.
    pub fn verdict(&self) -> Option<Verdict> {
        self.images.is_empty().then_some(if self.unsupported.is_empty() {
            Verdict::Error
        } else {
            Verdict::Unsupported
        })
    }
}

/// One camera's image.
#[derive(Clone, Debug, Serialize)]
pub struct ImageEntry {
    /// The camera's `ImageName`.
    pub image_name: String,
    /// The row's verdict.
    pub verdict: Verdict,
    /// The known quirk of the data this image has, if any.
    pub quirk: Option<String>,
    /// Our render, relative to the report folder.
    pub render: Option<String>,
    /// The expected image as the browser shows it (a PNG preview for EXR/HDR).
    pub expected: Option<String>,
    /// The copy of the original expected file, when it differs from `expected`.
    pub expected_original: Option<String>,
    /// The expected image in the course folder.
    pub expected_source: Option<String>,
    /// The LDR-FLIP heatmap.
    pub heatmap: Option<String>,
    /// Thumbnails of render, expected and heatmap.
    pub thumbs: Thumbs,
    /// The comparison's numbers.
    pub metrics: Option<Metrics>,
    /// The bar it was judged by.
    pub threshold: ThresholdEntry,
    /// An HDR camera's linear image against the course's, when it has one.
    pub hdr: Option<HdrEntry>,
    /// Render seconds.
    pub seconds: f64,
    /// Why it could not be written or compared.
    pub error: Option<String>,
}

/// An HDR row's linear images and their numbers.
#[derive(Clone, Debug, Serialize)]
pub struct HdrEntry {
    /// Our `.exr`, relative to the report folder.
    pub render: String,
    /// The copy of the course's `.exr`/`.hdr`.
    pub expected: Option<String>,
    /// Thumbnails of both, tone-mapped by one curve (keyed by the course's
    /// image): ours, then the course's.
    pub thumbs: Option<[String; 2]>,
    /// Relative mean absolute error `Σ|t − r| / Σ|r|`.
    pub relative_mae: f64,
    /// Mean HDR-FLIP.
    pub hdr_flip: f64,
}

/// Thumbnail paths, relative to the report folder.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Thumbs {
    /// Of our render.
    pub render: Option<String>,
    /// Of the expected image.
    pub expected: Option<String>,
    /// Of the heatmap.
    pub heatmap: Option<String>,
}

/// A comparison's numbers (the per-pixel maps are in the heatmap).
#[derive(Clone, Debug, Serialize)]
pub struct Metrics {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `display` (sRGB values) or `linear` (both images EXR/HDR).
    pub space: &'static str,
    /// PSNR in dB; `null` when infinite (identical images).
    pub psnr: Option<f64>,
    /// Mean SSIM on luma.
    pub ssim: f64,
    /// Mean LDR-FLIP error (Andersson et al. 2020).
    pub flip: f64,
    /// Pixels whose 8-bit codes differ.
    pub differing_pixels: usize,
    /// The same as a percentage of all pixels.
    pub differing_percent: f64,
    /// Inclusive bounding box `[x0, y0, x1, y1]` of the differing pixels.
    pub diff_bbox: Option<[u32; 4]>,
    /// Largest absolute channel difference.
    pub max_abs_diff: f32,
    /// Whether the PSNR part of the threshold was met.
    pub psnr_ok: bool,
    /// Whether the FLIP part of the threshold was met.
    pub flip_ok: bool,
    /// PSNR of the means of 8×8 blocks, when the threshold tests it.
    pub coarse_psnr: Option<f64>,
    /// Whether that part of the threshold was met (true when not tested).
    pub coarse_ok: bool,
    /// Statistical rule: mean luma of ours and of the expected image.
    pub mean_luma: Option<[f64; 2]>,
    /// Statistical rule: luma contrast (standard deviation) of ours and of the expected image.
    pub contrast: Option<[f64; 2]>,
    /// Whether the statistics agreed (true when not tested).
    pub stats_ok: bool,
    /// Noise-aware rule: the space the noise was judged in (`display` on the
    /// 8-bit images, `linear` against the course's `.exr`).
    pub noise_space: Option<&'static str>,
    /// Noise-aware rule: the block edge in pixels.
    pub block: Option<u32>,
    /// Noise-aware rule: mean z² of the block means (see
    /// `conformance::noise::block_z`).
    pub block_mean_z2: Option<f64>,
    /// Noise-aware rule: share of blocks with |z| > 5.
    pub block_outliers: Option<f64>,
    /// Noise-aware rule: blocks left out (showing a light, or clipped at white).
    pub left_out_blocks: Option<usize>,
    /// Noise-aware rule: our mean luminance minus the course's, in standard
    /// errors.
    pub luminance_z: Option<f64>,
    /// Noise-aware rule: mean luminance of ours and of the expected image.
    pub mean_luminance: Option<[f64; 2]>,
    /// Whether the z-scores met the bar (true when not tested).
    pub z_ok: bool,
}

/// The bar an image was judged by.
#[derive(Clone, Debug, Serialize)]
pub struct ThresholdEntry {
    /// `fixed` or `noise-aware`.
    pub kind: &'static str,
    /// Minimum PSNR in dB (for a noise-aware rule, derived from the pair).
    pub min_psnr: f64,
    /// Maximum mean LDR-FLIP (likewise).
    pub max_flip: f64,
    /// Why this bar, and the rule in words.
    pub reason: String,
    /// Samples per pixel of the render.
    pub spp: u32,
    /// Noise-aware: PSNR of our render against our render with the next
    /// seed; `null` when identical or not rendered.
    pub pair_psnr: Option<f64>,
    /// Noise-aware: mean LDR-FLIP between our two renders.
    pub pair_flip: Option<f64>,
    /// Noise-aware: the largest mean z² of the 8×8 block means.
    pub max_mean_z2: Option<f64>,
    /// Noise-aware: the largest share of blocks with |z| > 5.
    pub max_outliers: Option<f64>,
    /// Noise-aware: the largest |offset| of the mean luminance in standard
    /// errors.
    pub max_luminance_z: Option<f64>,
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

fn scene_entry(r: &CaseResult, root: &Path, outdir: &Path) -> SceneEntry {
    let unsupported = r.unsupported();
    SceneEntry {
        label: r.case.label(),
        hw: r.case.hw.clone(),
        encoding: r.case.encoding.name().to_string(),
        scene: r.case.scene.display().to_string(),
        error: r.error.clone(),
        warnings: r.warnings.clone(),
        setup_seconds: r.setup_seconds,
        seconds: r.seconds,
        images: r.images.iter().map(|i| image_entry(i, root, outdir, !unsupported.is_empty())).collect(),
        unsupported,
    }
}

fn image_entry(i: &ImageResult, root: &Path, outdir: &Path, unsupported: bool) -> ImageEntry {
    let verdict = if i.error.is_some() {
        if unsupported {
            Verdict::Unsupported
        } else {
            Verdict::Error
        }
    } else if i.expected.is_none() {
        Verdict::NoReference
    } else if i.pass {
        // A pass is a pass, whatever the scene lacks.
        Verdict::Pass
    } else if unsupported {
        Verdict::Unsupported
    } else if i.quirk.is_some() && i.comparison.is_some() {
        Verdict::KnownQuirk
    } else if i.comparison.is_some() {
        Verdict::Fail
    } else {
        Verdict::Error
    };
    let mut error = i.error.clone();
    let mut note = |e: String| {
        error = Some(match error.take() {
            Some(prev) => format!("{prev}; {e}"),
            None => e,
        })
    };
    let render = i.render.is_file().then(|| assets::relative(&i.render, outdir));
    let heatmap = i.heatmap.as_ref().filter(|p| p.is_file()).map(|p| assets::relative(p, outdir));
    let mut thumbs = Thumbs::default();
    if render.is_some() {
        thumbs.render = assets::thumbnail(&i.render, outdir).map_err(&mut note).ok();
    }
    if let Some(h) = &i.heatmap {
        if heatmap.is_some() {
            thumbs.heatmap = assets::thumbnail(h, outdir).map_err(&mut note).ok();
        }
    }
    let (mut expected, mut expected_original) = (None, None);
    if let Some(src) = &i.expected {
        match assets::copy_expected(src, root, outdir) {
            Ok(copy) => {
                thumbs.expected = assets::thumbnail(&copy.shown, outdir).map_err(&mut note).ok();
                expected = Some(assets::relative(&copy.shown, outdir));
                expected_original = copy.original.map(|p| assets::relative(&p, outdir));
            }
            Err(e) => note(e),
        }
    }
    let t = &i.bar;
    ImageEntry {
        image_name: i.image_name.clone(),
        verdict,
        quirk: i.quirk.map(str::to_string),
        render,
        expected,
        expected_original,
        expected_source: i.expected.as_ref().map(|p| p.display().to_string()),
        heatmap,
        thumbs,
        metrics: i
            .comparison
            .as_ref()
            .map(|c| metrics(c, t, i.coarse_psnr, i.stats.as_ref(), i.block_z.as_ref())),
        threshold: ThresholdEntry {
            kind: match i.threshold.rule {
                Rule::Fixed { .. } => "fixed",
                Rule::NoiseAware { .. } => "noise-aware",
                Rule::Statistical { .. } => "statistical",
            },
            min_psnr: t.min_psnr,
            max_flip: t.max_flip,
            reason: i.threshold.describe(),
            spp: i.spp,
            pair_psnr: i.pair.as_ref().and_then(|p| p.psnr.is_finite().then_some(p.psnr)),
            pair_flip: i.pair.as_ref().map(|p| p.flip),
            max_mean_z2: t.tests_z().then_some(t.max_mean_z2),
            max_outliers: t.tests_z().then_some(t.max_outliers),
            max_luminance_z: t.tests_z().then_some(t.max_luminance_z),
        },
        hdr: i.hdr.as_ref().map(|h| hdr_entry(h, root, outdir, &mut note)),
        seconds: i.seconds,
        error,
    }
}

/// Copies the course's HDR image and makes the tone-mapped pair of
/// thumbnails; a problem is noted on the row.
fn hdr_entry(h: &HdrResult, root: &Path, outdir: &Path, note: &mut impl FnMut(String)) -> HdrEntry {
    let mut entry = HdrEntry {
        render: assets::relative(&h.render, outdir),
        expected: None,
        thumbs: None,
        relative_mae: h.relative_mae,
        hdr_flip: h.hdr_flip,
    };
    match assets::copy_expected(&h.expected, root, outdir) {
        Ok(copy) => {
            let original = copy.original.unwrap_or(copy.shown);
            entry.thumbs = assets::hdr_thumbnails(&h.render, &original, outdir).map_err(&mut *note).ok();
            entry.expected = Some(assets::relative(&original, outdir));
        }
        Err(e) => note(e),
    }
    entry
}

fn metrics(
    c: &Comparison,
    t: &Bar,
    coarse_psnr: Option<f64>,
    stats: Option<&StatsPair>,
    z: Option<&BlockZ>,
) -> Metrics {
    Metrics {
        width: c.width,
        height: c.height,
        space: match c.space {
            MetricSpace::Display => "display",
            MetricSpace::Linear => "linear",
        },
        psnr: c.psnr.is_finite().then_some(c.psnr),
        ssim: c.ssim,
        flip: c.flip,
        differing_pixels: c.differing_pixels,
        differing_percent: 100.0 * c.differing_fraction(),
        diff_bbox: c.diff_bbox.map(|(a, b, x, y)| [a, b, x, y]),
        max_abs_diff: c.max_abs_diff,
        psnr_ok: t.psnr_ok(c),
        flip_ok: t.flip_ok(c),
        coarse_psnr: coarse_psnr.filter(|p| p.is_finite()),
        coarse_ok: t.coarse_ok(coarse_psnr),
        mean_luma: stats.map(|s| [s.ours.mean, s.reference.mean]),
        contrast: stats.map(|s| [s.ours.contrast, s.reference.contrast]),
        stats_ok: t.stats_ok(stats),
        noise_space: z.map(|z| z.space.name()),
        block: z.map(|z| z.block),
        block_mean_z2: z.map(|z| z.mean_z2),
        block_outliers: z.map(|z| z.outliers),
        left_out_blocks: z.map(|z| z.left_out),
        luminance_z: z.map(|z| z.luminance_z),
        mean_luminance: z.map(|z| z.mean_luminance),
        z_ok: t.z_ok(z),
    }
}
