//! Shader texture maps: compiling the scene's scripts into one
//! [`ShaderSet`], checking each map's decal mode against the entry points its
//! script defines, and evaluating a map at a surface point.
//!
//! Which entry point a decal mode calls:
//!
//! | mode | calls | effect |
//! |---|---|---|
//! | `replace_kd`, `blend_kd`, `replace_ks` | `color` | as for any map |
//! | `replace_all` | `color` | the point's colour, unlit |
//! | `replace_km` | `reflect` | the mirror reflectance |
//! | `bump_normal` | `height` | [`bump::height_bump`], scaled by `BumpFactor` |
//! | `material` | every material output the script defines | [`apply_outputs`] |
//!
//! `replace_normal` and `replace_background` take no shader: a tangent-space
//! normal is what `height` already expresses better, and the background has
//! no surface point to give a script.

use std::time::Duration;

use super::{bump, Image, TexFrame, TextureMap, Textures};
use crate::bsdf::{Brdf, Microfacet};
use crate::material::Material;
use crate::material::Specular;
use crate::math::{Vec2, Vec3};
use crate::scene::description::{DecalMode, ImageDesc, TextureMapDesc, TextureSource};
use crate::shader::{
    Entry, ImageSampler, MaterialOutputs, SampleFilter, ShadeInput, ShadePoint, ShaderError, ShaderImages,
    ShaderSet, ShaderSource,
};
use std::sync::Arc;

/// A shader map the scene cannot use: which map and why.
#[derive(Debug)]
pub struct MapError {
    /// Index of the map in the description.
    pub map: usize,
    /// The reason, a sentence fragment.
    pub message: String,
}

/// The entry point a decal mode calls, or `None` for modes shaders cannot drive.
fn entry_for(decal: DecalMode) -> Option<&'static str> {
    match decal {
        DecalMode::ReplaceKd | DecalMode::BlendKd | DecalMode::ReplaceKs | DecalMode::ReplaceAll => {
            Some("color")
        }
        DecalMode::ReplaceKm => Some("reflect"),
        DecalMode::BumpNormal => Some("height"),
        DecalMode::Material => Some("material"),
        DecalMode::ReplaceNormal | DecalMode::ReplaceBackground => None,
    }
}

/// The name errors give a shader: its script's file name without extension.
pub(crate) fn shader_name(path: &std::path::Path) -> String {
    path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned())
}

/// Compiles the scripts of every shader map (the k-th shader map becomes
/// shader k of the set), or `None` when the scene has none. Every map gets
/// its own source, so one script may serve several maps with different
/// parameters.
pub fn compile(
    descs: &[TextureMapDesc],
    timeout: Duration,
    images: Option<ShaderImages>,
) -> Result<Option<ShaderSet>, MapError> {
    compile_with_modules(descs, timeout, images, Vec::new())
}

/// Like [`compile`], with the folders the scripts' `require` searches.
pub fn compile_with_modules(
    descs: &[TextureMapDesc],
    timeout: Duration,
    images: Option<ShaderImages>,
    module_dirs: Vec<std::path::PathBuf>,
) -> Result<Option<ShaderSet>, MapError> {
    let mut maps = Vec::new();
    let mut sources = Vec::new();
    for (i, d) in descs.iter().enumerate() {
        if let TextureSource::Shader { path, code, params } = &d.source {
            let mut src = ShaderSource::new(shader_name(path), path.clone(), code.clone());
            src.params = params.clone();
            maps.push(i);
            sources.push(src);
        }
    }
    if sources.is_empty() {
        return Ok(None);
    }
    let make = |sources: Vec<ShaderSource>| {
        ShaderSet::with_modules(sources, timeout, images.clone(), module_dirs.clone())
    };
    let set = match make(sources.clone()) {
        Ok(set) => set,
        // The set reports the first script that fails; compile them one by
        // one to find its map (a script used twice may fail with one map's
        // parameters only). Only the error path pays for this.
        Err(e) => {
            let map = sources
                .iter()
                .zip(&maps)
                .find(|(s, _)| make(vec![(*s).clone()]).is_err())
                .map_or(maps[0], |(_, &m)| m);
            return Err(MapError { map, message: e.to_string() });
        }
    };
    for (id, &m) in maps.iter().enumerate() {
        let decal = descs[m].decal;
        let Some(entry) = entry_for(decal) else {
            return Err(MapError {
                map: m,
                message: format!(
                    "a shader cannot drive DecalMode {} (shaders take replace_kd, blend_kd, replace_ks, \
                     replace_all, replace_km, bump_normal or material)",
                    decal_name(decal)
                ),
            });
        };
        let has = match entry {
            "color" => set.has_color(id),
            "reflect" => set.has_reflect(id),
            "material" => set.has_material(id),
            _ => set.has_height(id),
        };
        if !has {
            let name = set.name(id).unwrap_or("?");
            let TextureSource::Shader { path, .. } = &descs[m].source else { continue };
            if decal == DecalMode::Material {
                return Err(MapError {
                    map: m,
                    message: format!(
                        "shader '{name}': {} defines none of color, specular, roughness, metalness, \
                         emission or reflect, one of which DecalMode material needs",
                        path.display()
                    ),
                });
            }
            return Err(MapError {
                map: m,
                message: format!(
                    "shader '{name}': {} defines no {entry}(s) function, which DecalMode {} calls",
                    path.display(),
                    decal_name(decal)
                ),
            });
        }
    }
    Ok(Some(set))
}

