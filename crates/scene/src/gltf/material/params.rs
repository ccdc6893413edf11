//! One glTF material's factors, textures and extensions as the parameters
//! of the built-in shader `gltf_pbr.lua` (the table in
//! `docs/gltf-materials.md`), and its normal texture as a `replace_normal`
//! image map.

use super::images::Images;
use crate::description::{DecalMode, ImageDesc, ImageEncoding, Interpolation, TextureMapDesc, TextureSource};
use crate::error::{Loc, SceneError, Warning};
use crate::obj::PartMap;
use gltf::texture::{MagFilter, WrappingMode};
use luster_shading::shader::ParamValue;
use serde_json::Value;

/// Most texture slots the shader has (`SLOTS` in `pbr.lua`): every texture
/// a material can have, with the alpha channels read apart.
pub(super) const SLOTS: usize = 12;

/// What [`map`] makes of a material.
pub(super) struct Mapped {
    /// The shader's parameters.
    pub params: Vec<(String, ParamValue)>,
    /// The images the shader samples.
    pub images: Vec<ImageDesc>,
    /// The normal texture as a `replace_normal` map.
    pub normal: Option<PartMap>,
}

/// A texture reference: glTF's `textureInfo`, typed or read raw from an
/// extension, with its `KHR_texture_transform`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TexRef {
    texture: usize,
    tex_coord: u32,
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
}

impl TexRef {
    fn from_info(info: &gltf::texture::Info<'_>) -> TexRef {
        let mut r = TexRef {
            texture: info.texture().index(),
            tex_coord: info.tex_coord(),
            offset: [0.0; 2],
            rotation: 0.0,
            scale: [1.0; 2],
        };
        if let Some(t) = info.texture_transform() {
            (r.offset, r.rotation, r.scale) = (t.offset(), t.rotation(), t.scale());
            r.tex_coord = t.tex_coord().unwrap_or(r.tex_coord);
        }
        r
    }

    /// The 2×3 matrix of `uv' = offset + rotation · scale · uv`
    /// (KHR_texture_transform's `T · R · S`, rotation counter-clockwise in
    /// uv, that is, the image turning clockwise).
    fn matrix(&self) -> [[f64; 3]; 2] {
        let (s, c) = f64::from(self.rotation).sin_cos();
        let [sx, sy] = self.scale.map(f64::from);
        let [ox, oy] = self.offset.map(f64::from);
        [[c * sx, s * sy, ox], [-s * sx, c * sy, oy]]
    }
}

/// The mapping of one material: its JSON path for messages, the file's
/// images, and the slots filled so far.
struct Mapper<'m, 'a> {
    at: String,
    file: &'m std::path::Path,
    doc: &'m gltf::Document,
    images: &'m mut Images<'a>,
    warnings: &'m mut Vec<Warning>,
    slots: Vec<(TexRef, usize, ImageEncoding)>,
    params: Vec<(String, ParamValue)>,
    out_images: Vec<ImageDesc>,
    warned_tex_coord: bool,
}

fn num(x: f64) -> ParamValue {
    ParamValue::Number(x)
}

fn rgb(c: [f32; 3]) -> ParamValue {
    ParamValue::Vec3(c.map(f64::from))
}

impl Mapper<'_, '_> {
    fn loc(&self, field: &str) -> Loc {
        Loc { line: None, path: format!("{}{field}", self.at) }
    }

    fn warn(&mut self, field: &str, message: String) {
        let loc = self.loc(field);
        self.warnings.push(Warning { loc, message });
    }

    fn err(&self, field: &str, message: impl Into<String>) -> SceneError {
        SceneError::at(self.file, &self.loc(field), message)
    }

    fn set(&mut self, name: &str, v: ParamValue) {
        self.params.push((name.to_string(), v));
    }

    /// `x` limited to `lo..=hi`, with a warning naming `field` when it was not.
    fn ranged(&mut self, field: &str, x: f32, lo: f32, hi: f32) -> f32 {
        if x >= lo && x <= hi {
            return x;
        }
        let used = if x.is_nan() { lo } else { x.clamp(lo, hi) };
        self.warn(field, format!("{x} is outside {lo} to {hi}; {used} is used"));
        used
    }

