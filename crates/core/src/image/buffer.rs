//! A floating-point RGB image that remembers how its values are encoded.
//!
//! [`Rgb32Image`] is what the comparison metrics work on. Whatever the file
//! held (8- or 16-bit, gray, gray+alpha, RGB, RGBA, half or full float) is
//! converted to three `f32` channels per pixel:
//!
//! | file format        | stored values                         | [`Encoding`]        |
//! |--------------------|---------------------------------------|---------------------|
//! | PNG, JPEG          | display-referred, `code / max` ∈ \[0,1\] | [`Encoding::Srgb`]  |
//! | OpenEXR, Radiance HDR | scene-referred linear, unbounded   | [`Encoding::Linear`]|
//!
//! Gray images are replicated to three channels; alpha is dropped (the course's
//! expected images and our renders are opaque). Embedded ICC profiles and PNG
//! `gAMA` chunks are ignored: 8/16-bit files are taken to be sRGB-encoded, as
//! every renderer in the course writes them.
//!
//! The sRGB transfer functions are those of IEC 61966-2-1 (piecewise: linear
//! segment of slope 12.92 below 0.0031308, power 1/2.4 with offset 0.055 above).

use std::io::BufReader;
use std::path::Path;

use image::{DynamicImage, ImageFormat, ImageReader};

use super::error::ImageError;

/// How the values of an [`Rgb32Image`] relate to light.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Display-referred, sRGB-encoded values in [0, 1] (what PNG and JPEG hold).
    Srgb,
    /// Scene-referred linear radiance, possibly above 1 (what EXR and HDR hold).
    Linear,
}

/// A floating-point RGB image, row-major, top row first.
///
/// The fields are public for easy construction in tests and tools; the
/// invariant `pixels.len() == width * height` is checked by
/// [`Rgb32Image::from_pixels`] and again by the comparison functions.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgb32Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` RGB triples, row-major.
    pub pixels: Vec<[f32; 3]>,
    /// How the values are encoded.
    pub encoding: Encoding,
}

impl Rgb32Image {
    /// A black image.
    pub fn new(width: u32, height: u32, encoding: Encoding) -> Self {
        Self { width, height, pixels: vec![[0.0; 3]; width as usize * height as usize], encoding }
    }

