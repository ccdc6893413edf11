//! Textures on the render side (hw4): the images a scene decodes once, the
//! texture maps that read them (or compute a procedural value), and what a
//! map's `DecalMode` does to a surface point.
//!
//! Every object has a (usually short) list of maps. At a hit, [`Textures::apply`]
//! goes through the list in order: colour maps change the point's copy of the
//! material, a normal or bump map changes its shading normal, and
//! `replace_all` makes the point an unlit colour.
//!
//! What each decal mode does, as the hw4 text defines it (the value `c` is
//! the texel divided by the map's `Normalizer`, the Perlin value in [0, 1] as
//! grey, or the checkerboard colour):
//!
//! | mode | effect |
//! |---|---|
//! | `replace_kd` | `kd = c` |
//! | `blend_kd` | `kd = (kd + c) / 2` |
//! | `replace_ks` | `ks = c` |
//! | `replace_km` | `km = c` (mirror reflectance; luster's extension; a non-mirror material becomes a mirror) |
//! | `replace_all` | the point's colour is `c`, no lighting |
//! | `replace_normal` | `n = normalize(T x + B y + N z)` with `(x, y, z) = 2 texel/255 - 1` |
//! | `bump_normal` | see [`bump`] |
//! | `replace_background` | rays that miss take `255 c` at their camera sample's image position |
//! | `material` | shader maps only: every material output the script defines ([`shader::apply_outputs`]) |
//!
//! Shader maps (a Lua script, [`shader`]) call the script's entry point that
//! the decal mode needs; a script's runtime error comes back from
//! [`Textures::apply`] for the renderer to report.

pub mod bump;
pub mod exr_header;
pub mod image;
pub mod procedural;
pub mod shader;

pub use image::Image;
pub use procedural::{Checkerboard, Perlin};

use crate::bsdf::closure::Lobes;
use crate::material::Material;
use luster_core::math::{Transform, Vec2, Vec3};
use luster_scene::description::{DecalMode, Interpolation, TextureMapDesc, TextureSource};
use luster_shading::shader::{ShaderError, ShaderSet};
use std::sync::Arc;

/// Where a map's value comes from.
#[derive(Clone, Copy, Debug)]
pub enum Texture {
    /// An image of [`Textures::images`].
    Image {
        /// Index of the image.
        image: u32,
        /// Filtering.
        interpolation: Interpolation,
        /// `1 / Normalizer`.
        scale: f32,
    },
    /// Perlin noise.
    Perlin(Perlin),
    /// The 3D checkerboard.
    Checkerboard(Checkerboard),
    /// A Lua shader: shader `id` of [`Textures::shaders`].
    Shader {
        /// Index in the set.
        id: u32,
    },
}

/// A texture map.
#[derive(Clone, Copy, Debug)]
pub struct TextureMap {
    /// The value's source.
    pub texture: Texture,
    /// What the value does.
    pub decal: DecalMode,
    /// Height multiplier for bump maps.
    pub bump_factor: f32,
}

/// A slice of [`Textures::lists`]: one object's maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TexList {
    /// First entry.
    pub start: u32,
    /// Number of maps.
    pub len: u32,
}

impl TexList {
    /// Whether the object has no maps.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Everything texturing needs to know about a surface point.
#[derive(Clone, Copy, Debug)]
pub struct TexFrame {
    /// Texture coordinates.
    pub uv: Vec2,
    /// Object-space position (before the object's transform and motion).
    pub p_object: Vec3,
    /// World-space position, where the ray hit (with motion).
    pub p_world: Vec3,
    /// The ray's shutter time, 0 to 1.
    pub time: f32,
    /// Where Perlin noise is evaluated, a position that moves with its
    /// object. The course's references pin it down per kind of object: for
    /// spheres and ellipsoids the world position without the motion blur
    /// translation (hw4 `ellipsoids_texture`: the noise on a squashed sphere
    /// is not squashed); for meshes the object-space position (hw4
    /// `cube_perlin`, `cube_perlin_bump`: on cubes scaled by 0.8 the
    /// references' noise is 1.25 times finer than world-space noise).
    pub p_rest: Vec3,
    /// Whether [`p_rest`](Self::p_rest) is in object space (meshes) rather
    /// than world space: a Perlin bump then tilts the object-space normal,
    /// and an image bump displaces the object-space surface (otherwise the
    /// world-space one, see `bump/mod.rs`).
    pub rest_in_object: bool,
    /// Object-space ∂p/∂u.
    pub dpdu: Vec3,
    /// Object-space ∂p/∂v.
    pub dpdv: Vec3,
    /// Unit shading normal, object space.
    pub n: Vec3,
    /// The object's transform (`None`: the identity).
    pub to_world: Option<Transform>,
    /// World-space width of the pixel's footprint at the point (for mipmaps).
    pub footprint: f32,
    /// What only shaders read (the rest of a script's `s`).
    pub ctx: ShadeCtx,
}

/// The camera's frame, for camera-space points: its eye and unit axes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct View {
    /// The eye.
    pub eye: Vec3,
    /// Unit right, up and backward (towards the viewer) axes.
    pub right: Vec3,
    /// See `right`.
    pub up: Vec3,
    /// See `right`.
    pub back: Vec3,
}

