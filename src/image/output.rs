//! Writing rendered images. A render is written to a temporary file beside
//! its destination and renamed into place, so a failure never leaves a
//! half-written image under the real name.

use std::path::{Path, PathBuf};

/// An image could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: cannot write the image: {reason}", path.display())]
pub struct WriteError {
    /// The destination.
    pub path: PathBuf,
    /// Why.
    pub reason: String,
}

/// Writes 8-bit RGB pixels to `path` in the format its extension names (PNG
/// or JPEG), atomically.
pub fn write_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), WriteError> {
    let err = |reason: String| WriteError { path: path.to_path_buf(), reason };
    let format = image::ImageFormat::from_path(path)
        .ok()
        .filter(|f| matches!(f, image::ImageFormat::Png | image::ImageFormat::Jpeg))
        .ok_or_else(|| err("only .png and .jpg/.jpeg outputs are supported for 8-bit images".into()))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| err(crate::scene::io_reason(&e)))?;
    let mut builder = tempfile::Builder::new();
    builder.prefix(".luster-").suffix(".tmp");
    // A temporary file is private (0600) by default; the image is not.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let tmp = builder.tempfile_in(&dir).map_err(|e| err(crate::scene::io_reason(&e)))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file());
        image::write_buffer_with_format(&mut w, rgb, width, height, image::ExtendedColorType::Rgb8, format)
            .map_err(|e| err(e.to_string()))?;
        std::io::Write::flush(&mut w).map_err(|e| err(crate::scene::io_reason(&e)))?;
    }
    tmp.persist(path).map_err(|e| err(crate::scene::io_reason(&e.error)))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_png_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/a.png");
        write_rgb8(&p, 2, 1, &[255, 0, 0, 0, 255, 0]).unwrap();
        let img = image::open(&p).unwrap().to_rgb8();
        assert_eq!(img.get_pixel(1, 0).0, [0, 255, 0]);
        let names: Vec<_> =
            std::fs::read_dir(dir.path().join("sub")).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode & 0o044, 0o044, "the image must be readable by others: {mode:o}");
        }
    }

    #[test]
    fn unsupported_extension_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_rgb8(&dir.path().join("a.xyz"), 1, 1, &[0, 0, 0]).unwrap_err();
        assert!(e.to_string().contains("a.xyz"));
    }
}
