//! Writing rendered images: 8-bit PNG/JPEG and 32-bit float OpenEXR and
//! Radiance HDR. A file is written to a hidden temporary (`.luster-*.tmp`)
//! beside its destination and renamed into place, so a failure never leaves a
//! half-written image under the real name; [`temporaries_in_progress`] lets a
//! program's Ctrl-C or SIGTERM handler remove the temporaries too.

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

/// The temporaries being written right now: what a program's Ctrl-C or
/// SIGTERM handler removes before it exits (the library installs no handler).
pub fn temporaries_in_progress() -> Vec<PathBuf> {
    match TEMPORARIES.lock() {
        Ok(t) => t.clone(),
        Err(p) => p.into_inner().clone(),
    }
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
    if format == image::ImageFormat::Png {
        return write_atomic(path, |w| super::png_writer::write_rgb8(w, width, height, rgb));
    }
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

/// 32-bit float RGB, uncompressed scan lines: the bytes the `exr` crate's
/// own writer gives (a test compares them), written without it. The crate
/// writes the header and a zeroed offset table; the offsets and the lines
/// follow from the size alone (one line a block, each `8 + 12 · width`
/// bytes), so each line is laid out straight from the film into one reused
/// buffer that goes to `w` in writes of [`EXR_CHUNK`] bytes or more, where
/// the crate would zero, fill and copy a `Vec` of its own per line.
/// Uncompressed: RLE and ZIP cost far more time than the bytes they save
/// (`cargo bench --bench film -- --exr-compression` shows both).
fn write_exr(
    w: &mut impl std::io::Write,
    width: usize,
    height: usize,
    pixels: &[Vec3],
) -> Result<(), String> {
    let io = |e: std::io::Error| crate::file::io_reason(&e);
    if width == 0 || height == 0 || pixels.len() != width * height {
        return Err(format!("an EXR of {width}x{height} pixels cannot hold {} pixels", pixels.len()));
    }
    let mut head = exr_head(width, height)?;
    let line_bytes =
        u32::try_from(12 * width).map_err(|_| format!("{width} pixels are too wide for an EXR line"))?;
    // Each line's block, in 4-byte words: its y, its byte count, then the
    // B, G and R samples.
    let words = 2 + 3 * width;
    let table = head.len() - 8 * height;
    let mut at = head.len() as u64;
    for entry in head[table..].chunks_exact_mut(8) {
        entry.copy_from_slice(&at.to_le_bytes());
        at += 4 * words as u64;
    }
    w.write_all(&head).map_err(io)?;
    let lines_per_write = EXR_CHUNK.div_ceil(4 * words).min(height);
    let mut buf = vec![0u32; lines_per_write * words];
    for (k, lines) in pixels.chunks(lines_per_write * width).enumerate() {
        let rows = lines.chunks_exact(width);
        let n = rows.len();
        for (j, (row, out)) in rows.zip(buf.chunks_exact_mut(words)).enumerate() {
            let y = i32::try_from(k * lines_per_write + j)
                .map_err(|_| format!("{height} lines are too many for an EXR"))?;
            let (top, samples) = out.split_at_mut(2);
            top[0] = (y as u32).to_le();
            top[1] = line_bytes.to_le();
            let (b, gr) = samples.split_at_mut(width);
            let (g, r) = gr.split_at_mut(width);
            // One loop reading each pixel once, which the compiler turns
            // into vector loads and shuffles.
            for (((p, b), g), r) in row.iter().zip(b).zip(g).zip(r) {
                *b = sample(p.z);
                *g = sample(p.y);
                *r = sample(p.x);
            }
        }
        w.write_all(as_bytes(&buf[..n * words])).map_err(io)?;
    }
    Ok(())
}

/// A value cleaned as an EXR sample: its bits, little-endian in memory.
#[inline(always)]
fn sample(c: f32) -> u32 {
    clean(c).to_bits().to_le()
}

/// The bytes of `words`, in memory order.
fn as_bytes(words: &[u32]) -> &[u8] {
    // SAFETY: the bytes of initialized `u32`s are initialized, `u8` needs
    // no alignment, and the slice covers exactly the words' memory.
    unsafe { std::slice::from_raw_parts(words.as_ptr().cast::<u8>(), std::mem::size_of_val(words)) }
}

/// Bytes an EXR is handed in each write: at least a [`write_atomic`]
/// `BufWriter`'s capacity, so that it passes them on without copying them.
const EXR_CHUNK: usize = 256 << 10;

/// The header of a `width` × `height` uncompressed 32-bit float RGB EXR (one
/// scan line a block) as the `exr` crate writes it, followed by the line
/// offset table's `8 · height` bytes, zeroed.
fn exr_head(width: usize, height: usize) -> Result<Vec<u8>, String> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, WritableImage,
    };
    let plane = |name: &str| AnyChannel::new(name, FlatSamples::F32(Vec::new()));
    let channels = AnyChannels::sort([plane("R"), plane("G"), plane("B")].into_iter().collect());
    let layer = Layer::new((width, height), LayerAttributes::default(), Encoding::UNCOMPRESSED, channels);
    let headers = Image::from_layer(layer).write().infer_meta_data();
    if headers.len() != 1 || headers[0].chunk_count != height {
        return Err(format!("an EXR of {height} lines must have one block a line"));
    }
    let mut head = std::io::Cursor::new(Vec::new());
    // The crate writes the header and the zeroed table, then asks for the
    // blocks; declining them stops it there.
    match exr::block::write(&mut head, headers, true, |_, _| Err(exr::error::Error::Aborted)) {
        Err(exr::error::Error::Aborted) => {}
        Err(e) => return Err(e.to_string()),
        Ok(()) => return Err("the EXR writer finished without its blocks".into()),
    }
    let head = head.into_inner();
    if head.len() <= 8 * height {
        return Err("the EXR header is shorter than its offset table".into());
    }
    Ok(head)
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
            std::fs::create_dir_all(dir).map_err(|e| crate::file::io_reason(&e))
        }
        Err(e) => Err(crate::file::io_reason(&e)),
    }
}

