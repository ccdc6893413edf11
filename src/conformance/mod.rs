//! Conformance against the course's expected images: finding the scenes of a
//! course folder, the expected image of each camera, the threshold each image
//! must meet, and rendering plus comparing one scene. The golden-image tests
//! and `luster suite` both use this module, so they judge alike.
//!
//! The folder layout is the course's: `hwN/{json,xml}/**/scene` with expected
//! images in `hwN/expected/<ImageName>`. An XML scene prefers
//! `hwN/expected/2022/<ImageName>` and then `.../2020/...` when present: those
//! older images belong to the older XML version of a scene.

pub mod measures;
pub mod runner;
pub mod thresholds;

use crate::image::{compare, CompareOptions, Comparison, Rgb32Image};
use crate::render::{self, RenderOptions, Scene};
use std::path::{Path, PathBuf};
use std::time::Instant;
pub use thresholds::{threshold, Bar, Rule, Threshold};

/// Which encoding a scene uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Encoding {
    /// The 2025 JSON.
    Json,
    /// The older XML.
    Xml,
}

impl Encoding {
    /// `json` or `xml`.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Json => "json",
            Encoding::Xml => "xml",
        }
    }
}

/// A scene of a course folder.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Case {
    /// The homework folder name (`hw1`).
    pub hw: String,
    /// Its encoding.
    pub encoding: Encoding,
    /// The scene file.
    pub scene: PathBuf,
    /// The homework folder.
    pub hw_dir: PathBuf,
}

impl Case {
    /// A short, unique, human name: `hw2/xml/ellipsoids.xml`.
    pub fn label(&self) -> String {
        let rel = self.scene.strip_prefix(&self.hw_dir).unwrap_or(&self.scene);
        format!("{}/{}", self.hw, rel.display()).replace('\\', "/")
    }

    /// The expected image for a camera's `ImageName`, if the folder has one.
    pub fn expected_image(&self, image_name: &str) -> Option<PathBuf> {
        let exp = self.hw_dir.join("expected");
        if self.encoding == Encoding::Xml {
            for year in ["2022", "2020"] {
                let p = exp.join(year).join(image_name);
                if p.is_file() {
                    return Some(p);
                }
            }
        }
        let p = exp.join(image_name);
        p.is_file().then_some(p)
    }

    /// Whether the scene file names one of its homework's expected images.
    ///
    /// A cheap textual test, made without loading the scene (and its meshes):
    /// true when the file's text contains the file name of an image in
    /// `hwN/expected/` (or, for XML, `expected/2022/` and `expected/2020/`).
    /// It errs on the side of true: a scene that fails to load is still kept
    /// if it mentions an expected image, so its failure gets reported.
    pub fn mentions_expected_image(&self) -> bool {
        let Ok(bytes) = std::fs::read(&self.scene) else { return true };
        let text = String::from_utf8_lossy(&bytes);
        let exp = self.hw_dir.join("expected");
        let mut dirs = vec![exp.clone()];
        if self.encoding == Encoding::Xml {
            dirs.extend(["2022", "2020"].map(|y| exp.join(y)));
        }
        dirs.iter().filter_map(|d| std::fs::read_dir(d).ok()).flat_map(|rd| rd.flatten()).any(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            e.path().is_file() && text.contains(name.as_ref())
        })
    }
}

/// Every scene file under `root/hw*/{json,xml}`, sorted.
pub fn discover(root: &Path) -> Vec<Case> {
    let mut cases = Vec::new();
    let Ok(hws) = std::fs::read_dir(root) else { return cases };
    for hw in hws.flatten() {
        let hw_dir = hw.path();
        let hw_name = hw.file_name().to_string_lossy().to_string();
        if !hw_dir.is_dir() || !hw_name.starts_with("hw") {
            continue;
        }
        for (sub, encoding) in [("json", Encoding::Json), ("xml", Encoding::Xml)] {
            let mut files = Vec::new();
            walk(&hw_dir.join(sub), sub, &mut files);
            for scene in files {
                cases.push(Case { hw: hw_name.clone(), encoding, scene, hw_dir: hw_dir.clone() });
            }
        }
    }
    cases.sort();
    cases
}

fn walk(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(&p, ext, out);
        } else if p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(ext)) {
            out.push(p);
        }
    }
}

