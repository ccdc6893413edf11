//! The report folder's images: copies of the expected images, browser
//! previews of EXR/HDR files, and thumbnails.
//!
//! Expected images are copied to `expected/<path under the course folder>`
//! (`expected/hw1/expected/2022/simple.png`), so two homeworks' images of the
//! same name cannot collide. A browser cannot show OpenEXR or Radiance HDR, so
//! beside such a copy goes `<name>.preview.png`, tone-mapped by
//! [`tonemap_like`] with the image's own key.
//! Thumbnails are PNGs at most [`THUMB_WIDTH`] pixels wide under `thumbs/`,
//! named after the file's path inside the report folder. An HDR row's pair of
//! linear images (ours and the course's) gets thumbnails tone-mapped by one
//! curve, the one the course's image calls for, so that a difference in
//! brightness stays visible ([`hdr_thumbnails`]).

use luster_core::image::Rgb32Image;
use std::path::{Component, Path, PathBuf};

/// Largest thumbnail width in pixels (shown at half that on the page, so they
/// stay sharp on high-density screens).
pub const THUMB_WIDTH: u32 = 224;

/// `path` relative to `base`, with `/` separators (the path itself, made
/// `/`-separated, if it is not under `base`).
pub fn relative(path: &Path, base: &Path) -> String {
    let rel = path.strip_prefix(base).unwrap_or(path);
    rel.components()
        .filter_map(|c| match c {
            Component::Normal(s) => Some(s.to_string_lossy().into_owned()),
            _ => None,
        })
        .collect::<Vec<_>>()
        .join("/")
}

/// Where a copied expected image went.
pub struct ExpectedCopy {
    /// The file the page shows (the copy, or its PNG preview).
    pub shown: PathBuf,
    /// The copy of the original, when a preview is shown instead.
    pub original: Option<PathBuf>,
}

/// Copies an expected image into `outdir/expected/` and, for EXR/HDR, writes
/// a PNG preview beside it.
pub fn copy_expected(src: &Path, root: &Path, outdir: &Path) -> Result<ExpectedCopy, String> {
    let rel = match src.strip_prefix(root) {
        Ok(r) => PathBuf::from(relative(r, Path::new(""))),
        Err(_) => PathBuf::from(src.file_name().unwrap_or_default()),
    };
    let dst = outdir.join("expected").join(rel);
    if let Some(dir) = dst.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("could not create the folder `{}`: {e}", dir.display()))?;
    }
    std::fs::copy(src, &dst)
        .map_err(|e| format!("could not copy the expected image `{}`: {e}", src.display()))?;
    let ext = dst.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if matches!(ext.as_deref(), Some("png" | "jpg" | "jpeg")) {
        return Ok(ExpectedCopy { shown: dst, original: None });
    }
    let preview = dst.with_file_name(format!(
        "{}.preview.png",
        dst.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
    ));
    let img = Rgb32Image::load(&dst).map_err(|e| e.to_string())?;
    tonemap_like(&img, &img)
        .save(&preview)
        .map_err(|e| format!("could not write the preview `{}`: {e}", preview.display()))?;
    Ok(ExpectedCopy { shown: preview, original: Some(dst) })
}

/// The key value of the photographic operator (Reinhard et al. 2002, and
/// hw5's default).
const KEY: f64 = 0.18;

/// `image` (linear radiance) tone-mapped for display by Reinhard et al.'s
/// global photographic operator, `L / (1 + L)` with `L = key / Ȳ · Y`, where
/// `Ȳ` is the log-average luminance of `keyed_by`'s non-black pixels, and
/// sRGB-encoded. Keying
/// two images by the same one maps them by the same curve.
pub fn tonemap_like(keyed_by: &Rgb32Image, image: &Rgb32Image) -> image::RgbImage {
    let lum = |p: &[f32; 3]| {
        let y = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        if y.is_finite() && y > 0.0 {
            y
        } else {
            0.0
        }
    };
    // Over the lit pixels only: a black background would drag the
    // log-average down and wash the thumbnail out to white.
    let (log_sum, n) = keyed_by
        .pixels
        .iter()
        .map(lum)
        .filter(|&y| y > 0.0)
        .fold((0.0f64, 0usize), |(s, n), y| (s + f64::from(y).ln(), n + 1));
    let log_avg = if n == 0 { 1.0 } else { (log_sum / n as f64).exp() };
    let scale = (KEY / log_avg) as f32;
    let mut out = image::RgbImage::new(image.width, image.height);
    for (dst, p) in out.pixels_mut().zip(&image.pixels) {
        let y = lum(p);
        if y > 0.0 {
            let l = y * scale;
            let ratio = l / (1.0 + l) / y;
            dst.0 = p.map(|c| {
                let v = (c * ratio).clamp(0.0, 1.0);
                (luster_core::image::buffer::linear_to_srgb(if v.is_nan() { 0.0 } else { v }) * 255.0).round()
                    as u8
            });
        }
    }
    out
}

/// Thumbnails of an HDR row's two linear images, ours and the course's
/// (both inside `outdir`), tone-mapped alike by [`tonemap_like`] keyed by
/// the course's; returns their paths relative to `outdir` (ours first).
pub fn hdr_thumbnails(ours: &Path, expected: &Path, outdir: &Path) -> Result<[String; 2], String> {
    let reference = Rgb32Image::load(expected).map_err(|e| e.to_string())?;
    let test = Rgb32Image::load(ours).map_err(|e| e.to_string())?;
    let thumb = |path: &Path, img: &Rgb32Image| save_thumbnail(tonemap_like(&reference, img), path, outdir);
    Ok([thumb(ours, &test)?, thumb(expected, &reference)?])
}

/// Writes a thumbnail of `image` (a PNG or JPEG inside `outdir`) and returns
/// its path relative to `outdir`.
pub fn thumbnail(image: &Path, outdir: &Path) -> Result<String, String> {
    let img = image::open(image)
        .map_err(|e| format!("could not read `{}` for its thumbnail: {e}", image.display()))?
        .to_rgb8();
    save_thumbnail(img, image, outdir)
}

/// Shrinks `img` (the picture of the file `source`) and writes it under
/// `outdir/thumbs/`, named after `source`'s path in the report folder.
fn save_thumbnail(img: image::RgbImage, source: &Path, outdir: &Path) -> Result<String, String> {
    let rel = relative(source, outdir);
    let name = format!("{}.png", rel.replace('/', "__"));
    let dst = outdir.join("thumbs").join(&name);
    let (w, h) = img.dimensions();
    let thumb = if w > THUMB_WIDTH {
        let th = ((u64::from(h) * u64::from(THUMB_WIDTH)) / u64::from(w.max(1))).max(1) as u32;
        image::imageops::thumbnail(&img, THUMB_WIDTH, th)
    } else {
        img
    };
    if let Some(dir) = dst.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("could not create the folder `{}`: {e}", dir.display()))?;
    }
    thumb.save(&dst).map_err(|e| format!("could not write the thumbnail `{}`: {e}", dst.display()))?;
    Ok(format!("thumbs/{name}"))
}