    fn colour(&mut self, field: &str, c: [f32; 3]) -> [f32; 3] {
        let (lo, hi) =
            (c.iter().copied().fold(f32::MAX, f32::min), c.iter().copied().fold(f32::MIN, f32::max));
        if lo >= 0.0 && hi <= 1.0 {
            return c;
        }
        self.warn(field, "has a value outside 0 to 1; it is clamped".to_string());
        c.map(|x| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) })
    }

    /// The slot (1-based) that samples texture `t`'s image read as
    /// `encoding`, added when no slot does yet; sets `param` to it.
    fn texture(
        &mut self,
        param: &str,
        field: &str,
        t: TexRef,
        encoding: ImageEncoding,
    ) -> Result<(), SceneError> {
        if t.tex_coord != 0 && !self.warned_tex_coord {
            self.warned_tex_coord = true;
            self.warn(
                field,
                format!("uses texCoord {}; luster reads TEXCOORD_0 only, which is used", t.tex_coord),
            );
        }
        let texture =
            self.doc.textures().nth(t.texture).ok_or_else(|| {
                self.err(field, format!("names texture {}, which does not exist", t.texture))
            })?;
        let image = texture.source().index();
        let key = TexRef { tex_coord: 0, ..t };
        let slot = match self.slots.iter().position(|s| s.0 == key && s.1 == image && s.2 == encoding) {
            Some(k) => k + 1,
            None => {
                if self.slots.len() == SLOTS {
                    return Err(self.err(field, format!("the material has more than {SLOTS} textures")));
                }
                let (desc, (w, h)) = self.images.get(image, encoding)?;
                let sampler = texture.sampler();
                let wrap = |m: WrappingMode| match m {
                    WrappingMode::Repeat => 0.0,
                    WrappingMode::ClampToEdge => 1.0,
                    WrappingMode::MirroredRepeat => 2.0,
                };
                let nearest = if sampler.mag_filter() == Some(MagFilter::Nearest) { 1.0 } else { 0.0 };
                let k = self.slots.len() + 1;
                let [u, v] = key.matrix();
                self.set(&format!("image{k}"), ParamValue::Text(desc.id.clone()));
                self.set(&format!("u{k}"), ParamValue::Vec3(u));
                self.set(&format!("v{k}"), ParamValue::Vec3(v));
                self.set(
                    &format!("sampler{k}"),
                    ParamValue::Vec3([wrap(sampler.wrap_s()), wrap(sampler.wrap_t()), nearest]),
                );
                self.set(
                    &format!("texel{k}"),
                    ParamValue::Vec3([0.5 / f64::from(w), 0.5 / f64::from(h), 0.0]),
                );
                self.slots.push((key, image, encoding));
                self.out_images.push(desc);
                k
            }
        };
        self.set(param, num(slot as f64));
        Ok(())
    }

    fn info(
        &mut self,
        param: &str,
        field: &str,
        info: Option<gltf::texture::Info<'_>>,
        encoding: ImageEncoding,
    ) -> Result<(), SceneError> {
        match info {
            Some(i) => self.texture(param, field, TexRef::from_info(&i), encoding),
            None => Ok(()),
        }
    }

    /// A `textureInfo` read raw from an extension's JSON (`field` is its path).
    fn raw_info(
        &mut self,
        param: &str,
        field: &str,
        v: Option<&Value>,
        encoding: ImageEncoding,
    ) -> Result<(), SceneError> {
        let Some(v) = v else { return Ok(()) };
        let bad = |what: &str| self.err(field, format!("is not a textureInfo ({what})"));
        let texture = v.get("index").and_then(Value::as_u64).ok_or_else(|| bad("no index"))?;
        let tex_coord = match v.get("texCoord") {
            None => 0,
            Some(t) => t
                .as_u64()
                .and_then(|t| u32::try_from(t).ok())
                .ok_or_else(|| bad("texCoord is not a count"))?,
        };
        let mut r = TexRef {
            texture: usize::try_from(texture).unwrap_or(usize::MAX),
            tex_coord,
            offset: [0.0; 2],
            rotation: 0.0,
            scale: [1.0; 2],
        };
        if let Some(t) = v.pointer("/extensions/KHR_texture_transform") {
            let pair = |k: &str, d: [f32; 2]| -> Option<[f32; 2]> {
                match t.get(k) {
                    None => Some(d),
                    Some(a) => Some([a.get(0)?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]),
                }
            };
            r.offset =
                pair("offset", [0.0; 2]).ok_or_else(|| bad("its transform's offset is not two numbers"))?;
            r.scale =
                pair("scale", [1.0; 2]).ok_or_else(|| bad("its transform's scale is not two numbers"))?;
            r.rotation = match t.get("rotation") {
                None => 0.0,
                Some(x) => x.as_f64().ok_or_else(|| bad("its transform's rotation is not a number"))? as f32,
            };
            if let Some(tc) = t.get("texCoord").and_then(Value::as_u64) {
                r.tex_coord = u32::try_from(tc).unwrap_or(u32::MAX);
            }
        }
        self.texture(param, field, r, encoding)
    }
}

