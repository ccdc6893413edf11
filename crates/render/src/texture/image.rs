//! Image textures: decoded texels, an optional mipmap pyramid, and nearest,
//! bilinear and trilinear lookups.
//!
//! Texel values keep the file's scale: 0–255 for 8- and 16-bit images (16-bit
//! ones are scaled down), linear floats for EXR and HDR. The texture map's
//! `Normalizer` turns them into reflectances later, as the course specifies.
//!
//! Addressing follows the course: `(u, v) = (0, 0)` is the top-left corner of
//! the image, `v` grows downwards, and texel `(i, j)` covers
//! `[i, i+1) × [j, j+1)` in the continuous coordinates `(u·W, v·H)`. Outside
//! [0, 1] the image repeats. Bilinear filtering weights the four texels whose
//! centres surround the point and repeats the edge texel beyond the border
//! (the hw4 text's advice), so a texture stretched over a quad has no seam of
//! averaged opposite edges. Like the course, bilinear weights are the
//! fractional parts of `(u·W, v·H)` themselves: texel `(i, j)` has full
//! weight at `(i, j)`, not at its centre `(i + ½, j + ½)`. The references
//! show it clearly (hw4 `cube_wall`), so luster follows it rather than shift
//! every texture by half a texel.
//!
//! Mipmaps are built only for images that a trilinear map uses: each level
//! averages 2×2 texels of the one below (an odd edge's last texel is counted
//! with its neighbour), down to 1×1.

use luster_core::math::{Vec2, Vec3};
use std::path::Path;

/// Texels of one level, in the file's precision.
enum Texels {
    Ldr(Vec<[u8; 3]>),
    Hdr(Vec<[f32; 3]>),
}

/// One level of the pyramid.
struct Level {
    width: u32,
    height: u32,
    texels: Texels,
}

impl Level {
    #[inline]
    fn fetch(&self, x: u32, y: u32) -> Vec3 {
        let i = (y * self.width + x) as usize;
        match &self.texels {
            Texels::Ldr(t) => {
                let [r, g, b] = t[i];
                Vec3::new(r as f32, g as f32, b as f32)
            }
            Texels::Hdr(t) => Vec3::from_array(t[i]),
        }
    }

    /// Texel `(x, y)` with `x`, `y` clamped to the image (the edge repeats).
    #[inline]
    fn fetch_clamped(&self, x: i64, y: i64) -> Vec3 {
        let x = x.clamp(0, self.width as i64 - 1) as u32;
        let y = y.clamp(0, self.height as i64 - 1) as u32;
        self.fetch(x, y)
    }

    /// The continuous texel coordinates of `uv`, wrapped into the image.
    #[inline]
    fn coords(&self, uv: Vec2) -> (f32, f32) {
        let u = uv.x - luster_core::math::floor(uv.x);
        let v = uv.y - luster_core::math::floor(uv.y);
        (u * self.width as f32, v * self.height as f32)
    }

    fn nearest(&self, uv: Vec2) -> Vec3 {
        let (x, y) = self.coords(uv);
        self.fetch_clamped(x as i64, y as i64)
    }

    fn bilinear(&self, uv: Vec2) -> Vec3 {
        let (x, y) = self.coords(uv);
        // The course weights texels as if their centres sat at integer
        // coordinates, half a texel up and left of where they are (hw4
        // cube_wall).
        let (x0, y0) = (luster_core::math::floor(x), luster_core::math::floor(y));
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.fetch_clamped(x0, y0) * (1.0 - fx) + self.fetch_clamped(x0 + 1, y0) * fx;
        let bottom = self.fetch_clamped(x0, y0 + 1) * (1.0 - fx) + self.fetch_clamped(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The next level down: 2×2 averages.
    fn halve(&self) -> Level {
        let (w, h) = ((self.width / 2).max(1), (self.height / 2).max(1));
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let (x0, y0) = (x * 2, y * 2);
                let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
                let s = self.fetch(x0, y0) + self.fetch(x1, y0) + self.fetch(x0, y1) + self.fetch(x1, y1);
                out.push(s * 0.25);
            }
        }
        let texels = match self.texels {
            Texels::Ldr(_) => {
                Texels::Ldr(out.iter().map(|c| c.to_array().map(|v| v.round() as u8)).collect())
            }
            Texels::Hdr(_) => Texels::Hdr(out.iter().map(|c| c.to_array()).collect()),
        };
        Level { width: w, height: h, texels }
    }
}

