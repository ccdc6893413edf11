//! Writing rendered images: 8-bit PNG/JPEG and 32-bit float OpenEXR and
//! Radiance HDR. A file is written to a hidden temporary (`.luster-*.tmp`)
//! beside its destination and renamed into place, so a failure never leaves a
//! half-written image under the real name; and [`remove_temporaries_on_signal`]
//! makes Ctrl-C or SIGTERM during a write remove the temporary too.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// An image could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write the image: {reason}", path.display())]
pub struct WriteError {
    /// The destination.
    pub path: PathBuf,
    /// Why.
    pub reason: String,
}

/// The extensions the writers take, lower case: 8-bit ones, then HDR ones.
pub const LDR_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg"];
/// See [`LDR_EXTENSIONS`].
pub const HDR_EXTENSIONS: &[&str] = &["exr", "hdr"];

/// Temporaries being written right now, for the signal handler.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Installs a Ctrl-C / SIGTERM handler that removes the temporaries being
/// written and exits with status 130. For programs (the CLI), not libraries:
/// a process has one such handler. Failing to install it is not fatal.
pub fn remove_temporaries_on_signal() -> Result<(), String> {
    ctrlc::set_handler(|| {
        let temps = match TEMPORARIES.lock() {
            Ok(t) => t.clone(),
            Err(p) => p.into_inner().clone(),
        };
        for t in temps {
            let _ = std::fs::remove_file(t);
        }
        std::process::exit(130);
    })
    .map_err(|e| e.to_string())
}

fn track(p: &Path, add: bool) {
    let mut t = TEMPORARIES.lock().unwrap_or_else(|p| p.into_inner());
    if add {
        t.push(p.to_path_buf());
    } else {
        t.retain(|q| q != p);
    }
}

/// Writes 8-bit RGB pixels to `path` in the format its extension names (PNG
/// or JPEG), atomically.
pub fn write_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), WriteError> {
    let format = format_of(path)
        .filter(|f| matches!(f, image::ImageFormat::Png | image::ImageFormat::Jpeg))
        .ok_or_else(|| WriteError {
            path: path.to_path_buf(),
            reason: "only .png and .jpg/.jpeg outputs are supported for 8-bit images".into(),
        })?;
    write_atomic(path, |w| {
        image::write_buffer_with_format(w, rgb, width, height, image::ExtendedColorType::Rgb8, format)
            .map_err(|e| e.to_string())
    })
}

/// Writes linear RGB (`3 · width · height` floats) to `path` as 32-bit float
/// OpenEXR (`.exr`) or Radiance RGBE (`.hdr`), atomically.
pub fn write_rgb32f(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<(), WriteError> {
    let format = format_of(path)
        .filter(|f| matches!(f, image::ImageFormat::OpenExr | image::ImageFormat::Hdr))
        .ok_or_else(|| WriteError {
            path: path.to_path_buf(),
            reason: "only .exr and .hdr outputs are supported for HDR images".into(),
        })?;
    if rgb.len() != 3 * width as usize * height as usize {
        return Err(WriteError {
            path: path.to_path_buf(),
            reason: "the pixel buffer does not match the size".into(),
        });
    }
    // Neither format holds a NaN or an infinity usefully: the course's EXRs
    // have none, and RGBE cannot encode them.
    let clean = |c: f32| if c.is_finite() { c.max(0.0) } else { 0.0 };
    if format == image::ImageFormat::OpenExr {
        return write_atomic(path, |w| write_exr(w, width as usize, height as usize, rgb, clean));
    }
    let bytes: Vec<u8> = rgb.iter().flat_map(|&c| clean(c).to_ne_bytes()).collect();
    write_atomic(path, |w| {
        image::write_buffer_with_format(w, &bytes, width, height, image::ExtendedColorType::Rgb32F, format)
            .map_err(|e| e.to_string())
    })
}

/// 32-bit float RGB, uncompressed scan lines, from planar channels. The
/// `image` crate's encoder (RLE on 64×64 tiles, pixel by pixel through a
/// closure) and ZIP compression each cost a fifth of a simple 800×800
/// render; planar uncompressed data is close to a copy
/// (`cargo bench --bench film`). The files are larger (12 bytes a pixel).
fn write_exr(
    w: &mut std::io::BufWriter<&std::fs::File>,
    width: usize,
    height: usize,
    rgb: &[f32],
    clean: impl Fn(f32) -> f32 + Sync,
) -> Result<(), String> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
        WritableImage,
    };
    let plane = |c: usize| FlatSamples::F32(rgb.chunks_exact(3).map(|p| clean(p[c])).collect());
    let (r, (g, b)) = rayon::join(|| plane(0), || rayon::join(|| plane(1), || plane(2)));
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("R", r),
        AnyChannel::new("G", g),
        AnyChannel::new("B", b),
    ]));
    let layer = Layer::new((width, height), LayerAttributes::default(), Encoding::UNCOMPRESSED, channels);
    Image::from_layer(layer).write().non_parallel().to_buffered(w).map_err(|e| e.to_string())
}