    /// An image whose pixel `(x, y)` is `f(x, y)`.
    pub fn from_fn(
        width: u32,
        height: u32,
        encoding: Encoding,
        mut f: impl FnMut(u32, u32) -> [f32; 3],
    ) -> Self {
        let mut pixels = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                pixels.push(f(x, y));
            }
        }
        Self { width, height, pixels, encoding }
    }

    /// Wraps a pixel vector, checking that its length matches the size.
    pub fn from_pixels(
        width: u32,
        height: u32,
        pixels: Vec<[f32; 3]>,
        encoding: Encoding,
    ) -> Result<Self, ImageError> {
        let image = Self { width, height, pixels, encoding };
        image.check_len()?;
        Ok(image)
    }

    /// Converts a decoded image; `encoding` says what its values mean.
    pub fn from_dynamic(image: DynamicImage, encoding: Encoding) -> Self {
        // `into_rgb32f` scales integer samples by 1/max, replicates gray, drops
        // alpha, and leaves float samples untouched.
        let rgb = image.into_rgb32f();
        let (width, height) = rgb.dimensions();
        let pixels = rgb.pixels().map(|p| p.0).collect();
        Self { width, height, pixels, encoding }
    }

    /// Converts an 8-bit sRGB image (such as a render written by the film).
    pub fn from_rgb8(image: &image::RgbImage) -> Self {
        let pixels = image.pixels().map(|p| p.0.map(|c| f32::from(c) / 255.0)).collect();
        Self { width: image.width(), height: image.height(), pixels, encoding: Encoding::Srgb }
    }

    /// Reads a PNG, JPEG, OpenEXR or Radiance HDR file.
    ///
    /// The format is recognised from the file's first bytes, falling back to
    /// the extension. Errors name the file and say whether it is missing,
    /// unreadable, of an unsupported format, or corrupt.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ImageError> {
        let path = path.as_ref();
        // Not a regular file (a folder, a FIFO, a device) or an absurd size:
        // refused before opening, so nothing blocks or runs memory out.
        if let Err(detail) = crate::file::check_regular(path, crate::image::MAX_IMAGE_BYTES) {
            if std::fs::metadata(path).is_ok() {
                let detail =
                    if detail == "it is a folder" { "it is a directory".to_string() } else { detail };
                return Err(ImageError::Unreadable { path: path.to_path_buf(), detail });
            }
        }
        let file = std::fs::File::open(path).map_err(|e| ImageError::from_io(path, &e))?;
        let mut reader = ImageReader::new(BufReader::new(file));
        if let Ok(format) = ImageFormat::from_path(path) {
            reader.set_format(format);
        }
        let reader = reader.with_guessed_format().map_err(|e| ImageError::from_io(path, &e))?;
        let encoding = match reader.format() {
            Some(ImageFormat::Png | ImageFormat::Jpeg) => Encoding::Srgb,
            Some(ImageFormat::OpenExr | ImageFormat::Hdr) => Encoding::Linear,
            Some(other) => {
                return Err(ImageError::Unsupported {
                    path: path.to_path_buf(),
                    detail: format!(
                        "{other:?} images are not read (only PNG, JPEG, OpenEXR and Radiance HDR)"
                    ),
                })
            }
            None => {
                return Err(ImageError::Unsupported {
                    path: path.to_path_buf(),
                    detail: "neither its contents nor its extension identify it as PNG, JPEG, \
                             OpenEXR or Radiance HDR"
                        .to_string(),
                })
            }
        };
        let image = reader.decode().map_err(|e| ImageError::from_decode(path, e))?;
        Ok(Self::from_dynamic(image, encoding))
    }

    /// The number of pixels, `width * height`.
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether the image has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The pixel at `(x, y)`, or `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<[f32; 3]> {
        if x < self.width && y < self.height {
            self.pixels.get(y as usize * self.width as usize + x as usize).copied()
        } else {
            None
        }
    }

    /// Mutable access to the pixel at `(x, y)`, or `None` outside the image.
    pub fn get_mut(&mut self, x: u32, y: u32) -> Option<&mut [f32; 3]> {
        if x < self.width && y < self.height {
            self.pixels.get_mut(y as usize * self.width as usize + x as usize)
        } else {
            None
        }
    }

    /// Checks the `pixels.len() == width * height` invariant.
    pub fn check_len(&self) -> Result<(), ImageError> {
        if self.pixels.len() == self.len() {
            Ok(())
        } else {
            Err(ImageError::BufferSize {
                width: self.width,
                height: self.height,
                len: self.pixels.len(),
                expected: self.len(),
            })
        }
    }

    /// The image as display values in [0, 1]: sRGB images are clamped; linear
    /// images are scaled by `2^exposure`, clamped and sRGB-encoded.
    /// Non-finite samples become 0.
    pub fn to_display(&self, exposure: f32) -> Vec<[f32; 3]> {
        let scale = exposure.exp2();
        match self.encoding {
            Encoding::Srgb => self.pixels.iter().map(|p| p.map(clamp01)).collect(),
            Encoding::Linear => {
                self.pixels.iter().map(|p| p.map(|c| linear_to_srgb(clamp01(c * scale)))).collect()
            }
        }
    }

    /// Converts to an 8-bit sRGB image (display values rounded to nearest).
    pub fn to_rgb8(&self, exposure: f32) -> image::RgbImage {
        let mut out = image::RgbImage::new(self.width, self.height);
        for (dst, src) in out.pixels_mut().zip(self.to_display(exposure)) {
            dst.0 = src.map(quantize8);
        }
        out
    }
}

/// Clamps to [0, 1], sending NaN to 0.
pub(crate) fn clamp01(c: f32) -> f32 {
    if c.is_nan() {
        0.0
    } else {
        c.clamp(0.0, 1.0)
    }
}

/// Rounds a display value in [0, 1] to its 8-bit code.
pub fn quantize8(c: f32) -> u8 {
    // clamp01 bounds the product to [0, 255], so the cast cannot truncate.
    (clamp01(c) * 255.0).round() as u8
}

/// The sRGB decoding function (display value → linear), IEC 61966-2-1.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB encoding function (linear → display value), IEC 61966-2-1.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn srgb_round_trip() {
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5);
        }
    }

    #[test]
    fn png_round_trip_and_gray_conversion() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gray.png");
        let gray = image::GrayImage::from_fn(4, 3, |x, y| image::Luma([(x * 60 + y) as u8]));
        gray.save(&path).unwrap();
        let img = Rgb32Image::load(&path).unwrap();
        assert_eq!((img.width, img.height), (4, 3));
        assert_eq!(img.encoding, Encoding::Srgb);
        let p = img.get(2, 1).unwrap();
        assert!(p.iter().all(|c| (c - 121.0 / 255.0).abs() < 1e-6), "{p:?}");
    }

    #[test]
    fn rgba16_png_drops_alpha() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rgba16.png");
        let img =
            image::ImageBuffer::<image::Rgba<u16>, _>::from_pixel(2, 2, image::Rgba([65535, 0, 32768, 100]));
        img.save(&path).unwrap();
        let loaded = Rgb32Image::load(&path).unwrap();
        let p = loaded.get(1, 1).unwrap();
        assert_eq!(p[0], 1.0);
        assert_eq!(p[1], 0.0);
        assert!((p[2] - 32768.0 / 65535.0).abs() < 1e-6);
    }

    #[test]
    fn exr_is_linear_and_unclamped() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hdr.exr");
        let img = image::Rgb32FImage::from_pixel(3, 2, image::Rgb([2.5, 0.25, 0.0]));
        DynamicImage::ImageRgb32F(img).save(&path).unwrap();
        let loaded = Rgb32Image::load(&path).unwrap();
        assert_eq!(loaded.encoding, Encoding::Linear);
        assert_eq!(loaded.get(2, 1).unwrap(), [2.5, 0.25, 0.0]);
    }

    #[test]
    fn corrupt_png_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("broken_render.png");
        let mut f = std::fs::File::create(&path).unwrap();
        f.write_all(b"this is certainly not a PNG file \x00\x01\x02\x03").unwrap();
        drop(f);
        let err = Rgb32Image::load(&path).unwrap_err();
        assert!(matches!(err, ImageError::Corrupt { .. }), "{err:?}");
        let msg = err.to_string();
        assert!(msg.contains("broken_render.png"), "{msg}");
        assert!(msg.contains("corrupt"), "{msg}");
    }

    #[test]
    fn truncated_png_is_corrupt() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.png");
        let img = image::RgbImage::from_fn(64, 64, |x, y| image::Rgb([x as u8, y as u8, 7]));
        img.save(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let err = Rgb32Image::load(&path).unwrap_err();
        assert!(matches!(err, ImageError::Corrupt { .. }), "{err:?}");
        assert!(err.to_string().contains("cut.png"));
    }

    #[test]
    fn missing_and_unsupported_files() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope.png");
        let err = Rgb32Image::load(&missing).unwrap_err();
        assert!(matches!(err, ImageError::NotFound { .. }), "{err:?}");
        assert!(err.to_string().contains("nope.png"));

        let text = dir.path().join("notes.txt");
        std::fs::write(&text, "hello").unwrap();
        let err = Rgb32Image::load(&text).unwrap_err();
        assert!(matches!(err, ImageError::Unsupported { .. }), "{err:?}");
        assert!(err.to_string().contains("notes.txt"));

        let err = Rgb32Image::load(dir.path()).unwrap_err();
        assert!(matches!(err, ImageError::Unreadable { .. }), "{err:?}");
    }

    #[test]
    fn from_pixels_checks_length() {
        assert!(Rgb32Image::from_pixels(2, 2, vec![[0.0; 3]; 3], Encoding::Srgb).is_err());
        assert!(Rgb32Image::from_pixels(2, 2, vec![[0.0; 3]; 4], Encoding::Srgb).is_ok());
    }
}
