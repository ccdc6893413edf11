//! One row of the report per camera image (or per scene that failed before
//! rendering any): the serialisable entries, their verdicts, and how they are
//! built from the [`conformance`](crate::conformance) results, with the
//! expected images copied and the thumbnails made on the way ([`super::assets`]).

use super::assets;
use super::metrics::{metrics, Metrics};
use crate::conformance::{CaseResult, HdrResult, ImageResult, Rule};
use serde::Serialize;
use std::path::Path;

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

pub(super) fn scene_entry(r: &CaseResult, root: &Path, outdir: &Path) -> SceneEntry {
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