/// The outcome for one camera's image.
#[derive(Clone, Debug)]
pub struct ImageResult {
    /// The camera's `ImageName`.
    pub image_name: String,
    /// Where the render was written.
    pub render: PathBuf,
    /// The expected image, when the folder has one.
    pub expected: Option<PathBuf>,
    /// The difference heatmap, when one was written.
    pub heatmap: Option<PathBuf>,
    /// Metrics against the expected image.
    pub comparison: Option<Comparison>,
    /// The threshold it was judged by.
    pub threshold: Threshold,
    /// The numbers it had to reach (the threshold applied to `pair`).
    pub bar: Bar,
    /// For a noise-aware threshold: our render against our render with the
    /// next seed, which measures our own noise.
    pub pair: Option<Comparison>,
    /// PSNR of the means of 8×8-pixel blocks against the expected image
    /// (where noise averages out), when the bar tests it.
    pub coarse_psnr: Option<f64>,
    /// Luma statistics of ours and the expected image, when the bar tests them.
    pub stats: Option<thresholds::StatsPair>,
    /// Samples per pixel it was rendered with.
    pub spp: u32,
    /// Render seconds for this camera (both renders of a pair).
    pub seconds: f64,
    /// Whether it met the threshold (false without an expected image).
    pub pass: bool,
    /// Why it failed beyond the metrics (an unreadable expected image, ...).
    pub error: Option<String>,
}

/// The outcome for one scene.
#[derive(Clone, Debug)]
pub struct CaseResult {
    /// The scene.
    pub case: Case,
    /// Seconds to load and build.
    pub setup_seconds: f64,
    /// Wall-clock seconds for the whole case: load, build, render, compare.
    pub seconds: f64,
    /// One entry per camera; empty if the scene failed to load.
    pub images: Vec<ImageResult>,
    /// The load or build error, if any.
    pub error: Option<String>,
    /// Warnings of the loader.
    pub warnings: Vec<String>,
}

/// Loads, builds and renders `case` on the current rayon pool, writes each
/// image and its heatmap under `outdir`, and compares with the expected images.
pub fn run_case(case: &Case, outdir: &Path) -> CaseResult {
    run_case_with(case, outdir, &RenderOptions::default())
}

/// [`run_case`] with render options (a reduced sample count for quick checks,
/// a seed, a filter). An image judged by a noise-aware threshold is rendered
/// a second time with the next seed, and the distance between the two sets
/// its bar.
pub fn run_case_with(case: &Case, outdir: &Path, opts: &RenderOptions) -> CaseResult {
    let t0 = Instant::now();
    let mut result = CaseResult::failed(case, None);
    run_case_into(case, outdir, opts, &mut result);
    result.seconds = t0.elapsed().as_secs_f64();
    result
}

/// [`run_case`], with a panic anywhere in loading, building, rendering or
/// comparing caught and turned into the case's error, so that one bad scene
/// cannot stop a suite. The panic message is kept; images finished before the
/// panic are lost.
pub fn run_case_guarded(case: &Case, outdir: &Path, opts: &RenderOptions) -> CaseResult {
    let t0 = Instant::now();
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_case_with(case, outdir, opts))) {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".to_string());
            let mut r = CaseResult::failed(case, Some(format!("luster crashed on this scene: {msg}")));
            r.seconds = t0.elapsed().as_secs_f64();
            r
        }
    }
}

impl CaseResult {
    /// A result without images, failed with `error` (or still empty when `None`).
    pub fn failed(case: &Case, error: Option<String>) -> Self {
        CaseResult {
            case: case.clone(),
            setup_seconds: 0.0,
            seconds: 0.0,
            images: Vec::new(),
            error,
            warnings: Vec::new(),
        }
    }

    /// Frees the per-pixel FLIP and difference maps of every comparison,
    /// keeping the summary numbers (the heatmap is already written).
    pub fn drop_pixel_maps(&mut self) {
        for c in self.images.iter_mut().flat_map(|i| i.comparison.iter_mut().chain(i.pair.iter_mut())) {
            c.flip_map = Vec::new();
            c.diff_map = Vec::new();
        }
    }
}

