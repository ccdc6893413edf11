//! Images and texture maps in the scene description (`<Images>`,
//! `<TextureMap>`, `DecalMode`, shader scripts used as textures).

use crate::error::Loc;
use luster_core::math::Vec3;
use luster_shading::shader::ParamValue;
use std::path::PathBuf;
use std::sync::Arc;

/// An image file that texture maps read.
#[derive(Clone, Debug)]
pub struct ImageDesc {
    /// The image's id.
    pub id: String,
    /// Resolved path; for an image held in [`bytes`](Self::bytes), only its
    /// name in messages.
    pub path: PathBuf,
    /// Whether texels are display-encoded colours to raise to the power 2.2
    /// (`degamma="true"` on the image or on a texture map reading it).
    pub degamma: bool,
    /// Where.
    pub loc: Loc,
    /// The encoded image (PNG, JPEG) when it is not a file of its own: one
    /// inside a glTF binary buffer or a `data:` URI.
    pub bytes: Option<Arc<[u8]>>,
    /// What the texels hold, and so how they are decoded.
    pub encoding: ImageEncoding,
}

impl ImageDesc {
    /// An image file read as the scene's display transform reads images.
    pub fn file(id: String, path: PathBuf, degamma: bool, loc: Loc) -> ImageDesc {
        ImageDesc { id, path, degamma, loc, bytes: None, encoding: ImageEncoding::Scene }
    }

    /// Whether two descriptions decode to the same texels (one image read once).
    pub fn same_texels(&self, other: &ImageDesc) -> bool {
        self.path == other.path && self.encoding == other.encoding && self.degamma == other.degamma
    }
}

/// What an image's texels hold: how the renderer turns them into values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImageEncoding {
    /// As the scene's display transform says: under a linear workflow
    /// 8-bit colour images are sRGB-decoded (unless only normal and bump
    /// maps read them), otherwise texels are used as stored.
    Scene,
    /// sRGB-encoded colour: 8- and 16-bit texels are always decoded (glTF's
    /// base colour, emissive, sheen and specular colour textures).
    Srgb,
    /// Linear data, used as stored (glTF's metallic-roughness, transmission,
    /// clearcoat textures).
    Linear,
    /// The image's alpha channel as grey, linear (1 where the image has none).
    Alpha,
    /// A tangent-space normal map in OpenGL's convention (glTF's: +Y is up
    /// in the image, towards decreasing v), with x and y scaled by `scale`:
    /// decoded into luster's `replace_normal` convention (+Y along +v).
    GlNormal {
        /// glTF's `normalTexture.scale`.
        scale: f32,
    },
}

/// How an image texture is filtered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The texel the point falls in.
    Nearest,
    /// The four nearest texels, weighted by distance.
    Bilinear,
    /// Bilinear in the two mipmap levels around the pixel's footprint, blended.
    Trilinear,
}

/// What a texture's value does to the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecalMode {
    /// The value is the diffuse reflectance.
    ReplaceKd,
    /// The diffuse reflectance is the mean of the material's and the value.
    BlendKd,
    /// The value is the specular reflectance.
    ReplaceKs,
    /// The value is the colour of camera rays that miss (sampled at the pixel).
    ReplaceBackground,
    /// The value is a tangent-space normal.
    ReplaceNormal,
    /// The value is a height whose gradient perturbs the normal.
    BumpNormal,
    /// The value is the surface's colour, unlit.
    ReplaceAll,
    /// The value is the mirror reflectance (`MirrorReflectance`, the course's
    /// `km`); a luster extension, mainly for shaders' `reflect`. A point of a
    /// material with no mirror part becomes a mirror.
    ReplaceKm,
    /// A shader sets every material output its script defines (base and
    /// specular colour, roughness, metalness, emission, mirror reflectance);
    /// a luster extension for shader maps only (`docs/shaders.md`).
    Material,
}

/// How Perlin noise in [-1, 1] becomes a texture value in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseConversion {
    /// `(n + 1) / 2`: patchy.
    Linear,
    /// `|n|`: veins.
    AbsVal,
}

/// Where a texture map's value comes from.
#[derive(Clone, Debug)]
pub enum TextureSource {
    /// An image, looked up by the surface's texture coordinates.
    Image {
        /// Index into [`Description::images`](super::Description::images).
        image: usize,
        /// Filtering.
        interpolation: Interpolation,
        /// Texel values are divided by this (`Normalizer`; 255 by default for
        /// 8-bit images, 1 for floating-point ones when not given).
        normalizer: Option<f32>,
    },
    /// Perlin noise of the object-space position.
    Perlin {
        /// Multiplies the position before the noise (`NoiseScale`).
        scale: f32,
        /// From noise to value.
        conversion: NoiseConversion,
        /// Octaves summed (`NumOctaves`, 1 by default).
        octaves: u32,
    },
    /// A 3D checkerboard of the object-space position.
    Checkerboard {
        /// Squares per unit (`Scale`).
        scale: f32,
        /// Shift of the pattern (`Offset`).
        offset: f32,
        /// Colour of the "black" squares.
        black: Vec3,
        /// Colour of the "white" squares.
        white: Vec3,
    },
    /// A Lua shader script (a luster extension; see `docs/shaders.md`).
    Shader {
        /// The script's path (relative ones resolved against the scene's folder).
        path: PathBuf,
        /// The script's text, read when the scene loads.
        code: String,
        /// `Parameter` elements, in order: what the script reads as `param.NAME`.
        params: Vec<(String, ParamValue)>,
    },
}

/// A texture map.
#[derive(Clone, Debug)]
pub struct TextureMapDesc {
    /// The map's id.
    pub id: String,
    /// Its source.
    pub source: TextureSource,
    /// What it does.
    pub decal: DecalMode,
    /// Height multiplier of bump maps (`BumpFactor`, 1 by default).
    pub bump_factor: f32,
    /// Where.
    pub loc: Loc,
}
