//! The report folder's images: copies of the expected images, browser
//! previews of EXR/HDR files, and thumbnails.
//!
//! Expected images are copied to `expected/<path under the course folder>`
//! (`expected/hw1/expected/2022/simple.png`), so two homeworks' images of the
//! same name cannot collide. A browser cannot show OpenEXR or Radiance HDR, so
//! beside such a copy goes `<name>.preview.png`: the image exposed at 0 stops,
//! clamped and sRGB-encoded — the same display values the comparison used.
//! Thumbnails are PNGs at most [`THUMB_WIDTH`] pixels wide under `thumbs/`,
//! named after the file's path inside the report folder.

use crate::image::Rgb32Image;
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
    img.to_rgb8(0.0)
        .save(&preview)
        .map_err(|e| format!("could not write the preview `{}`: {e}", preview.display()))?;
    Ok(ExpectedCopy { shown: preview, original: Some(dst) })
}

/// Writes a thumbnail of `image` (a PNG or JPEG inside `outdir`) and returns
/// its path relative to `outdir`.
pub fn thumbnail(image: &Path, outdir: &Path) -> Result<String, String> {
    let rel = relative(image, outdir);
    let name = format!("{}.png", rel.replace('/', "__"));
    let dst = outdir.join("thumbs").join(&name);
    let img = image::open(image)
        .map_err(|e| format!("could not read `{}` for its thumbnail: {e}", image.display()))?
        .to_rgb8();
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