/// Packed RGB bytes as texels, in the same memory where the sizes allow
/// (always, for a decoder's exact-size buffer): a copy would add to the
/// longest image's decode, which is what a small render waits for.
fn rgb_texels(raw: Vec<u8>) -> Vec<[u8; 3]> {
    if raw.len() % 3 != 0 || raw.capacity() % 3 != 0 {
        return raw.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    }
    let mut raw = std::mem::ManuallyDrop::new(raw);
    // SAFETY: `[u8; 3]` has `u8`'s alignment and three times its size, so
    // the allocation of `capacity` bytes is one of `capacity / 3` texels,
    // of which the first `len / 3` are initialized; `raw` is not dropped.
    unsafe { Vec::from_raw_parts(raw.as_mut_ptr().cast::<[u8; 3]>(), raw.len() / 3, raw.capacity() / 3) }
}

/// Which of an image's channels become its texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channels {
    /// Red, green and blue (grey images repeat their one channel).
    Rgb,
    /// Alpha, as grey (fully opaque where the image has no alpha).
    Alpha,
}

/// A decoded image with its mipmap levels (level 0 only until
/// [`Image::build_mipmaps`]).
pub struct Image {
    levels: Vec<Level>,
    hdr: bool,
}

/// Largest edge accepted, in texels: far beyond any texture a scene needs, and
/// small enough that a corrupt header cannot ask for gigabytes.
pub const MAX_EDGE: u32 = 32768;

impl Image {
    /// Decodes an image file (PNG, JPEG, EXR, HDR; anything the `image` crate reads).
    pub fn load(path: &Path) -> Result<Image, String> {
        Image::load_channels(path, Channels::Rgb)
    }

    /// Decodes an image file into the texels `channels` says.
    pub fn load_channels(path: &Path, channels: Channels) -> Result<Image, String> {
        let (file, _) = luster_core::file::open_regular(path, luster_core::image::MAX_IMAGE_BYTES)
            .map_err(|why| format!("cannot open {}: {why}", path.display()))?;
        let mut file = std::io::BufReader::new(file);
        let start = std::io::BufRead::fill_buf(&mut file)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        if super::exr_header::is_exr(start) {
            super::exr_header::check(path)?;
        }
        let mut reader = ::image::ImageReader::new(file);
        if let Ok(format) = ::image::ImageFormat::from_path(path) {
            reader.set_format(format);
        }
        let reader =
            reader.with_guessed_format().map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let img = reader.decode().map_err(|e| format!("cannot decode image {}: {e}", path.display()))?;
        Image::from_dynamic(img, channels, &path.display().to_string())
    }