fn decal_name(d: DecalMode) -> &'static str {
    match d {
        DecalMode::ReplaceKd => "replace_kd",
        DecalMode::BlendKd => "blend_kd",
        DecalMode::ReplaceKs => "replace_ks",
        DecalMode::ReplaceAll => "replace_all",
        DecalMode::ReplaceKm => "replace_km",
        DecalMode::BumpNormal => "bump_normal",
        DecalMode::Material => "material",
        DecalMode::ReplaceNormal => "replace_normal",
        DecalMode::ReplaceBackground => "replace_background",
    }
}

/// The scene's images as `texture(name, u, v)` samples them: with the scene
/// format's conventions (uv repeat; texel centres at integer multiples of
/// 1/W, as the image maps use), values normalized like an image map's with
/// the default `Normalizer`.
pub struct SceneImages(pub Arc<[Image]>);

impl ImageSampler for SceneImages {
    fn sample(&self, index: usize, u: f32, v: f32, filter: SampleFilter) -> Option<[f32; 3]> {
        let img = self.0.get(index)?;
        let uv = Vec2::new(u, v);
        let c = match filter {
            SampleFilter::Nearest => img.nearest(uv),
            SampleFilter::Bilinear => img.bilinear(uv),
        };
        let scale = if img.is_hdr() { 1.0 } else { 1.0 / 255.0 };
        Some((c * scale).to_array())
    }
}

/// The names scripts give the scene's images: each image's id and, where no
/// other image shares it, its file name.
pub fn image_names(descs: &[ImageDesc]) -> Vec<(String, usize)> {
    let mut names: Vec<(String, usize)> = descs.iter().enumerate().map(|(i, d)| (d.id.clone(), i)).collect();
    let file = |d: &ImageDesc| d.path.file_name().map(|f| f.to_string_lossy().into_owned());
    for (i, d) in descs.iter().enumerate() {
        let Some(f) = file(d) else { continue };
        let shared = descs.iter().filter(|e| file(e).as_deref() == Some(f.as_str())).count() > 1;
        if !shared && !names.iter().any(|(n, _)| *n == f) {
            names.push((f, i));
        }
    }
    names
}

/// The world point of object-space `p` near the hit of frame `f`.
#[inline(always)]
fn world_point(f: &TexFrame, p: Vec3) -> Vec3 {
    if p == f.p_object {
        return f.p_world;
    }
    match &f.to_world {
        // The world point of an offset lies as far from the hit as its object point.
        Some(xf) => f.p_world + xf.vector(p - f.p_object),
        None => f.p_world + (p - f.p_object),
    }
}

/// `base` (the shading point of frame `f`) moved to object-space `p` with
/// texture coordinates `uv`: what [`input`] gives there, without computing
/// again what the points share.
#[inline(always)]
fn moved(f: &TexFrame, base: &ShadeInput, p: Vec3, uv: Vec2) -> ShadeInput {
    let pw = world_point(f, p);
    ShadeInput {
        p: p.to_array(),
        pw: pw.to_array(),
        pc: f.ctx.view.to_camera(pw).to_array(),
        uv: uv.to_array(),
        ..*base
    }
}

/// [`input_at`], out of line: inlined into [`Textures::apply`], its
/// arithmetic was hoisted in front of the map loop, where every hit paid
/// for it whatever its maps' modes.
#[inline(never)]
fn input(f: &TexFrame, p: Vec3, uv: Vec2, n: Vec3) -> ShadeInput {
    input_at(f, p, uv, n)
}

