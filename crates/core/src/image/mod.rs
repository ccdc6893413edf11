//! Reading and writing images.
//!
//! - [`buffer`]: [`Rgb32Image`], a float RGB image loaded from PNG, JPEG,
//!   OpenEXR or Radiance HDR, remembering whether its values are sRGB-encoded
//!   or linear.
//! - [`output`]: atomic PNG/JPEG/EXR/HDR writers (the PNG encoder in
//!   [`png_writer`]).
//! - [`outputs`]: which files a camera's `ImageName` and `Tonemap`s ask for.
//! - [`error`]: [`ImageError`], one sentence naming the file and the problem.

pub mod buffer;
pub mod error;
pub mod output;
pub mod outputs;
pub mod png_writer;

pub use buffer::{Encoding, Rgb32Image};
pub use error::ImageError;

/// Largest image file any loader accepts (textures, compared images), in bytes.
pub const MAX_IMAGE_BYTES: u64 = 1 << 30;
