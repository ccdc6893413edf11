//! Conformance against the course's expected images: finding the scenes of a
//! course folder, the expected image of each camera, the threshold each image
//! must meet, and rendering plus comparing one scene. The golden-image tests
//! and `luster suite` both use this module, so they judge alike.
//!
//! The folder layout is the course's: `hwN/{json,xml}/**/scene` with expected
//! images in `hwN/expected/<ImageName>`. An XML scene prefers
//! `hwN/expected/2022/<ImageName>` and then `.../2020/...` when present: those
//! older images belong to the older XML version of a scene.

mod discover;
pub mod measures;
pub mod noise;
mod quirks;
pub mod ref_noise;
mod rule;
pub mod runner;
pub mod thresholds;

use crate::metrics::{compare, CompareOptions, Comparison};
pub use discover::{discover, Case, Encoding};
use luster_core::image::Rgb32Image;
use luster_render::film::Film;
use luster_render::render::{self, RenderOptions, Scene};
pub use noise::Space;
use std::path::{Path, PathBuf};
use std::time::Instant;
pub use thresholds::{threshold, Bar, Rule, Threshold, STOCHASTIC};

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
    /// The numbers it had to reach.
    pub bar: Bar,
    /// For a noise-aware threshold: our render against our render with the
    /// next seed (shown in reports; the block z-scores use the two renders).
    pub pair: Option<Comparison>,
    /// PSNR of the means of 8×8-pixel blocks against the expected image
    /// (where noise averages out), for reports.
    pub coarse_psnr: Option<f64>,
    /// Luma statistics of ours and the expected image, when the bar tests them.
    pub stats: Option<thresholds::StatsPair>,
    /// Per-block z-scores against the expected image, with the variance from
    /// the second render, when the bar tests them.
    pub block_z: Option<thresholds::BlockZ>,
    /// HDR numbers against the course's `.exr`/`.hdr`, for an HDR camera
    /// that has one.
    pub hdr: Option<HdrResult>,
    /// The camera's own sample count (the expected image's).
    pub scene_spp: u32,
    /// A known quirk of the course's data that makes this image differ.
    pub quirk: Option<&'static str>,
    /// Samples per pixel it was rendered with.
    pub spp: u32,
    /// Render seconds for this camera (both renders of a pair).
    pub seconds: f64,
    /// Whether it met the threshold (false without an expected image).
    pub pass: bool,
    /// Why it failed beyond the metrics (an unreadable expected image, ...).
    pub error: Option<String>,
}

/// An HDR camera's linear image against the course's.
#[derive(Clone, Debug)]
pub struct HdrResult {
    /// Our linear image (`.exr`).
    pub render: PathBuf,
    /// The course's.
    pub expected: PathBuf,
    /// Relative mean absolute error `Σ|t − r| / Σ|r|`.
    pub relative_mae: f64,
    /// Mean HDR-FLIP.
    pub hdr_flip: f64,
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

/// What the loader says when a scene uses an element luster ignores.
const UNSUPPORTED_WARNING: &str = " is not supported yet";

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
    run_case_into(case, outdir, opts, None, &mut result);
    result.seconds = t0.elapsed().as_secs_f64();
    result
}