/// A number from an extension's JSON, or `default` when absent.
fn raw_num(ext: &Value, key: &str, default: f32) -> Option<f32> {
    match ext.get(key) {
        None => Some(default),
        Some(v) => v.as_f64().map(|x| x as f32),
    }
}

fn raw_rgb(ext: &Value, key: &str, default: [f32; 3]) -> Option<[f32; 3]> {
    match ext.get(key) {
        None => Some(default),
        Some(v) => Some([v.get(0)?.as_f64()? as f32, v.get(1)?.as_f64()? as f32, v.get(2)?.as_f64()? as f32]),
    }
}

/// The F0 of an interface of index `ior` with air.
fn f0_of(ior: f32) -> f32 {
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

/// The index of refraction whose F0 is `f0`, at most 5 (luster's range).
fn ior_of(f0: f32) -> f32 {
    let r = f0.clamp(0.0, 1.0).sqrt();
    if r >= 1.0 {
        return 5.0;
    }
    ((1.0 + r) / (1.0 - r)).min(5.0)
}

/// Maps material `m` (JSON path `at`).
pub(super) fn map(
    m: &gltf::Material<'_>,
    at: String,
    doc: &gltf::Document,
    images: &mut Images<'_>,
    file: &std::path::Path,
    warnings: &mut Vec<Warning>,
) -> Result<Mapped, SceneError> {
    let mut w = Mapper {
        at,
        file,
        doc,
        images,
        warnings,
        slots: Vec::new(),
        params: Vec::new(),
        out_images: Vec::new(),
        warned_tex_coord: false,
    };
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    let base = w.colour(".pbrMetallicRoughness.baseColorFactor", [r, g, b]);
    let alpha = w.ranged(".pbrMetallicRoughness.baseColorFactor", a, 0.0, 1.0);
    w.set("base_color", rgb(base));
    w.info(
        "base_tex",
        ".pbrMetallicRoughness.baseColorTexture",
        pbr.base_color_texture(),
        ImageEncoding::Srgb,
    )?;
    let alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => 0.0,
        gltf::material::AlphaMode::Mask => 1.0,
        gltf::material::AlphaMode::Blend => 2.0,
    };
    if alpha_mode > 0.0 {
        w.set("alpha", num(f64::from(alpha)));
        w.set("alpha_mode", num(alpha_mode));
        let cutoff = m.alpha_cutoff().unwrap_or(0.5);
        let cutoff = w.ranged(".alphaCutoff", cutoff, 0.0, f32::MAX);
        w.set("alpha_cutoff", num(f64::from(cutoff)));
        w.info(
            "alpha_tex",
            ".pbrMetallicRoughness.baseColorTexture",
            pbr.base_color_texture(),
            ImageEncoding::Alpha,
        )?;
    }
    if m.extension_value("KHR_materials_unlit").is_some() {
        w.set("unlit", num(1.0));
        return finish(w, None);
    }

    let metallic = w.ranged(".pbrMetallicRoughness.metallicFactor", pbr.metallic_factor(), 0.0, 1.0);
    let roughness = w.ranged(".pbrMetallicRoughness.roughnessFactor", pbr.roughness_factor(), 0.0, 1.0);
    w.set("metallic", num(f64::from(metallic)));
    w.set("roughness", num(f64::from(roughness)));
    let mr = pbr.metallic_roughness_texture();
    w.info(
        "metallic_tex",
        ".pbrMetallicRoughness.metallicRoughnessTexture",
        mr.clone(),
        ImageEncoding::Linear,
    )?;
    w.info("roughness_tex", ".pbrMetallicRoughness.metallicRoughnessTexture", mr, ImageEncoding::Linear)?;

    // Emission: glTF's emissive 1 is display white, the film's 255.
    let emissive = w.colour(".emissiveFactor", m.emissive_factor());
    let strength = w.ranged(
        ".extensions.KHR_materials_emissive_strength.emissiveStrength",
        m.emissive_strength().unwrap_or(1.0),
        0.0,
        1e6,
    );
    if emissive.iter().any(|&c| c > 0.0) && strength > 0.0 {
        w.set("emission", rgb(emissive));
        w.set("emission_scale", num(255.0 * f64::from(strength)));
        w.info("emission_tex", ".emissiveTexture", m.emissive_texture(), ImageEncoding::Srgb)?;
    }

    let mut ior = match m.ior() {
        Some(x) => w.ranged(".extensions.KHR_materials_ior.ior", x, 1.0, 5.0),
        None => 1.5,
    };
    let mut spec_color = [1.0f32; 3];
    if let Some(s) = m.specular() {
        let at = ".extensions.KHR_materials_specular";
        let factor = w.ranged(&format!("{at}.specularFactor"), s.specular_factor(), 0.0, 1.0);
        w.set("specular", num(f64::from(factor)));
        w.info("specular_tex", &format!("{at}.specularTexture"), s.specular_texture(), ImageEncoding::Alpha)?;
        let c = s.specular_color_factor();
        let c = c.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 });
        // glTF's colour scales F0 and may exceed 1; luster's tint stops at
        // 1, so the excess raises the index of refraction instead.
        let top = c.iter().copied().fold(0.0f32, f32::max);
        spec_color = if top > 1.0 {
            ior = ior_of(f0_of(ior) * top);
            c.map(|x| x / top)
        } else {
            c
        };
        w.info(
            "specular_color_tex",
            &format!("{at}.specularColorTexture"),
            s.specular_color_texture(),
            ImageEncoding::Srgb,
        )?;
    }
    w.set("ior", num(f64::from(ior)));
    w.set("specular_color", rgb(spec_color));

    if let Some(t) = m.transmission() {
        let at = ".extensions.KHR_materials_transmission";
        let factor = w.ranged(&format!("{at}.transmissionFactor"), t.transmission_factor(), 0.0, 1.0);
        w.set("transmission", num(f64::from(factor)));
        w.info(
            "transmission_tex",
            &format!("{at}.transmissionTexture"),
            t.transmission_texture(),
            ImageEncoding::Linear,
        )?;
        // Without KHR_materials_volume (or with no thickness) the surface is
        // thin-walled, as the spec says.
        let mut thin = true;
        let mut tint = [1.0f32; 3];
        if let Some(v) = m.volume() {
            let at = ".extensions.KHR_materials_volume";
            let thickness = w.ranged(&format!("{at}.thicknessFactor"), v.thickness_factor(), 0.0, f32::MAX);
            thin = thickness == 0.0;
            if v.thickness_texture().is_some() {
                w.warn(
                    &format!("{at}.thicknessTexture"),
                    "is ignored; the thicknessFactor is used everywhere".to_string(),
                );
            }
            let dist = v.attenuation_distance();
            let colour = w.colour(&format!("{at}.attenuationColor"), v.attenuation_color());
            if !thin && dist.is_finite() && dist > 0.0 {
                // Beer's law over the thickness, half at each of the two
                // interfaces a ray crosses: c^(d / D) in all.
                let k = thickness / (2.0 * dist);
                tint = colour.map(|c| c.powf(k));
            }
        }
        w.set("thin", num(if thin { 1.0 } else { 0.0 }));
        w.set("transmission_tint", rgb(tint));
    }

    if let Some(c) = m.extension_value("KHR_materials_clearcoat") {
        let at = ".extensions.KHR_materials_clearcoat";
        let factor = raw_num(c, "clearcoatFactor", 0.0)
            .ok_or_else(|| w.err(&format!("{at}.clearcoatFactor"), "is not a number"))?;
        let factor = w.ranged(&format!("{at}.clearcoatFactor"), factor, 0.0, 1.0);
        let rough = raw_num(c, "clearcoatRoughnessFactor", 0.0)
            .ok_or_else(|| w.err(&format!("{at}.clearcoatRoughnessFactor"), "is not a number"))?;
        let rough = w.ranged(&format!("{at}.clearcoatRoughnessFactor"), rough, 0.0, 1.0);
        if factor > 0.0 {
            w.set("coat", num(f64::from(factor)));
            w.set("coat_roughness", num(f64::from(rough)));
            w.raw_info(
                "coat_tex",
                &format!("{at}.clearcoatTexture"),
                c.get("clearcoatTexture"),
                ImageEncoding::Linear,
            )?;
            w.raw_info(
                "coat_roughness_tex",
                &format!("{at}.clearcoatRoughnessTexture"),
                c.get("clearcoatRoughnessTexture"),
                ImageEncoding::Linear,
            )?;
            if c.get("clearcoatNormalTexture").is_some() {
                w.warn(
                    &format!("{at}.clearcoatNormalTexture"),
                    "is ignored; the coat follows the base's normal".to_string(),
                );
            }
        }
    }

    if let Some(s) = m.extension_value("KHR_materials_sheen") {
        let at = ".extensions.KHR_materials_sheen";
        let colour = raw_rgb(s, "sheenColorFactor", [0.0; 3])
            .ok_or_else(|| w.err(&format!("{at}.sheenColorFactor"), "is not three numbers"))?;
        let colour = w.colour(&format!("{at}.sheenColorFactor"), colour);
        let rough = raw_num(s, "sheenRoughnessFactor", 0.0)
            .ok_or_else(|| w.err(&format!("{at}.sheenRoughnessFactor"), "is not a number"))?;
        let rough = w.ranged(&format!("{at}.sheenRoughnessFactor"), rough, 0.0, 1.0);
        if colour.iter().any(|&c| c > 0.0) {
            w.set("sheen", num(1.0));
            w.set("sheen_color", rgb(colour));
            w.set("sheen_roughness", num(f64::from(rough)));
            w.raw_info(
                "sheen_color_tex",
                &format!("{at}.sheenColorTexture"),
                s.get("sheenColorTexture"),
                ImageEncoding::Srgb,
            )?;
            w.raw_info(
                "sheen_roughness_tex",
                &format!("{at}.sheenRoughnessTexture"),
                s.get("sheenRoughnessTexture"),
                ImageEncoding::Alpha,
            )?;
        }
    }

    let normal = match m.normal_texture() {
        Some(n) => Some(normal_map(&mut w, &n)?),
        None => None,
    };
    finish(w, normal)
}