impl View {
    /// A world point in camera space: x right, y up, z towards the viewer.
    pub fn to_camera(&self, p: Vec3) -> Vec3 {
        let d = p - self.eye;
        Vec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.back))
    }
}

/// The parts of a shader's shading context that the texture maps themselves
/// do not need: where the ray came from, which object and pixel, and the
/// footprint as two vectors.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadeCtx {
    /// Unit direction of the incident ray, world space.
    pub incident: Vec3,
    /// Unit geometric normal, world space.
    pub ng: Vec3,
    /// World-space change of the point to the next pixel right and down.
    pub dpdx: Vec3,
    /// See `dpdx`.
    pub dpdy: Vec3,
    /// The geometry's object index (an instance gives its mesh's).
    pub object: u32,
    /// The shaded object's own index.
    pub instance: u32,
    /// Ray depth, 0 for camera rays.
    pub depth: u32,
    /// The pixel.
    pub pixel: [u32; 2],
    /// The camera.
    pub view: View,
}

impl ShadeCtx {
    /// Sets `dpdx`, `dpdy` from a ray cone of width `width` at the point: the
    /// camera's right and down axes scaled by the width, carried along the
    /// incident ray onto the surface's tangent plane (Igehy's transfer of ray
    /// differentials, exact for camera rays of a pinhole; after a bounce the
    /// cone keeps only its width, so the vectors are an estimate). At grazing
    /// angles the stretch is capped at 20×, as for the texture footprint.
    pub fn set_footprint(&mut self, width: f32) {
        let (d, n) = (self.incident, self.ng);
        let dn = d.dot(n);
        let dn = if dn < 0.0 { dn.min(-0.05) } else { dn.max(0.05) };
        let onto = |v: Vec3| v - d * (v.dot(n) / dn);
        self.dpdx = onto(self.view.right * width);
        self.dpdy = onto(-self.view.up * width);
    }
}

impl TexFrame {
    /// An object-space normal in world space, unit length.
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        match &self.to_world {
            Some(xf) => xf.normal_to_world(n).normalize(),
            None => n,
        }
    }

    /// World-space area swept by a unit square of texture coordinates here.
    fn world_uv_area(&self) -> f32 {
        match &self.to_world {
            Some(xf) => xf.vector(self.dpdu).cross(xf.vector(self.dpdv)).length(),
            None => self.dpdu.cross(self.dpdv).length(),
        }
    }
}

/// What the maps made of a surface point.
pub enum Applied {
    /// Shade it with the (possibly changed) material and normal.
    Lit,
    /// Its colour is this, unlit (`replace_all`).
    Unlit(Vec3),
}

/// The scene's images and texture maps.
#[derive(Default)]
pub struct Textures {
    /// Decoded images, shared with the shaders' `texture()`.
    pub images: Arc<[Image]>,
    /// Texture maps.
    pub maps: Vec<TextureMap>,
    /// Every object's maps, one run per object.
    pub lists: Vec<u32>,
    /// The map that replaces the background.
    pub background: Option<u32>,
    /// The compiled scripts of the shader maps, if any.
    pub shaders: Option<ShaderSet>,
}