/// The shading point a script sees at object-space `p` with texture
/// coordinates `uv`, in frame `f` whose world shading normal is now `n`.
#[inline(always)]
fn input_at(f: &TexFrame, p: Vec3, uv: Vec2, n: Vec3) -> ShadeInput {
    let pw = world_point(f, p);
    let c = &f.ctx;
    let to_object = |v: Vec3| match &f.to_world {
        Some(xf) => xf.inv_vector(v),
        None => v,
    };
    let (dpdx, dpdy) = (to_object(c.dpdx), to_object(c.dpdy));
    ShadeInput {
        p: p.to_array(),
        pw: pw.to_array(),
        pc: c.view.to_camera(pw).to_array(),
        n: n.to_array(),
        ng: c.ng.to_array(),
        i: c.incident.to_array(),
        dpdu: f.dpdu.to_array(),
        dpdv: f.dpdv.to_array(),
        dpdx: dpdx.to_array(),
        dpdy: dpdy.to_array(),
        uv: uv.to_array(),
        time: f.time,
        filterwidth: dpdx.length().max(dpdy.length()),
        object_id: c.object,
        instance_id: c.instance,
        depth: c.depth,
        pixel: c.pixel,
    }
}

/// The shading point of frame `f` with world shading normal `n`, as the
/// shader runtime takes it: [`input`] runs where the record Lua reads is
/// written.
struct Hit<'a> {
    f: &'a TexFrame,
    n: Vec3,
}

impl ShadePoint for Hit<'_> {
    #[inline(always)]
    fn input(&self) -> ShadeInput {
        input_at(self.f, self.f.p_object, self.f.uv, self.n)
    }

    #[inline(always)]
    fn instance_id(&self) -> u32 {
        self.f.ctx.instance
    }
}

/// Writes the colour `entry` of shader `id` gives at `hit` into `out`
/// (in place: a returned colour came back through the stack).
#[inline(never)]
fn rgb(
    set: &ShaderSet,
    id: usize,
    entry: Entry,
    hit: &Hit<'_>,
    out: &mut Vec3,
) -> Result<(), Box<ShaderError>> {
    let mut c = [0.0; 3];
    let code = set.call_point(id, entry, hit, &mut c);
    if code != 0 {
        c = set.call_slow(id, entry, hit, code)?;
    }
    *out = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    Ok(())
}

impl Textures {
    /// Applies shader map `map` (shader `id`) at `f`: like the other maps, it
    /// may change `m` and the world normal `n`, or make the point unlit.
    pub(super) fn apply_shader(
        &self,
        id: u32,
        map: &TextureMap,
        f: &TexFrame,
        m: &mut Material,
        n: &mut Vec3,
    ) -> Result<Option<Vec3>, Box<ShaderError>> {
        let Some(set) = &self.shaders else { return Ok(None) };
        let id = id as usize;
        let hit = Hit { f, n: *n };
        match map.decal {
            DecalMode::ReplaceKd => rgb(set, id, Entry::Color, &hit, &mut m.diffuse)?,
            DecalMode::BlendKd => {
                let mut c = Vec3::ZERO;
                rgb(set, id, Entry::Color, &hit, &mut c)?;
                m.diffuse = (m.diffuse + c) * 0.5;
            }
            DecalMode::ReplaceKs => rgb(set, id, Entry::Color, &hit, &mut m.specular)?,
            DecalMode::ReplaceAll => {
                let mut c = Vec3::ZERO;
                rgb(set, id, Entry::Color, &hit, &mut c)?;
                return Ok(Some(c));
            }
            DecalMode::ReplaceKm => {
                rgb(set, id, Entry::Reflect, &hit, &mut m.mirror)?;
                if m.kind == Specular::None {
                    m.kind = Specular::Mirror;
                }
            }
            DecalMode::BumpNormal => {
                if map.bump_factor != 0.0 {
                    *n = shader_bump(set, id, map.bump_factor, f, *n)?;
                }
            }
            DecalMode::Material => apply_outputs(&set.material(id, &input(f, f.p_object, f.uv, *n))?, m),
            DecalMode::ReplaceNormal | DecalMode::ReplaceBackground => {}
        }
        Ok(None)
    }
}