fn finish(w: Mapper<'_, '_>, normal: Option<PartMap>) -> Result<Mapped, SceneError> {
    Ok(Mapped { params: w.params, images: w.out_images, normal })
}

/// The normal texture as a `replace_normal` image map: luster's tangent
/// frame is the surface's ∂p/∂u and ∂p/∂v, and the image is turned into its
/// convention when decoded ([`ImageEncoding::GlNormal`]).
fn normal_map(w: &mut Mapper<'_, '_>, n: &gltf::material::NormalTexture<'_>) -> Result<PartMap, SceneError> {
    let field = ".normalTexture";
    if n.tex_coord() != 0 && !w.warned_tex_coord {
        w.warned_tex_coord = true;
        w.warn(
            field,
            format!("uses texCoord {}; luster reads TEXCOORD_0 only, which is used", n.tex_coord()),
        );
    }
    let ext = n.extension_value("KHR_texture_transform");
    if ext.is_some() {
        w.warn(
            field,
            "has a KHR_texture_transform, which luster does not apply to normal textures".to_string(),
        );
    }
    let texture = n.texture();
    let sampler = texture.sampler();
    if sampler.wrap_s() != WrappingMode::Repeat || sampler.wrap_t() != WrappingMode::Repeat {
        w.warn(
            field,
            "is sampled with repeat; its sampler's clamp or mirror wrapping is not applied".to_string(),
        );
    }
    let scale = n.scale();
    let scale = if scale.is_finite() { scale } else { 1.0 };
    let (image, _) = w.images.get(texture.source().index(), ImageEncoding::GlNormal { scale })?;
    let interpolation = if sampler.mag_filter() == Some(MagFilter::Nearest) {
        Interpolation::Nearest
    } else {
        Interpolation::Bilinear
    };
    let loc = w.loc(field);
    let map = TextureMapDesc {
        id: format!("{}{field}", w.at),
        source: TextureSource::Image { image: 0, interpolation, normalizer: None },
        decal: DecalMode::ReplaceNormal,
        bump_factor: 1.0,
        loc,
    };
    Ok(PartMap { map, image: Some(image) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_transform_matrix_is_translation_rotation_scale() {
        let t = TexRef {
            texture: 0,
            tex_coord: 0,
            offset: [0.25, 0.5],
            rotation: std::f32::consts::FRAC_PI_2,
            scale: [2.0, 3.0],
        };
        let [u, v] = t.matrix();
        // uv = (1, 0): scaled (2, 0), rotated by +90° to (0, -2), offset (0.25, -1.5).
        let at = |m: [f64; 3], x: f64, y: f64| m[0] * x + m[1] * y + m[2];
        assert!((at(u, 1.0, 0.0) - 0.25).abs() < 1e-6 && (at(v, 1.0, 0.0) + 1.5).abs() < 1e-6);
        // uv = (0, 1): scaled (0, 3), rotated to (3, 0), offset (3.25, 0.5).
        assert!((at(u, 0.0, 1.0) - 3.25).abs() < 1e-6 && (at(v, 0.0, 1.0) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn ior_and_f0_invert_each_other() {
        assert!((f0_of(1.5) - 0.04).abs() < 1e-6);
        for ior in [1.0f32, 1.33, 1.5, 2.4, 4.0] {
            assert!((ior_of(f0_of(ior)) - ior).abs() < 1e-4, "{ior}");
        }
        assert_eq!(ior_of(1.0), 5.0);
    }
}
