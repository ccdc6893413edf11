//! The one error type of the image module.
//!
//! Every message is a single sentence that names the file (or, for a
//! comparison, both image sizes) and says what is wrong with it, so the CLI can
//! print it as is: "image file `out.png` is corrupt or truncated: ...".
//! The underlying codec or I/O error is folded into the sentence rather than
//! kept as an error `source`, so that `anyhow`'s `{:#}` does not print it twice.

use std::path::{Path, PathBuf};

/// Why an image could not be loaded, written or compared.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The path does not exist.
    #[error("image file `{}` does not exist", path.display())]
    NotFound {
        /// The file that was asked for.
        path: PathBuf,
    },
    /// The file exists but could not be read (permissions, a directory, I/O failure).
    #[error("could not read image file `{}`: {detail}", path.display())]
    Unreadable {
        /// The file that was asked for.
        path: PathBuf,
        /// What the operating system said.
        detail: String,
    },
    /// The file is not in one of the formats we read (PNG, JPEG, OpenEXR, Radiance HDR),
    /// or uses a variant of the format the decoder does not support.
    #[error("image file `{}` is in an unsupported format: {detail}", path.display())]
    Unsupported {
        /// The offending file.
        path: PathBuf,
        /// Which format or feature is unsupported.
        detail: String,
    },
    /// The file claims a supported format but its contents do not decode.
    #[error("image file `{}` is corrupt or truncated: {detail}", path.display())]
    Corrupt {
        /// The offending file.
        path: PathBuf,
        /// What the decoder said.
        detail: String,
    },
    /// Writing an image (for example a heatmap) failed.
    #[error("could not write image file `{}`: {detail}", path.display())]
    Write {
        /// The file we tried to write.
        path: PathBuf,
        /// What the encoder or the operating system said.
        detail: String,
    },
    /// Two images of different sizes were given to a comparison.
    #[error(
        "cannot compare images of different sizes: the reference is {}×{} pixels but the test image is {}×{}",
        reference.0, reference.1, test.0, test.1
    )]
    SizeMismatch {
        /// Width and height of the reference image.
        reference: (u32, u32),
        /// Width and height of the test image.
        test: (u32, u32),
    },
    /// A pixel buffer whose length does not match its stated size.
    #[error("image buffer holds {len} pixels but its stated size {width}×{height} needs {expected}")]
    BufferSize {
        /// Stated width.
        width: u32,
        /// Stated height.
        height: u32,
        /// Number of pixels actually present.
        len: usize,
        /// `width * height`.
        expected: usize,
    },
    /// A comparison of images without pixels.
    #[error("cannot compare images with no pixels ({width}×{height})")]
    Empty {
        /// Width of the images.
        width: u32,
        /// Height of the images.
        height: u32,
    },
}

impl ImageError {
    /// Classifies an I/O error met while opening or reading `path`.
    pub(crate) fn from_io(path: &Path, err: &std::io::Error) -> Self {
        match err.kind() {
            std::io::ErrorKind::NotFound => ImageError::NotFound { path: path.to_path_buf() },
            std::io::ErrorKind::UnexpectedEof => {
                ImageError::Corrupt { path: path.to_path_buf(), detail: "the file ends early".to_string() }
            }
            _ => ImageError::Unreadable { path: path.to_path_buf(), detail: err.to_string() },
        }
    }

    /// Classifies an error from the `image` crate's decoders.
    pub(crate) fn from_decode(path: &Path, err: image::ImageError) -> Self {
        use image::ImageError as Codec;
        let path = path.to_path_buf();
        match err {
            Codec::IoError(io) => Self::from_io(&path, &io),
            Codec::Unsupported(e) => ImageError::Unsupported { path, detail: e.to_string() },
            Codec::Limits(e) => ImageError::Unsupported {
                path,
                detail: format!("the image exceeds the decoder's limits ({e})"),
            },
            Codec::Decoding(e) => ImageError::Corrupt { path, detail: e.to_string() },
            Codec::Parameter(e) => ImageError::Corrupt { path, detail: e.to_string() },
            Codec::Encoding(e) => ImageError::Corrupt { path, detail: e.to_string() },
        }
    }
}