/// [`run_case_with`], with each camera's sample count capped at `max_spp`
/// (when `opts` sets no count of its own), and a panic anywhere in loading,
/// building, rendering or comparing caught and turned into the case's
/// error, so that one bad scene cannot stop a suite. The panic message is
/// kept; images finished before the panic are lost.
pub fn run_case_guarded(
    case: &Case,
    outdir: &Path,
    opts: &RenderOptions,
    max_spp: Option<u32>,
) -> CaseResult {
    let t0 = Instant::now();
    let run = || {
        let mut result = CaseResult::failed(case, None);
        run_case_into(case, outdir, opts, max_spp, &mut result);
        result.seconds = t0.elapsed().as_secs_f64();
        result
    };
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)) {
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

    /// The features of the scene that luster does not implement yet, as the
    /// loader reported them: `<Renderer>` for an ignored element. A scene that
    /// needs them cannot match its expected image, so the suite counts it
    /// apart from failures.
    pub fn unsupported(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for w in &self.warnings {
            if let Some(end) = w.find(UNSUPPORTED_WARNING) {
                // "...: <DirectionalLight> inside <Lights> is not supported yet; ignored"
                let head = &w[..end];
                let element = head.find('<').map(|i| &head[i..]).and_then(|h| h.split(" inside").next());
                let feature = element.unwrap_or(head).trim().to_string();
                if !out.contains(&feature) {
                    out.push(feature);
                }
            }
        }
        out
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

fn run_case_into(
    case: &Case,
    outdir: &Path,
    opts: &RenderOptions,
    max_spp: Option<u32>,
    result: &mut CaseResult,
) {
    let t0 = Instant::now();
    let built = luster_scene::load(&case.scene).and_then(|d| {
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
        match camera_result(case, &scene, i, cam, outdir, &stem, opts, max_spp) {
            Ok(r) => result.images.push(r),
            Err(e) => {
                result.error = Some(e);
                return;
            }
        }
    }
}

/// Renders camera `i` of a case's scene, writes the image and judges it
/// against the course's; `Err` is a shader failure, which ends the case.
#[allow(clippy::too_many_arguments)]
fn camera_result(
    case: &Case,
    scene: &Scene,
    i: usize,
    cam: &luster_render::render::camera::Camera,
    outdir: &Path,
    stem: &str,
    opts: &RenderOptions,
    max_spp: Option<u32>,
) -> Result<ImageResult, String> {
    let t = Instant::now();
    let capped;
    let opts = match (max_spp, opts.spp) {
        (Some(m), None) if cam.num_samples > m => {
            capped = RenderOptions { spp: Some(m.max(1)), ..*opts };
            &capped
        }
        _ => opts,
    };
    // A shader that fails makes the scene an error row, not a black image.
    let img = render::try_render_with(scene, i, opts, &|_| {})
        .map_err(|e| format!("{}: {e}", case.scene.display()))?;
    // An .exr camera is judged by its tone-mapped .png, as the course's is.
    let (ldr, ldr_name) =
        match luster_core::image::outputs::first_ldr(&cam.image_name, &cam.tonemaps, cam.display) {
            Some(o) => (o.kind, o.name.display().to_string()),
            None => (luster_core::image::outputs::OutputKind::Course, cam.image_name.clone()),
        };
    let threshold = threshold(case, &ldr_name, cam.num_samples);
    let expected = case.expected_image(&ldr_name);
    let expected_hdr = case.expected_hdr(&cam.image_name);
    // The second render is only worth its time when there is a
    // reference to judge.
    let second = (threshold.needs_pair() && expected.is_some()).then(|| {
        let next = RenderOptions { seed: opts.seed.wrapping_add(1), ..*opts };
        render::render_with(scene, i, &next, &|_| {}).film
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
        bar: threshold.bar(),
        pair: None,
        coarse_psnr: None,
        stats: None,
        block_z: None,
        hdr: None,
        scene_spp: cam.num_samples.max(1),
        quirk: thresholds::known_quirk(case, &cam.image_name),
        spp: opts.spp.unwrap_or(cam.num_samples).max(1),
        seconds,
        pass: false,
        error: None,
    };
    let rgb = luster_render::film::write::rgb8(&img.film, &ldr).unwrap_or_default();
    if let Err(e) = luster_core::image::output::write_rgb8(&png, img.width, img.height, &rgb) {
        r.error = Some(e.to_string());
        return Ok(r);
    }
    let second_rgb = second.as_ref().map(|f| luster_render::film::write::rgb8(f, &ldr).unwrap_or_default());
    if let Some(second_rgb) = &second_rgb {
        match compare_rgb8(img.width, img.height, second_rgb, &rgb) {
            Ok(p) => r.pair = Some(p),
            Err(e) => r.error = Some(e),
        }
        let pair_png =
            png.with_file_name(format!("{}__seed{}.png", file_stem(&png), opts.seed.wrapping_add(1)));
        // Kept for looking at; judging does not need the file.
        let _ = luster_core::image::output::write_rgb8(&pair_png, img.width, img.height, second_rgb);
    }
    let hdr_reference = match expected_hdr.as_deref().map(Rgb32Image::load) {
        Some(Ok(reference)) => Some(reference),
        Some(Err(e)) => {
            r.error = Some(e.to_string());
            None
        }
        None => None,
    };
    if let (Some(reference), Some(path)) = (&hdr_reference, &expected_hdr) {
        let exr = png.with_extension("exr");
        match hdr_result(&img.film, reference, &exr, path) {
            Ok(h) => r.hdr = Some(h),
            Err(e) => r.error = Some(e),
        }
    }
    // An unreadable other year only costs the measured noise.
    let other_year = expected_hdr
        .as_deref()
        .filter(|_| second.is_some())
        .and_then(Case::other_year)
        .and_then(|p| Rgb32Image::load(p).ok());
    if let Some(exp) = expected {
        let judged = second.as_ref().map(|s| Judged {
            second_film: s,
            second_rgb: second_rgb.as_deref().unwrap_or_default(),
            film: &img.film,
            hdr_reference: hdr_reference.as_ref(),
            other_year: other_year.as_ref(),
            spp: r.spp,
            ref_spp: r.scene_spp,
        });
        judge(&mut r, &exp, img.width, img.height, &rgb, judged, &png);
    }
    Ok(r)
}

/// Compares the written 8-bit image `rgb` with the course's `expected` by the
/// camera's bar (noise-aware where `judged` holds a second render), writes
/// the FLIP heatmap beside `png`, and records the verdict in `r`.
fn judge(
    r: &mut ImageResult,
    expected: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
    judged: Option<Judged>,
    png: &Path,
) {
    match compare_with(expected, width, height, rgb, r.bar.tests_stats(), judged) {
        Ok((c, coarse, stats, block_z)) => {
            r.coarse_psnr = coarse;
            r.stats = stats;
            if let Some(z) = &block_z {
                r.bar = r.threshold.bar_in(z.space);
            }
            r.block_z = block_z;
            let heat = png.with_file_name(format!("{}__heatmap.png", file_stem(png)));
            if let Ok(h) = crate::metrics::comparison_heatmap(&c, crate::metrics::HeatmapSource::Flip) {
                if crate::metrics::write_heatmap(&h, &heat).is_ok() {
                    r.heatmap = Some(heat);
                }
            }
            r.pass =
                r.error.is_none() && r.bar.accepts(&c, r.coarse_psnr, r.stats.as_ref(), r.block_z.as_ref());
            r.comparison = Some(c);
        }
        Err(e) => r.error = Some(e),
    }
}

/// Writes our linear image to `exr` and measures it against the course's.
fn hdr_result(film: &Film, reference: &Rgb32Image, exr: &Path, expected: &Path) -> Result<HdrResult, String> {
    luster_core::image::output::write_rgb32f(exr, film.width, film.height, &film.pixels)
        .map_err(|e| e.to_string())?;
    let ours = linear_image(film);
    let rel = crate::metrics::relative_error(reference, &ours).map_err(|e| e.to_string())?;
    let c = compare(reference, &ours, &CompareOptions::default()).map_err(|e| e.to_string())?;
    Ok(HdrResult {
        render: exr.to_path_buf(),
        expected: expected.to_path_buf(),
        relative_mae: rel.mae,
        hdr_flip: c.flip,
    })
}

/// A film as a linear image.
fn linear_image(film: &Film) -> Rgb32Image {
    Rgb32Image {
        width: film.width,
        height: film.height,
        pixels: film.pixels.iter().map(|p| p.to_array()).collect(),
        encoding: luster_core::image::Encoding::Linear,
    }
}

/// What the noise judgement of a multi-sample image needs: both renders, as
/// 8-bit values and as films, and the course's linear image when it has one.
struct Judged<'a> {
    film: &'a Film,
    second_film: &'a Film,
    second_rgb: &'a [u8],
    hdr_reference: Option<&'a Rgb32Image>,
    /// The course's other year's render of the same image, which measures
    /// its noise.
    other_year: Option<&'a Rgb32Image>,
    spp: u32,
    ref_spp: u32,
}

fn file_stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default()
}

/// What [`compare_with`] measures: the comparison, the PSNR of block means,
/// and, when asked for, the luma statistics and the noise judgement.
type Measured = (Comparison, Option<f64>, Option<thresholds::StatsPair>, Option<thresholds::BlockZ>);

/// Compares an 8-bit render with the expected image file, and measures the
/// PSNR of the means of 8×8 blocks (see [`thresholds::coarse_psnr`]); with
/// `stats`, also the luma statistics of both; with `judged` (a multi-sample
/// image rendered twice), the noise judgement of [`noise::block_z`]: in
/// linear radiance against the course's HDR image when there is one, on the
/// 8-bit values otherwise.
fn compare_with(
    expected: &Path,
    w: u32,
    h: u32,
    rgb: &[u8],
    stats: bool,
    judged: Option<Judged>,
) -> Result<Measured, String> {
    let reference = Rgb32Image::load(expected).map_err(|e| e.to_string())?;
    let test = rgb8_image(w, h, rgb).ok_or("render buffer has the wrong size")?;
    let c = compare(&reference, &test, &CompareOptions::default()).map_err(|e| e.to_string())?;
    let coarse = thresholds::coarse_psnr(&reference, &test);
    let stats = stats.then(|| thresholds::StatsPair::of(&test, &reference));
    let z = match judged {
        Some(j) => match j.hdr_reference {
            Some(hdr) => {
                let model = noise::NoiseModel::linear(j.spp, j.ref_spp, hdr);
                let (ours, second) = (linear_image(j.film), linear_image(j.second_film));
                match j.other_year.and_then(|o| ref_noise::measured_if_agreeing(hdr, o, &model)) {
                    Some(course) => noise::block_z_measured(&ours, &second, hdr, &model, &course),
                    None => noise::block_z(&ours, &second, hdr, &model),
                }
            }
            None => {
                let second = rgb8_image(w, h, j.second_rgb).ok_or("the second render has the wrong size")?;
                noise::block_z(&test, &second, &reference, &noise::NoiseModel::display(j.spp, j.ref_spp))
            }
        },
        None => None,
    };
    Ok((c, coarse, stats, z))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn case(hw_dir: &Path, scene: &str, encoding: Encoding) -> Case {
        Case { hw: "hw7".into(), encoding, scene: hw_dir.join(scene), hw_dir: hw_dir.to_path_buf() }
    }

    #[test]
    fn unsupported_features_come_from_the_loaders_words() {
        let mut r = CaseResult::failed(&case(Path::new("hw5"), "xml/a.xml", Encoding::Xml), None);
        assert!(r.unsupported().is_empty());
        r.warnings = vec![
            "a.xml: line 18, Scene/Lights/DirectionalLight[id=1]: <DirectionalLight> inside <Lights> is not \
             supported yet; ignored"
                .into(),
            "a.xml: line 31, Scene/BRDFs: <BRDFs> inside <Scene> is not supported yet; ignored".into(),
            "a.xml: line 40: an unrelated warning".into(),
        ];
        assert_eq!(r.unsupported(), ["<DirectionalLight>", "<BRDFs>"]);
    }

    #[test]
    fn expected_images_follow_the_year_of_the_scene_and_exr_takes_its_png() {
        let dir = tempfile::tempdir().unwrap();
        let hw = dir.path();
        for p in [
            "expected/2020/a.png",
            "expected/2022/a.png",
            "expected/a.png",
            "expected/h.exr",
            "expected/h.png",
        ] {
            std::fs::create_dir_all(hw.join(p).parent().unwrap()).unwrap();
            std::fs::write(hw.join(p), b"").unwrap();
        }
        let exp = |scene: &str, enc, name: &str| {
            case(hw, scene, enc).expected_image(name).map(|p| p.strip_prefix(hw).unwrap().to_path_buf())
        };
        assert_eq!(exp("xml/2020/s.xml", Encoding::Xml, "a.png"), Some("expected/2020/a.png".into()));
        assert_eq!(exp("xml/s.xml", Encoding::Xml, "a.png"), Some("expected/2022/a.png".into()));
        assert_eq!(exp("json/s.json", Encoding::Json, "a.png"), Some("expected/a.png".into()));
        assert_eq!(exp("xml/s.xml", Encoding::Xml, "h.exr"), Some("expected/h.png".into()));
        assert_eq!(exp("xml/s.xml", Encoding::Xml, "none.png"), None);
        // The other year's render of the same image measures the course's
        // noise; an image in no year's folder has none.
        let other =
            |p: &str| Case::other_year(&hw.join(p)).map(|p| p.strip_prefix(hw).unwrap().to_path_buf());
        assert_eq!(other("expected/2022/a.png"), Some("expected/2020/a.png".into()));
        assert_eq!(other("expected/2020/a.png"), Some("expected/2022/a.png".into()));
        assert_eq!(other("expected/h.exr"), None);
        std::fs::remove_file(hw.join("expected/2020/a.png")).unwrap();
        assert_eq!(other("expected/2022/a.png"), None);
    }
}
