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
//! | `replace_normal` | `normal` | the world shading normal it returns, normalized (a zero vector keeps the normal) |
//!
//! `replace_background` takes no shader: the background has no surface
//! point to give a script.

use std::time::Duration;

pub mod attributes;

use super::{bump, Image, TexFrame, TextureMap, Textures};
use crate::bsdf::closure::{At, Lobes};
use crate::bsdf::lobe::{Conductor, Diffuse, Lobe};
use crate::bsdf::Brdf;
use crate::bsdf::Specular;
use crate::material::Material;
use luster_core::math::{Vec2, Vec3};
use luster_scene::description::{DecalMode, ImageDesc, TextureMapDesc, TextureSource};
use luster_shading::shader::{
    Entry, ImageSampler, MaterialOutputs, SampleFilter, ShadeInput, ShadePoint, ShaderError, ShaderErrorKind,
    ShaderImages, ShaderOptions, ShaderSet, ShaderSource,
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
        DecalMode::ReplaceNormal => Some("normal"),
        DecalMode::ReplaceBackground => None,
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
    compile_with(descs, ShaderOptions { timeout, images, ..ShaderOptions::default() })
}

/// Like [`compile`], with everything [`ShaderOptions`] holds (the folders
/// the scripts' `require` searches, the objects' attributes).
pub fn compile_with(descs: &[TextureMapDesc], options: ShaderOptions) -> Result<Option<ShaderSet>, MapError> {
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
    let set = match ShaderSet::build(sources, options) {
        Ok(set) => set,
        // The error names the script at fault by its index, which is its
        // map's (running the scripts again to find it would spend a
        // top level's time limit twice).
        Err(e) => {
            let map = e.source.and_then(|i| maps.get(i)).copied().unwrap_or(maps[0]);
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
                     replace_all, replace_km, bump_normal, replace_normal or material)",
                    decal_name(decal)
                ),
            });
        };
        let has = match entry {
            "color" => set.has_color(id),
            "reflect" => set.has_reflect(id),
            "material" => set.has_material(id),
            "normal" => set.has_normal(id),
            _ => set.has_height(id),
        };
        if !has {
            let name = set.name(id).unwrap_or("?");
            let TextureSource::Shader { path, .. } = &descs[m].source else { continue };
            if decal == DecalMode::Material {
                return Err(MapError {
                    map: m,
                    message: format!(
                        "shader '{name}': {} defines none of material, color, specular, roughness, \
                         metalness, emission or reflect, one of which DecalMode material needs",
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
/// arithmetic would be hoisted in front of the map loop, where every hit
/// would pay for it whatever its maps' modes.
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
    let (duvdx, duvdy) = (uv_change(f, dpdx), uv_change(f, dpdy));
    let camera = |v: Vec3| Vec3::new(v.dot(c.view.right), v.dot(c.view.up), v.dot(c.view.back));
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
        dpwdx: c.dpdx.to_array(),
        dpwdy: c.dpdy.to_array(),
        dpcdx: camera(c.dpdx).to_array(),
        dpcdy: camera(c.dpdy).to_array(),
        duvdx: duvdx.to_array(),
        duvdy: duvdy.to_array(),
    }
}

/// The change of the texture coordinates along object-space step `d` of
/// frame `f`: the `(du, dv)` whose `du·∂p/∂u + dv·∂p/∂v` comes closest to
/// `d` (least squares, as pbrt's ray differentials do); zero where the
/// surface has no usable parameterization.
#[inline(always)]
fn uv_change(f: &TexFrame, d: Vec3) -> Vec2 {
    let (a, b, c) = (f.dpdu.dot(f.dpdu), f.dpdu.dot(f.dpdv), f.dpdv.dot(f.dpdv));
    let det = a * c - b * b;
    if !det.is_finite() || det.abs() <= 1e-12 * a * c {
        return Vec2::ZERO;
    }
    let (pu, pv) = (f.dpdu.dot(d), f.dpdv.dot(d));
    Vec2::new((c * pu - b * pv) / det, (a * pv - b * pu) / det)
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
/// (in place: a returned colour would come back through the stack).
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
        lobes: &mut Lobes,
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
            DecalMode::Material => {
                let at = || At::new(*n, f.ctx.ng, tangent(f), f.ctx.incident);
                let applied = set
                    .material_with(id, &input(f, f.p_object, f.uv, *n), |o| apply_outputs(o, m, lobes, at))?;
                if applied.is_err() {
                    let name = set.name(id).unwrap_or("?");
                    return Err(Box::new(ShaderError::new(
                        ShaderErrorKind::BadResult,
                        name,
                        format!(
                            "material() returned a closure of more than {} lobes (or over 256 nodes, \
                             counting a shared one each time it is used)",
                            crate::bsdf::closure::MAX_LOBES
                        ),
                    )));
                }
            }
            DecalMode::ReplaceNormal => {
                let mut c = Vec3::ZERO;
                rgb(set, id, Entry::Normal, &hit, &mut c)?;
                // The renderer turns it to the side of the geometric normal.
                if let Some(u) = c.try_normalize() {
                    *n = u;
                }
            }
            DecalMode::ReplaceBackground => {}
        }
        Ok(None)
    }
}

/// The world normal `n` bumped by shader `id`'s `height` with factor `k`.
///
/// Out of line on purpose: inlined into [`Textures::apply`], LLVM hoists the
/// bump's set-up (tangent lengths, step, the three points) out of the map
/// loop, so every hit with any shader map would pay for it, even one with a
/// colour map only.
#[inline(never)]
fn shader_bump(set: &ShaderSet, id: usize, k: f32, f: &TexFrame, n: Vec3) -> Result<Vec3, Box<ShaderError>> {
    // The three points are built in place: `pts.map(input)` would build them
    // elsewhere and copy them (a `memmove` call) per hit.
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

/// The roughness whose GGX width matches a Blinn-Phong exponent `p`, so a
/// material that states only its exponent keeps its highlight's width:
/// Walter et al.'s (2007) `α = sqrt(2 / (p + 2))`, and roughness `√α`.
fn exponent_roughness(p: f32) -> f32 {
    (2.0 / (p.max(0.0) + 2.0)).sqrt().sqrt()
}

/// The world tangent of frame `f`: `∂p/∂u`, along which anisotropic lobes
/// stretch.
#[inline]
fn tangent(f: &TexFrame) -> Vec3 {
    match &f.to_world {
        Some(xf) => xf.vector(f.dpdu),
        None => f.dpdu,
    }
}

/// What a `DecalMode material` shader's outputs do to the point's material
/// (the tables in `docs/shaders.md`, "Material outputs", and
/// `docs/closures.md`):
///
/// * a closure (`material(s)`) replaces the material: its lobes go to
///   `lobes`, flattened at the point `at` gives, and its emission to the
///   material's;
/// * otherwise `color` is the base colour (`kd`), `specular` the specular
///   colour (`ks`), `reflect` the mirror reflectance (a non-mirror becomes
///   a mirror, as with `replace_km`), `emission` the emitted radiance;
/// * `roughness` or `metalness` make the point the closure
///   `diffuse{albedo = (1 − max ks) kd} + conductor{f0 = ks, roughness}`
///   whatever the material's own model, where metalness `μ` first turns
///   the diffuse part off and tints the specular colour by the base:
///   `kd ← (1 − μ) kd`, `ks ← (1 − μ) ks + μ kd`. Without a `roughness`
///   the width is the one matching the material's exponent.
///
/// Fails only for a closure of more than [`crate::bsdf::closure::MAX_LOBES`]
/// lobes.
pub fn apply_outputs(
    o: &MaterialOutputs,
    m: &mut Material,
    lobes: &mut Lobes,
    at: impl FnOnce() -> At,
) -> Result<(), crate::bsdf::closure::TooManyLobes> {
    if let Some(c) = &o.closure {
        lobes.flatten_into(c, &at())?;
        *m = Material { emission: lobes.emission, closure: true, ..Material::default() };
        return Ok(());
    }
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
        return Ok(());
    }
    let roughness = match (o.roughness, m.brdf) {
        (Some(r), _) => r,
        (None, Some(Brdf::Phong(p))) => exponent_roughness(p.exponent),
        (None, Some(Brdf::TorranceSparrow(t))) => exponent_roughness(t.exponent),
        (None, None) => exponent_roughness(m.phong),
    };
    if let Some(mu) = o.metalness {
        m.specular = m.specular * (1.0 - mu) + m.diffuse * mu;
        m.diffuse *= 1.0 - mu;
    }
    let (kd, ks) = (m.diffuse, m.specular);
    // A specular colour under 2% reflects nothing: no real material is
    // that dark head on, so it means "no specular" (Unreal's convention).
    let specular = ks.max_element() >= 0.02;
    let base = kd * (1.0 - ks.max_element().clamp(0.0, 1.0));
    let parts = [
        (Vec3::ONE, Lobe::Diffuse(Diffuse::new(base, 0.0))),
        (Vec3::ONE, Lobe::Conductor(Conductor::new(ks, Vec3::ONE, roughness, 0.0))),
    ];
    let n = if specular { 2 } else { 1 };
    lobes.of_into(&parts[..n], &at())?;
    m.brdf = None;
    m.closure = true;
    Ok(())
}

#[cfg(test)]
mod tests;