fn format_of(path: &Path) -> Option<image::ImageFormat> {
    image::ImageFormat::from_path(path).ok()
}

/// Why a folder cannot hold the image, in words that are true for symlinks to
/// devices and files too (`create_dir_all` would say "File exists").
fn check_folder(dir: &Path) -> Result<(), String> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(format!("the output folder {} is not a folder", dir.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            std::fs::create_dir_all(dir).map_err(|e| crate::scene::io_reason(&e))
        }
        Err(e) => Err(crate::scene::io_reason(&e)),
    }
}

pub(crate) fn write_atomic(
    path: &Path,
    encode: impl FnOnce(&mut std::io::BufWriter<&std::fs::File>) -> Result<(), String>,
) -> Result<(), WriteError> {
    let err = |reason: String| WriteError { path: path.to_path_buf(), reason };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    check_folder(&dir).map_err(err)?;
    let mut builder = tempfile::Builder::new();
    builder.prefix(".luster-").suffix(".tmp");
    // A temporary file is private (0600) by default; the image is not.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let tmp = builder.tempfile_in(&dir).map_err(|e| err(crate::scene::io_reason(&e)))?;
    let tmp_path = tmp.path().to_path_buf();
    track(&tmp_path, true);
    let written = (|| {
        {
            let mut w = std::io::BufWriter::new(tmp.as_file());
            encode(&mut w)?;
            std::io::Write::flush(&mut w).map_err(|e| crate::scene::io_reason(&e))?;
        }
        tmp.persist(path).map_err(|e| crate::scene::io_reason(&e.error))?;
        Ok(())
    })();
    track(&tmp_path, false);
    written.map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<std::ffi::OsString> {
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name()).collect()
    }

    #[test]
    fn writes_png_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/a.png");
        write_rgb8(&p, 2, 1, &[255, 0, 0, 0, 255, 0]).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.get_pixel(1, 0).0, [0, 255, 0]);
        assert_eq!(names(&dir.path().join("sub")).len(), 1);
        assert!(TEMPORARIES.lock().unwrap().is_empty());
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode & 0o044, 0o044, "the image must be readable by others: {mode:o}");
        }
    }

    #[test]
    fn exr_and_hdr_keep_values_above_one() {
        let dir = tempfile::tempdir().unwrap();
        let px = [1000.0, 0.5, 0.0, 0.25, 3.0, 70000.0];
        let p = dir.path().join("a.exr");
        write_rgb32f(&p, 2, 1, &px).unwrap();
        let back = image::open(&p).unwrap().to_rgb32f();
        assert_eq!(back.as_raw().as_slice(), &px, "EXR is lossless 32-bit float");
        let h = dir.path().join("a.hdr");
        write_rgb32f(&h, 2, 1, &px).unwrap();
        let back = image::open(&h).unwrap().to_rgb32f();
        for (a, b) in back.as_raw().iter().zip(px) {
            // RGBE keeps 8 bits of mantissa per channel relative to the largest channel.
            let tol = px.iter().copied().fold(0.0f32, f32::max) / 128.0;
            assert!((a - b).abs() <= tol.max(b * 0.01), "{a} vs {b}");
        }
        assert_eq!(names(dir.path()).len(), 2);
    }

    #[test]
    fn unsupported_extension_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_rgb8(&dir.path().join("a.xyz"), 1, 1, &[0, 0, 0]).unwrap_err();
        assert!(e.to_string().contains("a.xyz"));
        let e = write_rgb32f(&dir.path().join("a.png"), 1, 1, &[0.0; 3]).unwrap_err();
        assert!(e.to_string().contains("a.png"));
    }

    #[cfg(unix)]
    #[test]
    fn a_folder_that_is_a_device_says_so() {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("out");
        std::os::unix::fs::symlink("/dev/null", &link).unwrap();
        let e = write_rgb8(&link.join("a.png"), 1, 1, &[0, 0, 0]).unwrap_err().to_string();
        assert!(e.contains("is not a folder"), "{e}");
        assert!(!e.contains("File exists"), "{e}");
    }
}