    /// Decodes a PNG or JPEG image held in memory (one inside a glTF file);
    /// `name` names it in messages.
    pub fn decode_bytes(bytes: &[u8], name: &str, channels: Channels) -> Result<Image, String> {
        let reader = ::image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("cannot read image {name}: {e}"))?;
        // Formats with headers of their own to check (EXR) are files only.
        if !matches!(reader.format(), Some(::image::ImageFormat::Png | ::image::ImageFormat::Jpeg)) {
            return Err(format!("image {name} is not a PNG or JPEG image"));
        }
        let img = reader.decode().map_err(|e| format!("cannot decode image {name}: {e}"))?;
        Image::from_dynamic(img, channels, name)
    }

    fn from_dynamic(img: ::image::DynamicImage, channels: Channels, name: &str) -> Result<Image, String> {
        let (w, h) = (img.width(), img.height());
        if w == 0 || h == 0 || w > MAX_EDGE || h > MAX_EDGE {
            return Err(format!("image {name} is {w}×{h}; edges must be 1 to {MAX_EDGE}"));
        }
        use ::image::DynamicImage as D;
        let level = |texels| Level { width: w, height: h, texels };
        Ok(match (channels, &img) {
            (Channels::Alpha, D::ImageRgb32F(_) | D::ImageRgba32F(_)) => {
                let t = img.to_rgba32f().pixels().map(|p| [p.0[3]; 3]).collect();
                Image::from_level(level(Texels::Hdr(t)), true)
            }
            (
                Channels::Alpha,
                D::ImageLuma16(_) | D::ImageLumaA16(_) | D::ImageRgb16(_) | D::ImageRgba16(_),
            ) => {
                let t = img.to_rgba16().pixels().map(|p| [p.0[3] as f32 / 257.0; 3]).collect();
                Image::from_level(level(Texels::Hdr(t)), false)
            }
            (Channels::Alpha, _) => {
                let t = img.to_rgba8().pixels().map(|p| [p.0[3]; 3]).collect();
                Image::from_level(level(Texels::Ldr(t)), false)
            }
            (Channels::Rgb, D::ImageRgb32F(_) | D::ImageRgba32F(_)) => {
                let t = img.to_rgb32f().pixels().map(|p| p.0).collect();
                Image::from_level(level(Texels::Hdr(t)), true)
            }
            (
                Channels::Rgb,
                D::ImageLuma16(_) | D::ImageLumaA16(_) | D::ImageRgb16(_) | D::ImageRgba16(_),
            ) => {
                let t = img.to_rgb16().pixels().map(|p| p.0.map(|c| c as f32 / 257.0)).collect();
                Image::from_level(level(Texels::Hdr(t)), false)
            }
            (Channels::Rgb, _) => {
                // `into_`, not `to_`: an 8-bit RGB file (most JPEGs) keeps its
                // decoded buffer, which becomes the texels as it is.
                let t = rgb_texels(img.into_rgb8().into_raw());
                Image::from_level(level(Texels::Ldr(t)), false)
            }
        })
    }

    /// An 8-bit image from row-major RGB texels (tests and generated textures).
    pub fn from_rgb8(width: u32, height: u32, texels: Vec<[u8; 3]>) -> Option<Image> {
        (width > 0 && height > 0 && texels.len() == (width * height) as usize)
            .then(|| Image::from_level(Level { width, height, texels: Texels::Ldr(texels) }, false))
    }

    /// A linear float image from row-major RGB texels (tests and generated maps).
    pub fn from_rgb32f(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Option<Image> {
        (width > 0 && height > 0 && texels.len() == (width * height) as usize)
            .then(|| Image::from_level(Level { width, height, texels: Texels::Hdr(texels) }, true))
    }

    /// Level 0's texels, row-major, in the file's scale (an environment light
    /// keeps its own copy to sample from).
    pub fn texels(&self) -> Vec<Vec3> {
        let l = &self.levels[0];
        (0..l.height).flat_map(|y| (0..l.width).map(move |x| l.fetch(x, y))).collect()
    }

    fn from_level(level: Level, hdr: bool) -> Image {
        Image { levels: vec![level], hdr }
    }

    /// Whether texels are linear floats (so the default normalizer is 1, not 255).
    pub fn is_hdr(&self) -> bool {
        self.hdr
    }

    /// Turns display-encoded texels linear (`degamma`): `c^2.2` per channel,
    /// on the 0–1 scale for 8- and 16-bit images (their values stay 0–255).
    /// Call before [`Image::build_mipmaps`].
    pub fn degamma(&mut self) {
        self.decode(|c| c.powf(2.2));
    }

    /// Turns sRGB-encoded texels linear with the sRGB curve (IEC 61966-2-1),
    /// on the 0–1 scale like [`Image::degamma`]: what a scene's display
    /// transform does to its 8-bit colour images. Call before
    /// [`Image::build_mipmaps`].
    pub fn srgb_decode(&mut self) {
        self.decode(luster_core::image::buffer::srgb_to_linear);
    }

    fn decode(&mut self, f: impl Fn(f32) -> f32) {
        let scale = if self.hdr { 1.0 } else { 255.0 };
        self.map_texels(|c| Vec3::from_array((c.max(Vec3::ZERO) / scale).to_array().map(|c| f(c) * scale)));
    }

    /// Turns a tangent-space normal map in OpenGL's convention (+Y up in
    /// the image, glTF's) into the one `replace_normal` reads (+Y along +v,
    /// down the image), with x and y scaled by `scale` as glTF's
    /// `normalTexture.scale` does: `t = 2c − 1` becomes
    /// `(scale·tx, −scale·ty, tz)`, stored again as `255 (t + 1) / 2`.
    /// Call before [`Image::build_mipmaps`].
    pub fn gl_normal(&mut self, scale: f32) {
        let unit = if self.hdr { 1.0 } else { 255.0 };
        self.map_texels(|c| {
            let t = c / unit * 2.0 - Vec3::ONE;
            (Vec3::new(scale * t.x, -scale * t.y, t.z) + Vec3::ONE) * 127.5
        });
        // The texels are now on the 0–255 scale that normal maps read.
        self.hdr = false;
    }

    /// Replaces every texel `c` by `f(c)`, kept as floats.
    fn map_texels(&mut self, f: impl Fn(Vec3) -> Vec3) {
        for level in &mut self.levels {
            let out: Vec<[f32; 3]> = (0..level.height)
                .flat_map(|y| (0..level.width).map(move |x| (x, y)))
                .map(|(x, y)| f(level.fetch(x, y)).to_array())
                .collect();
            level.texels = Texels::Hdr(out);
        }
    }

    /// Width and height of level 0.
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// Number of mipmap levels built (1 before [`Image::build_mipmaps`]).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Builds the pyramid down to 1×1 (once).
    pub fn build_mipmaps(&mut self) {
        while let Some(last) = self.levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let next = last.halve();
            self.levels.push(next);
        }
    }

    /// The texel containing `uv`.
    pub fn nearest(&self, uv: Vec2) -> Vec3 {
        self.levels[0].nearest(uv)
    }

    /// The bilinear blend of the four texels around `uv`.
    pub fn bilinear(&self, uv: Vec2) -> Vec3 {
        self.levels[0].bilinear(uv)
    }

    /// Bilinear lookups in the two levels around `lod` (0 = full resolution;
    /// each step halves it), blended linearly. Without mipmaps this is bilinear.
    pub fn trilinear(&self, uv: Vec2, lod: f32) -> Vec3 {
        let top = (self.levels.len() - 1) as f32;
        let lod = if lod.is_nan() { 0.0 } else { lod.clamp(0.0, top) };
        let l0 = lod.floor();
        let f = lod - l0;
        let a = self.levels[l0 as usize].bilinear(uv);
        if f == 0.0 {
            return a;
        }
        let b = self.levels[(l0 as usize + 1).min(self.levels.len() - 1)].bilinear(uv);
        a * (1.0 - f) + b * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_bytes_become_texels_in_place_or_by_copy() {
        let raw: Vec<u8> = (0..12).collect();
        let at = raw.as_ptr();
        let t = rgb_texels(raw);
        assert_eq!(t, [[0, 1, 2], [3, 4, 5], [6, 7, 8], [9, 10, 11]]);
        assert_eq!(t.as_ptr().cast::<u8>(), at, "an exact-size buffer is kept");
        let mut odd = Vec::with_capacity(10);
        odd.extend_from_slice(&[1, 2, 3, 4, 5, 6]);
        assert_eq!(rgb_texels(odd), [[1, 2, 3], [4, 5, 6]]);
    }

    #[test]
    fn a_decoded_png_keeps_its_texels() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.png");
        let px: Vec<u8> = (0..2 * 3 * 3).map(|i| (i * 13) as u8).collect();
        image::save_buffer(&p, &px, 3, 2, image::ExtendedColorType::Rgb8).unwrap();
        let img = Image::load(&p).unwrap();
        assert_eq!(img.size(), (3, 2));
        assert_eq!(img.nearest(Vec2::new(0.5, 0.75)), Vec3::new(156.0, 169.0, 182.0));
    }
}