impl Textures {
    /// Builds the maps from their descriptions; `images` are already decoded
    /// (mipmapped where a trilinear map reads them). `shaders` holds the
    /// shader maps' scripts, in map order ([`shader::compile`]).
    pub fn new(
        images: impl Into<Arc<[Image]>>,
        descs: &[TextureMapDesc],
        background: Option<usize>,
        shaders: Option<ShaderSet>,
    ) -> Textures {
        let images = images.into();
        let mut next_shader = 0u32;
        let maps = descs
            .iter()
            .map(|d| {
                let texture = match &d.source {
                    TextureSource::Image { image, interpolation, normalizer } => {
                        let default = if images[*image].is_hdr() { 1.0 } else { 255.0 };
                        Texture::Image {
                            image: *image as u32,
                            interpolation: *interpolation,
                            scale: 1.0 / normalizer.unwrap_or(default),
                        }
                    }
                    TextureSource::Perlin { scale, conversion, octaves } => {
                        Texture::Perlin(Perlin { scale: *scale, conversion: *conversion, octaves: *octaves })
                    }
                    &TextureSource::Checkerboard { scale, offset, black, white } => {
                        Texture::Checkerboard(Checkerboard { scale, offset, black, white })
                    }
                    TextureSource::Shader { .. } => {
                        next_shader += 1;
                        Texture::Shader { id: next_shader - 1 }
                    }
                };
                TextureMap { texture, decal: d.decal, bump_factor: d.bump_factor }
            })
            .collect();
        Textures { images, maps, lists: Vec::new(), background: background.map(|b| b as u32), shaders }
    }

    /// The module files the shader maps' scripts required (canonical
    /// paths), for a watcher to watch with the scripts themselves.
    pub fn shader_modules(&self) -> Vec<std::path::PathBuf> {
        self.shaders.as_ref().map(ShaderSet::required_files).unwrap_or_default()
    }

    /// Records an object's maps; returns its list.
    pub fn add_list(&mut self, maps: &[usize]) -> TexList {
        let start = self.lists.len() as u32;
        self.lists.extend(maps.iter().map(|&m| m as u32));
        TexList { start, len: maps.len() as u32 }
    }