/// The world normal `n` bumped by shader `id`'s `height` with factor `k`.
///
/// Out of line on purpose: inlined into [`Textures::apply`], LLVM hoisted the
/// bump's set-up (tangent lengths, step, the three points) out of the map
/// loop, so every hit with any shader map paid for it, about 480
/// instructions a call; on the POV-Ray scene's floor (a colour map only) that
/// was wasted work.
#[inline(never)]
fn shader_bump(set: &ShaderSet, id: usize, k: f32, f: &TexFrame, n: Vec3) -> Result<Vec3, Box<ShaderError>> {
    // The three points are built in place: `pts.map(input)` built them
    // elsewhere and copied 468 bytes (a `memmove` call) per hit.
    let local = bump::height_bump(f, k, bump::bump_step(f), |pts| {
        let [(p0, uv0), (pa, uva), (pb, uvb)] = pts;
        let base = input(f, p0, uv0, n);
        let three = [base, moved(f, &base, pa, uva), moved(f, &base, pb, uvb)];
        set.heights3(id, &three).map_err(Box::new)
    })?;
    // No slope: the normal stays exactly as the renderer had it.
    Ok(match local {
        Some(local) => f.normal_to_world(local),
        None => n,
    })
}

/// What a `DecalMode material` shader's outputs do to the point's material
/// (the table in `docs/shaders.md`, "Material outputs"):
///
/// * `color` is the base colour (`kd`), `specular` the specular colour
///   (`ks`), `reflect` the mirror reflectance (a non-mirror becomes a mirror,
///   as with `replace_km`), `emission` the emitted radiance;
/// * `roughness` or `metalness` switch the point to the GGX microfacet BRDF
///   ([`Microfacet`]) whatever the material's own model: `α = roughness²`,
///   or without a `roughness` the width matching the material's exponent;
///   metalness `μ` turns the diffuse part off and tints the specular colour
///   by the base: `kd ← (1 - μ) kd`, `ks ← (1 - μ) ks + μ kd`.
pub fn apply_outputs(o: &MaterialOutputs, m: &mut Material) {
    if let Some(c) = o.color {
        m.diffuse = Vec3::from_array(c);
    }
    if let Some(c) = o.specular {
        m.specular = Vec3::from_array(c);
    }
    if let Some(c) = o.reflect {
        m.mirror = Vec3::from_array(c);
        if m.kind == Specular::None {
            m.kind = Specular::Mirror;
        }
    }
    if let Some(c) = o.emission {
        m.emission = Vec3::from_array(c);
    }
    if o.roughness.is_none() && o.metalness.is_none() {
        return;
    }
    let lobe = match (o.roughness, m.brdf) {
        (Some(r), _) => Microfacet::from_roughness(r),
        (None, Some(Brdf::Microfacet(mf))) => mf,
        (None, Some(Brdf::Phong(p))) => Microfacet::from_exponent(p.exponent),
        (None, Some(Brdf::TorranceSparrow(t))) => Microfacet::from_exponent(t.exponent),
        (None, None) => Microfacet::from_exponent(m.phong),
    };
    if let Some(mu) = o.metalness {
        m.specular = m.specular * (1.0 - mu) + m.diffuse * mu;
        m.diffuse *= 1.0 - mu;
    }
    m.brdf = Some(Brdf::Microfacet(lobe));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Loc;
    use crate::shader::ParamValue;
    use crate::texture::Texture;

    fn map(code: &str, decal: DecalMode, params: &[(&str, f64)]) -> TextureMapDesc {
        TextureMapDesc {
            id: "m".into(),
            source: TextureSource::Shader {
                path: "dir/s.lua".into(),
                code: code.into(),
                params: params.iter().map(|(k, v)| (k.to_string(), ParamValue::Number(*v))).collect(),
            },
            decal,
            bump_factor: 1.0,
            loc: Loc::default(),
        }
    }

    fn frame() -> TexFrame {
        TexFrame {
            uv: Vec2::new(0.25, 0.75),
            p_object: Vec3::new(0.5, 0.0, 0.0),
            p_world: Vec3::new(1.5, 0.0, 0.0),
            time: 0.5,
            p_rest: Vec3::new(1.5, 0.0, 0.0),
            rest_in_object: false,
            dpdu: Vec3::X,
            dpdv: Vec3::Y,
            n: Vec3::Z,
            to_world: None,
            footprint: 0.0,
            ctx: Default::default(),
        }
    }

    const GREY: &str = "local g = param.g\nassert(g < 1, 'g too big')\nfunction color(s) return g, g, g end";

    #[test]
    fn one_script_serves_maps_with_different_parameters() {
        let descs =
            [map(GREY, DecalMode::ReplaceKd, &[("g", 0.2)]), map(GREY, DecalMode::ReplaceKd, &[("g", 0.6)])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let lists = [tex.maps[0], tex.maps[1]];
        let diffuse: Vec<Vec3> = lists
            .iter()
            .map(|m| {
                let Texture::Shader { id } = m.texture else { panic!("a shader map") };
                let mut mat = Material::default();
                let mut n = Vec3::Z;
                assert_eq!(tex.apply_shader(id, m, &frame(), &mut mat, &mut n).unwrap(), None);
                mat.diffuse
            })
            .collect();
        assert_eq!(diffuse, [Vec3::splat(0.2), Vec3::splat(0.6)]);
    }

    #[test]
    fn the_failing_map_is_found_even_when_its_script_is_shared() {
        let descs =
            [map(GREY, DecalMode::ReplaceKd, &[("g", 0.2)]), map(GREY, DecalMode::ReplaceKd, &[("g", 3.0)])];
        let e = compile(&descs, DEFAULT, None).unwrap_err();
        assert_eq!(e.map, 1);
        assert!(e.message.contains("s.lua:2") && e.message.contains("g too big"), "{}", e.message);
    }

    #[test]
    fn decal_modes_need_their_entry_points() {
        let bg = [map(GREY, DecalMode::ReplaceBackground, &[("g", 0.1)])];
        assert!(compile(&bg, DEFAULT, None)
            .unwrap_err()
            .message
            .contains("cannot drive DecalMode replace_background"));
        let km = [map(GREY, DecalMode::ReplaceKm, &[("g", 0.1)])];
        assert!(compile(&km, DEFAULT, None).unwrap_err().message.contains("no reflect(s)"));
        assert!(compile(&[], DEFAULT, None).unwrap().is_none());
    }

    #[test]
    fn the_script_sees_the_frame_and_reflect_makes_a_mirror() {
        let code = "function reflect(s) return s.P.x, s.Pw.x, s.uv.v + s.time end\n\
                    function color(s) return s.N.x, s.N.y, s.N.z end";
        let descs = [map(code, DecalMode::ReplaceKm, &[]), map(code, DecalMode::ReplaceAll, &[])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let mut mat = Material::default();
        let mut n = Vec3::Y;
        assert_eq!(tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut n).unwrap(), None);
        assert_eq!(mat.mirror, Vec3::new(0.5, 1.5, 1.25));
        assert_eq!(mat.kind, Specular::Mirror);
        assert_eq!(tex.apply_shader(1, &tex.maps[1], &frame(), &mut mat, &mut n).unwrap(), Some(Vec3::Y));
    }

    #[test]
    fn a_height_shader_bumps_and_its_errors_come_back() {
        let code = "function height(s)\n  if s.P.y > 1 then error('bad') end\n  return 0.5 * s.P.x\nend";
        let descs = [map(code, DecalMode::BumpNormal, &[])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let mut mat = Material::default();
        let mut n = Vec3::Z;
        tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut n).unwrap();
        // Slope 0.5 along x tilts the normal towards -x: n ∝ (-0.5, 0, 1).
        assert!((n - Vec3::new(-0.5, 0.0, 1.0).normalize()).length() < 1e-3, "{n}");
        let high = TexFrame { p_object: Vec3::new(0.0, 2.0, 0.0), ..frame() };
        let e = tex.apply_shader(0, &tex.maps[0], &high, &mut mat, &mut n).unwrap_err();
        assert!(e.message.contains("s.lua:2: bad"), "{}", e.message);
    }

    #[test]
    fn material_outputs_set_the_material_and_switch_to_the_microfacet_model() {
        let code = "function color(s) return 0.8, 0.4, 0.2 end\n\
                    function specular(s) return 0.04, 0.04, 0.04 end\n\
                    function roughness(s) return 0.5 end\n\
                    function metalness(s) return 0.25 end\n\
                    function emission(s) return 3, 2, 1 end";
        let descs = [map(code, DecalMode::Material, &[])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let mut mat = Material { phong: 30.0, ..Material::default() };
        let mut n = Vec3::Z;
        assert_eq!(tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut n).unwrap(), None);
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        assert!(close(mat.diffuse, Vec3::new(0.6, 0.3, 0.15)), "{}", mat.diffuse);
        assert!(close(mat.specular, Vec3::new(0.23, 0.13, 0.08)), "{}", mat.specular);
        assert_eq!(mat.emission, Vec3::new(3.0, 2.0, 1.0));
        assert_eq!(mat.brdf, Some(Brdf::Microfacet(Microfacet { alpha: 0.25 })));
        assert_eq!(mat.kind, Specular::None);
    }

    #[test]
    fn material_mode_keeps_what_the_script_does_not_define() {
        // Only emission: the material's own model, colours and exponent stay.
        let descs = [map("function emission(s) return 0, 5, 0 end", DecalMode::Material, &[])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let before =
            Material { diffuse: Vec3::splat(0.5), specular: Vec3::ONE, phong: 40.0, ..Material::default() };
        let mut mat = before;
        tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone()).unwrap();
        assert_eq!(
            (mat.diffuse, mat.specular, mat.phong, mat.brdf),
            (before.diffuse, before.specular, 40.0, None)
        );
        assert_eq!(mat.emission, Vec3::new(0.0, 5.0, 0.0));
        // Metalness without roughness keeps the exponent's highlight width.
        let descs = [map("function metalness(s) return 1 end", DecalMode::Material, &[])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let mut mat = before;
        tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone()).unwrap();
        assert_eq!((mat.diffuse, mat.specular), (Vec3::ZERO, Vec3::splat(0.5)));
        assert_eq!(mat.brdf, Some(Brdf::Microfacet(Microfacet::from_exponent(40.0))));
    }

    #[test]
    fn out_of_range_material_outputs_are_one_sentence_errors() {
        for (code, what) in [
            (
                "function roughness(s) return 1.5 end",
                "roughness() returned 1.5 (expected a number from 0 to 1)",
            ),
            ("function metalness(s) return -0.1 end", "metalness() returned -0.1"),
            ("function roughness(s) return 0/0 end", "roughness() returned NaN"),
            (
                "function color(s) return 1.2, 0, 0 end",
                "color() returned 1.2 as its red value (expected 0 to 1",
            ),
            ("function specular(s) return 0, 0, -1 end", "specular() returned -1 as its blue value"),
            (
                "function emission(s) return 0, -2, 0 end",
                "emission() returned -2 as its green value (expected 0 or more",
            ),
            ("function emission(s) return 1/0, 0, 0 end", "emission() returned inf as its red value"),
            ("function reflect(s) return 0.5 end", "reflect() returned nothing (nil) as its green value"),
        ] {
            let descs = [map(code, DecalMode::Material, &[])];
            let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
            let mut mat = Material::default();
            let e = tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone()).unwrap_err();
            assert_eq!(e.kind, crate::shader::ShaderErrorKind::BadResult, "{code}: {e}");
            let text = e.to_string();
            assert!(text.contains(what) && !text.contains('\n'), "{code}: {text}");
        }
        // A script with no material output cannot drive the mode.
        let descs = [map("function height(s) return 0 end", DecalMode::Material, &[])];
        let e = compile(&descs, DEFAULT, None).unwrap_err();
        assert!(e.message.contains("defines none of color, specular, roughness"), "{}", e.message);
    }

    #[test]
    fn a_moved_point_is_the_point_input_builds_there() {
        let xf = crate::math::Transform::scaling(Vec3::new(2.0, 1.0, 0.5))
            .and_then(|s| crate::math::Transform::rotation(30.0, Vec3::Y).map(|r| s.then(&r)))
            .unwrap();
        let mut f = frame();
        f.to_world = Some(xf);
        f.ctx.view = crate::texture::View {
            eye: Vec3::new(0.0, 1.0, 5.0),
            right: Vec3::X,
            up: Vec3::Y,
            back: Vec3::Z,
        };
        f.ctx.incident = Vec3::new(0.0, -0.6, -0.8);
        f.ctx.set_footprint(0.01);
        let n = Vec3::new(0.0, 0.6, 0.8);
        let base = input(&f, f.p_object, f.uv, n);
        for (p, uv) in [
            (f.p_object + Vec3::new(1e-3, 0.0, 0.0), f.uv + Vec2::new(1e-3, 0.0)),
            (f.p_object + Vec3::new(0.0, -2e-3, 5e-4), f.uv + Vec2::new(0.0, 2e-3)),
            (f.p_object, f.uv),
        ] {
            assert_eq!(moved(&f, &base, p, uv), input(&f, p, uv, n), "at {p}");
        }
    }

    const DEFAULT: Duration = crate::shader::DEFAULT_TIMEOUT;
}