fn run_case_into(case: &Case, outdir: &Path, opts: &RenderOptions, result: &mut CaseResult) {
    let t0 = Instant::now();
    let built = crate::scene::load(&case.scene).and_then(|d| {
        result.warnings.extend(d.warnings.iter().map(|w| w.to_string()));
        Scene::build(&d)
    });
    let scene = match built {
        Ok(s) => s,
        Err(e) => {
            result.error = Some(e.to_string());
            return;
        }
    };
    result.warnings.extend(scene.warnings.iter().map(|w| w.to_string()));
    result.setup_seconds = t0.elapsed().as_secs_f64();
    let stem = case.label().replace(['/', '.'], "_");
    for (i, cam) in scene.cameras.iter().enumerate() {
        let t = Instant::now();
        // A shader that fails makes the scene an error row, not a black image.
        let img = match render::try_render_with(&scene, i, opts, &|_| {}) {
            Ok(img) => img,
            Err(e) => {
                result.error = Some(format!("{}: {e}", case.scene.display()));
                return;
            }
        };
        // An .exr camera is judged by its tone-mapped .png, as the course's is.
        let (ldr, ldr_name) = match crate::film::outputs::first_ldr(&cam.image_name, &cam.tonemaps) {
            Some(o) => (o.kind, o.name.display().to_string()),
            None => (crate::film::OutputKind::Course, cam.image_name.clone()),
        };
        let threshold = threshold(case, &ldr_name, cam.num_samples);
        let expected = case.expected_image(&ldr_name);
        // The second render is only worth its time when there is a
        // reference to judge.
        let second = (threshold.needs_pair() && expected.is_some()).then(|| {
            let next = RenderOptions { seed: opts.seed.wrapping_add(1), ..*opts };
            let film = render::render_with(&scene, i, &next, &|_| {}).film;
            crate::film::outputs::rgb8(&film, &ldr).unwrap_or_default()
        });
        let seconds = t.elapsed().as_secs_f64();
        let png = outdir.join(format!("{stem}__{}", sanitize(&cam.image_name))).with_extension("png");
        let mut r = ImageResult {
            image_name: cam.image_name.clone(),
            render: png.clone(),
            expected: expected.clone(),
            heatmap: None,
            comparison: None,
            threshold,
            bar: threshold.bar(None),
            pair: None,
            coarse_psnr: None,
            stats: None,
            spp: opts.spp.unwrap_or(cam.num_samples).max(1),
            seconds,
            pass: false,
            error: None,
        };
        let rgb = crate::film::outputs::rgb8(&img.film, &ldr).unwrap_or_default();
        if let Err(e) = crate::image::output::write_rgb8(&png, img.width, img.height, &rgb) {
            r.error = Some(e.to_string());
            result.images.push(r);
            continue;
        }
        if let Some(second) = &second {
            match compare_rgb8(img.width, img.height, second, &rgb) {
                Ok(p) => r.pair = Some(p),
                Err(e) => r.error = Some(e),
            }
            r.bar = threshold.bar(r.pair.as_ref());
            let pair_png =
                png.with_file_name(format!("{}__seed{}.png", file_stem(&png), opts.seed.wrapping_add(1)));
            // Kept for looking at; judging does not need the file.
            let _ = crate::image::output::write_rgb8(&pair_png, img.width, img.height, second);
        }
        if let Some(exp) = expected {
            match compare_with(&exp, img.width, img.height, &rgb, r.bar.tests_coarse(), r.bar.tests_stats()) {
                Ok((c, coarse, stats)) => {
                    r.coarse_psnr = coarse;
                    r.stats = stats;
                    let heat = png.with_file_name(format!("{}__heatmap.png", file_stem(&png)));
                    if let Ok(h) = crate::image::comparison_heatmap(&c, crate::image::HeatmapSource::Flip) {
                        if crate::image::write_heatmap(&h, &heat).is_ok() {
                            r.heatmap = Some(heat);
                        }
                    }
                    r.pass = r.error.is_none() && r.bar.accepts(&c, r.coarse_psnr, r.stats.as_ref());
                    r.comparison = Some(c);
                }
                Err(e) => r.error = Some(e),
            }
        }
        result.images.push(r);
    }
}

fn file_stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default()
}

/// What [`compare_with`] measures: the comparison, the PSNR of block means
/// and the luma statistics (the last two only when asked for).
type Measured = (Comparison, Option<f64>, Option<thresholds::StatsPair>);

/// Compares an 8-bit render with the expected image file; with `coarse`,
/// also the means of 8×8 blocks (see [`thresholds::coarse_psnr`]); with
/// `stats`, the luma statistics of both.
fn compare_with(
    expected: &Path,
    w: u32,
    h: u32,
    rgb: &[u8],
    coarse: bool,
    stats: bool,
) -> Result<Measured, String> {
    let reference = Rgb32Image::load(expected).map_err(|e| e.to_string())?;
    let test = rgb8_image(w, h, rgb).ok_or("render buffer has the wrong size")?;
    let c = compare(&reference, &test, &CompareOptions::default()).map_err(|e| e.to_string())?;
    let coarse = if coarse { thresholds::coarse_psnr(&reference, &test) } else { None };
    let stats = stats.then(|| thresholds::StatsPair::of(&test, &reference));
    Ok((c, coarse, stats))
}

/// Compares two 8-bit renders of the same camera (so of the same size).
fn compare_rgb8(w: u32, h: u32, reference: &[u8], test: &[u8]) -> Result<Comparison, String> {
    let a = rgb8_image(w, h, reference).ok_or("the second render has the wrong size")?;
    let b = rgb8_image(w, h, test).ok_or("render buffer has the wrong size")?;
    compare(&a, &b, &CompareOptions::default()).map_err(|e| e.to_string())
}

fn rgb8_image(w: u32, h: u32, rgb: &[u8]) -> Option<Rgb32Image> {
    image::RgbImage::from_raw(w, h, rgb.to_vec()).map(|b| Rgb32Image::from_rgb8(&b))
}

fn sanitize(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' { c } else { '_' }).collect()
}
