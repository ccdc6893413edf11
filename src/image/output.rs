//! Writing rendered images: 8-bit PNG/JPEG and 32-bit float OpenEXR and
//! Radiance HDR. A file is written to a hidden temporary (`.luster-*.tmp`)
//! beside its destination and renamed into place, so a failure never leaves a
//! half-written image under the real name; and [`remove_temporaries_on_signal`]
//! makes Ctrl-C or SIGTERM during a write remove the temporary too.

use crate::math::Vec3;
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

/// Writes linear RGB pixels (row-major, top row first) to `path` as 32-bit
/// float OpenEXR (`.exr`) or Radiance RGBE (`.hdr`), atomically.
pub fn write_rgb32f(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<(), WriteError> {
    let format = format_of(path)
        .filter(|f| matches!(f, image::ImageFormat::OpenExr | image::ImageFormat::Hdr))
        .ok_or_else(|| WriteError {
            path: path.to_path_buf(),
            reason: "only .exr and .hdr outputs are supported for HDR images".into(),
        })?;
    if pixels.len() != width as usize * height as usize {
        return Err(WriteError {
            path: path.to_path_buf(),
            reason: "the pixel buffer does not match the size".into(),
        });
    }
    if format == image::ImageFormat::OpenExr {
        return write_atomic(path, |w| write_exr(w, width as usize, height as usize, pixels));
    }
    let bytes: Vec<u8> =
        pixels.iter().flat_map(|p| p.to_array()).flat_map(|c| clean(c).to_ne_bytes()).collect();
    write_atomic(path, |w| {
        image::write_buffer_with_format(w, &bytes, width, height, image::ExtendedColorType::Rgb32F, format)
            .map_err(|e| e.to_string())
    })
}

/// Neither format holds a NaN or an infinity usefully (the course's EXRs have
/// none, RGBE cannot encode them), nor a negative value: they become 0.
#[inline]
fn clean(c: f32) -> f32 {
    if c.is_finite() {
        c.max(0.0)
    } else {
        0.0
    }
}

/// 32-bit float RGB, uncompressed scan lines. The `exr` crate writes the
/// header and offset table; [`ExrPixels`] lays each scan line's samples out
/// straight from the film, so the image is read once and never copied into
/// planes first. Compression does not pay: RLE and ZIP each cost a fifth of
/// a simple 800×800 render (`cargo bench --bench film`), for 12 bytes a
/// pixel written.
fn write_exr(
    w: impl std::io::Write + std::io::Seek,
    width: usize,
    height: usize,
    pixels: &[Vec3],
) -> Result<(), String> {
    use exr::prelude::{Encoding, Image, Layer, LayerAttributes, WritableImage};
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        ExrPixels { pixels, width },
    );
    Image::from_layer(layer).write().non_parallel().to_buffered(w).map_err(|e| e.to_string())
}

/// A film's pixels as the channels `B`, `G`, `R` (an EXR's channels are
/// stored in name order) of `f32` samples.
struct ExrPixels<'a> {
    pixels: &'a [Vec3],
    width: usize,
}

/// The channels in the order the file stores them (the blue, green and red
/// components: see `extract_uncompressed_block`).
const EXR_CHANNELS: [&str; 3] = ["B", "G", "R"];

impl<'a> exr::image::write::channels::WritableChannels<'a> for ExrPixels<'a> {
    type Writer = &'a ExrPixels<'a>;

    fn infer_channel_list(&self) -> exr::meta::attribute::ChannelList {
        use exr::prelude::{ChannelDescription, SampleType};
        exr::meta::attribute::ChannelList::new(
            EXR_CHANNELS.iter().map(|name| ChannelDescription::named(*name, SampleType::F32)).collect(),
        )
    }

    fn infer_level_modes(&self) -> (exr::meta::attribute::LevelMode, exr::math::RoundingMode) {
        (exr::meta::attribute::LevelMode::Singular, exr::math::RoundingMode::Down)
    }

    fn create_writer(&'a self, _: &exr::meta::header::Header) -> Self::Writer {
        self
    }
}