/// Writes `path` through `encode` into a temporary beside it, then renames
/// it into place: the file appears whole or not at all.
pub fn write_atomic(
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
    let tmp = builder.tempfile_in(&dir).map_err(|e| err(crate::file::io_reason(&e)))?;
    let tmp_path = tmp.path().to_path_buf();
    track(&tmp_path, true);
    let written = (|| {
        {
            // Large writes: an EXR's scan lines are bigger than the default 8 KiB.
            let mut w = std::io::BufWriter::with_capacity(256 << 10, tmp.as_file());
            encode(&mut w)?;
            std::io::Write::flush(&mut w).map_err(|e| crate::file::io_reason(&e))?;
        }
        // The image this one replaces is freed when its last handle closes:
        // holding one across the rename moves that wait (the file system
        // releasing its blocks, no CPU) onto a thread of its own, so the
        // next image or frame does not queue behind it.
        #[cfg(unix)]
        let replaced = std::fs::File::open(path).ok();
        tmp.persist(path).map_err(|e| crate::file::io_reason(&e.error))?;
        #[cfg(unix)]
        if let Some(old) = replaced {
            // If no thread can be made, the handle closes here instead.
            let _ = std::thread::Builder::new().name("luster-release".into()).spawn(move || drop(old));
        }
        Ok(())
    })();
    track(&tmp_path, false);
    written.map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether a temporary under `dir` is still registered (other tests
    /// write theirs at the same time, elsewhere).
    fn tracked_under(dir: &Path) -> bool {
        TEMPORARIES.lock().unwrap().iter().any(|t| t.starts_with(dir))
    }

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
        assert!(!tracked_under(dir.path()));
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode & 0o044, 0o044, "the image must be readable by others: {mode:o}");
        }
    }

    #[test]
    fn replacing_an_image_leaves_the_new_one_whole_and_nothing_else() {
        // The replaced file is released on a thread of its own; a reader
        // that still has it open keeps reading the old bytes.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        write_rgb8(&p, 1, 1, &[1, 2, 3]).unwrap();
        let mut reader = std::fs::File::open(&p).unwrap();
        for v in 0..20u8 {
            write_rgb8(&p, 1, 1, &[v, 2 * v, 3 * v]).unwrap();
            assert_eq!(image::open(&p).unwrap().to_rgb8().get_pixel(0, 0).0, [v, 2 * v, 3 * v]);
        }
        let mut old = Vec::new();
        std::io::Read::read_to_end(&mut reader, &mut old).unwrap();
        let first = image::load_from_memory(&old).unwrap().to_rgb8();
        assert_eq!(first.get_pixel(0, 0).0, [1, 2, 3]);
        assert_eq!(names(dir.path()), vec![std::ffi::OsString::from("a.png")]);
        assert!(!tracked_under(dir.path()));
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
        // Odd sizes, values to clean, more lines than one write.
        let (w, h) = (37usize, 1000usize);
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