    /// The maps of a list.
    #[inline]
    pub fn maps_of(&self, list: TexList) -> impl Iterator<Item = &TextureMap> + '_ {
        self.lists[list.start as usize..(list.start + list.len) as usize]
            .iter()
            .map(|&m| &self.maps[m as usize])
    }

    /// A map's raw value at a frame: texel (not yet normalized), Perlin grey,
    /// or checkerboard colour. The references pin down where each pattern
    /// lives: Perlin noise at the position at rest (hw4 `ellipsoids_texture`:
    /// the noise on a squashed sphere is not squashed), the checkerboard in
    /// object space (hw4 `VeachAjar`, whose floor is scaled by 1.8 along x).
    pub fn at(&self, texture: &Texture, f: &TexFrame, lod: f32) -> Vec3 {
        let p = match texture {
            Texture::Checkerboard(_) => f.p_object,
            _ => f.p_rest,
        };
        self.raw(texture, f.uv, p, lod)
    }

    /// A map's raw value at texture coordinates `uv` or position `p`:
    /// texel (not yet normalized), Perlin grey, or checkerboard colour.
    pub fn raw(&self, texture: &Texture, uv: Vec2, p: Vec3, lod: f32) -> Vec3 {
        match *texture {
            Texture::Image { image, interpolation, .. } => {
                let img = &self.images[image as usize];
                match interpolation {
                    Interpolation::Nearest => img.nearest(uv),
                    Interpolation::Bilinear => img.bilinear(uv),
                    Interpolation::Trilinear => img.trilinear(uv, lod),
                }
            }
            Texture::Perlin(t) => Vec3::splat(t.value(p)),
            Texture::Checkerboard(c) => c.value(p),
            // Shader maps are evaluated by `apply_shader`, never here.
            Texture::Shader { .. } => Vec3::ZERO,
        }
    }

    /// A map's colour value `c` (see the module table) from its raw value.
    fn normalized(texture: &Texture, raw: Vec3) -> Vec3 {
        match *texture {
            Texture::Image { scale, .. } => raw * scale,
            _ => raw,
        }
    }

    /// A map's colour value `c` at a frame.
    pub fn value(&self, texture: &Texture, f: &TexFrame, lod: f32) -> Vec3 {
        Self::normalized(texture, self.at(texture, f, lod))
    }

    /// Mipmap level for an image map at a frame: the log2 of texels per
    /// footprint width, from the texel density the uv parameterization gives
    /// (`W·H` texels over the area `|∂p/∂u × ∂p/∂v|`).
    fn lod(&self, texture: &Texture, f: &TexFrame) -> f32 {
        let Texture::Image { image, interpolation: Interpolation::Trilinear, .. } = *texture else {
            return 0.0;
        };
        let (w, h) = self.images[image as usize].size();
        let area = f.world_uv_area();
        if area <= 0.0 || f.footprint <= 0.0 {
            return 0.0;
        }
        (f.footprint * (w as f32 * h as f32 / area).sqrt()).log2()
    }

    /// Applies an object's maps to a surface point: may change `m` (its own
    /// copy of the material) and the world shading normal `n`. Normal and
    /// bump maps work in object space, on the object's own derivatives, and
    /// the result is carried to the world like any normal: the course's
    /// references show a bump's strength does not change when the object is
    /// scaled (hw4 `bump_mapping_transformed`).
    ///
    /// Fails only when a shader map's script fails (an error, a bad result,
    /// its time limit).
    pub fn apply(
        &self,
        list: TexList,
        f: &TexFrame,
        m: &mut Material,
        n: &mut Vec3,
        lobes: &mut Lobes,
    ) -> Result<Applied, Box<ShaderError>> {
        for map in self.maps_of(list) {
            let unlit = match map.texture {
                Texture::Shader { id } => self.apply_shader(id, map, f, m, n, lobes)?,
                _ => self.apply_map(map, f, m, n),
            };
            if let Some(c) = unlit {
                return Ok(Applied::Unlit(c));
            }
        }
        Ok(Applied::Lit)
    }

    /// [`Textures::apply`] for one map that is not a shader: `Some` colour
    /// for `replace_all`.
    ///
    /// Out of line on purpose: inlined into the loop of `apply`, LLVM hoists
    /// this arm's set-up (the mipmap level's `|∂p/∂u × ∂p/∂v|` and its square
    /// root, the frame's fields) in front of the loop, so a point with only
    /// shader maps would pay for it too.
    #[inline(never)]
    fn apply_map(&self, map: &TextureMap, f: &TexFrame, m: &mut Material, n: &mut Vec3) -> Option<Vec3> {
        let lod = self.lod(&map.texture, f);
        match map.decal {
            DecalMode::ReplaceKd => m.diffuse = self.value(&map.texture, f, lod),
            DecalMode::BlendKd => m.diffuse = (m.diffuse + self.value(&map.texture, f, lod)) * 0.5,
            DecalMode::ReplaceKs => m.specular = self.value(&map.texture, f, lod),
            DecalMode::ReplaceKm => {
                m.mirror = self.value(&map.texture, f, lod);
                if m.kind == crate::bsdf::Specular::None {
                    m.kind = crate::bsdf::Specular::Mirror;
                }
            }
            DecalMode::ReplaceAll => return Some(self.value(&map.texture, f, lod)),
            DecalMode::ReplaceNormal => {
                let c = self.at(&map.texture, f, lod) / 255.0;
                *n = f.normal_to_world(bump::normal_map(f, c * 2.0 - Vec3::ONE));
            }
            DecalMode::BumpNormal => *n = bump::bump(self, map, f),
            // Only shader maps are built with this mode (the reader refuses others).
            DecalMode::ReplaceBackground | DecalMode::Material => {}
        }
        None
    }

    /// The background at image position `uv` (0–1 across and down), if a map
    /// replaces it. Like `BackgroundColor`, it is in output units (0–255
    /// is black to white), so the value is scaled by 255: with the default
    /// `Normalizer` a texel shows as itself (hw4 `galactica_dynamic`).
    ///
    /// The texel is the nearest one, whatever the map's `Interpolation`: the
    /// course looks the background up once per pixel at the pixel's corner,
    /// where its bilinear weights fall on a single texel, so an image of the
    /// output's size shows pixel for pixel. Bilinear weights at jittered
    /// sample positions would blur every star over two texels; nearest
    /// lookups at those positions stay in the pixel's own texel, and for an
    /// image of another size they average to a box filter over the pixel.
    pub fn background(&self, uv: Vec2) -> Option<Vec3> {
        let map = &self.maps[self.background? as usize];
        let raw = match map.texture {
            Texture::Image { image, .. } => self.images[image as usize].nearest(uv),
            _ => self.raw(&map.texture, uv, uv.extend(0.0), 0.0),
        };
        Some(Self::normalized(&map.texture, raw) * 255.0)
    }
}

#[cfg(test)]
mod tests;