impl exr::image::write::channels::ChannelsWriter for &ExrPixels<'_> {
    /// The block's lines top to bottom, each holding its `B`, then `G`, then
    /// `R` samples left to right, in native byte order (the crate converts).
    fn extract_uncompressed_block(
        &self,
        _: &exr::meta::header::Header,
        block: exr::block::BlockIndex,
    ) -> Vec<u8> {
        let (x0, y0) = (block.pixel_position.x(), block.pixel_position.y());
        let (w, h) = (block.pixel_size.width(), block.pixel_size.height());
        let mut out = vec![0u8; 4 * 3 * w * h];
        let lines = out.chunks_exact_mut(4 * 3 * w);
        for (y, line) in (y0..y0 + h).zip(lines) {
            let row = &self.pixels[y * self.width + x0..][..w];
            let (b, gr) = line.split_at_mut(4 * w);
            let (g, r) = gr.split_at_mut(4 * w);
            // One loop per channel with the component fixed, so each is a
            // straight copy the compiler vectorizes (indexing a `Vec3` by a
            // variable component is a branch per sample).
            lay_out(b, row, |p| p.z);
            lay_out(g, row, |p| p.y);
            lay_out(r, row, |p| p.x);
        }
        out
    }
}

/// `component` of each pixel of `row`, cleaned, as native-endian `f32` samples.
#[inline(always)]
fn lay_out(samples: &mut [u8], row: &[Vec3], component: impl Fn(&Vec3) -> f32) {
    for (s, p) in samples.chunks_exact_mut(4).zip(row) {
        s.copy_from_slice(&clean(component(p)).to_ne_bytes());
    }
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
            // Large writes: an EXR's scan lines are bigger than the default 8 KiB.
            let mut w = std::io::BufWriter::with_capacity(256 << 10, tmp.as_file());
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
        let v = [Vec3::new(1000.0, 0.5, 0.0), Vec3::new(0.25, 3.0, 70000.0)];
        let p = dir.path().join("a.exr");
        write_rgb32f(&p, 2, 1, &v).unwrap();
        let back = image::open(&p).unwrap().to_rgb32f();
        assert_eq!(back.as_raw().as_slice(), &px, "EXR is lossless 32-bit float");
        let h = dir.path().join("a.hdr");
        write_rgb32f(&h, 2, 1, &v).unwrap();
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
        let e = write_rgb32f(&dir.path().join("a.png"), 1, 1, &[Vec3::ZERO]).unwrap_err();
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

    #[test]
    fn exr_lines_are_laid_out_as_the_crates_own_flat_sample_writer_does() {
        use exr::prelude::{
            AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
            WritableImage,
        };
        // Odd sizes, values to clean, more lines than one block.
        let (w, h) = (37usize, 23usize);
        let px: Vec<Vec3> = (0..w * h)
            .map(|i| match i % 11 {
                0 => Vec3::new(f32::NAN, -1.0, f32::INFINITY),
                k => Vec3::new(i as f32 * 0.25, k as f32 * 1e3, 1.0 / (i as f32 + 1.0)),
            })
            .collect();
        let mut ours = std::io::Cursor::new(Vec::new());
        write_exr(&mut ours, w, h, &px).unwrap();
        let ours = ours.into_inner();
        let plane = |c: usize| FlatSamples::F32(px.iter().map(|p| clean(p[c])).collect());
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            AnyChannel::new("R", plane(0)),
            AnyChannel::new("G", plane(1)),
            AnyChannel::new("B", plane(2)),
        ]));
        let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::UNCOMPRESSED, channels);
        let mut theirs = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer).write().non_parallel().to_buffered(&mut theirs).unwrap();
        let theirs = theirs.into_inner();
        assert!(ours.len() > 12 * w * h, "{} bytes", ours.len());
        assert!(ours == theirs, "the EXR bytes differ from the exr crate's generic writer");
    }
}
