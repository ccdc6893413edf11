//! Volumes (a luster extension of the scene format): participating media
//! that absorb, scatter and emit light along rays, and hypertextures, surfaces
//! where a density field crosses a threshold (Perlin & Hoffert 1989).
//!
//! A volume is a bound ([`Bound`]: ball, box or ellipsoid, with a transform)
//! and a density inside it: a constant, a Lua script's `density(s)`, or that
//! script baked on a [`Grid`]. `s.P` is the point in the bound's own space,
//! `s.Pw` in the world; a marched script also sees the ray ([`Probe`]: `s.Pc`,
//! `s.I`, the pixel, the time), and every script its volume's index and the
//! march step or grid cell as `s.filterwidth`. Outside its bound a volume has
//! no density. Baked grids may come from a [`GridCache`] kept across builds.
//!
//! This module is the volumes' data and their local queries (density,
//! emission, isosurface search, the majorants that bound a medium's
//! extinction), and the homogeneous media that fill objects ([`Interior`]).
//! How rays gather light through them is beside the integrators: ray
//! marching with single scattering for the recursive tracer in
//! `integrator::media`, tracking for the path tracer in
//! `integrator::tracking`. Scene parameters are listed in
//! `scene::ceng795::volumes` and `scene::ceng795::media`.

pub mod bound;
pub mod cache;
pub mod grid;
pub mod majorant;
mod surface;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_cache;
mod vdb;

pub use bound::Bound;
pub use cache::{Baking, GridCache};
pub use grid::Grid;
pub use majorant::Majorant;

use crate::texture::shader::shader_name;
use crate::texture::{TexList, Textures, View};
use luster_core::math::{Aabb, Vec3};
use luster_scene::description::{Description, RendererDesc, VolumeDesc, VolumeKind};
use luster_scene::SceneError;
use luster_shading::shader::{
    ShadeInput, ShaderError, ShaderErrorKind, ShaderImages, ShaderOptions, ShaderSet, ShaderSource,
};
use std::sync::Arc;
use std::time::Duration;

/// Default ray-marching steps across a medium's bound (its world diagonal over this).
pub const MEDIUM_STEPS: f32 = 64.0;
/// Default steps across a hypertexture's bound: finer, since a step can jump
/// over a feature thinner than itself; the crossing found is then refined by
/// bisection to a thousandth of a step.
pub const SURFACE_STEPS: f32 = 256.0;

/// Most steps one ray takes across one volume: a `StepSize` that would need
/// more is refused when the scene is built (it would stall the render).
pub const MAX_STEPS: f32 = 100_000.0;

/// Largest volume box accepted, corner to corner: beyond it the f32 positions
/// of the march are too coarse for any step size (and a box of 1e30 has an
/// infinite diagonal in f32).
pub const MAX_EXTENT: f32 = 1e7;

/// How many equal steps of at most `step` cover `len` (at least 1, at most
/// [`MAX_STEPS`]).
#[inline]
pub fn steps(len: f32, step: f32) -> u32 {
    (len / step).ceil().clamp(1.0, MAX_STEPS) as u32
}

/// Points per edge of the grid a medium's script is baked on when a path
/// tracer renders it and the scene gives no `GridResolution`.
pub const TRACKING_GRID: u32 = 128;

/// Most memory the baked grids of one volume may take.
pub const MAX_GRID_BYTES: u64 = 1 << 30;

/// Where a volume's density comes from.
#[derive(Debug)]
enum Field {
    Constant,
    Script(usize),
    Grid(Arc<Grid<f32>>),
}

/// Where a medium's emission comes from.
#[derive(Debug)]
pub enum Glow {
    /// Emission per unit length at density 1, times the density.
    Constant(Vec3),
    /// The script's `emission(s)`.
    Script(usize),
    /// The script's `emission(s)`, baked.
    Grid(Arc<Grid<Vec3>>),
}

/// What a volume does.
#[derive(Debug)]
pub enum Kind {
    /// A participating medium.
    Medium {
        /// σa at density 1.
        absorption: Vec3,
        /// σs at density 1.
        scattering: Vec3,
        /// Emission.
        glow: Glow,
        /// Henyey–Greenstein g.
        anisotropy: f32,
        /// Terms of the multiple-scattering approximation (1: single scattering).
        octaves: u32,
    },
    /// A hypertexture.
    Surface {
        /// Material index.
        material: u32,
        /// The density of the surface.
        threshold: f32,
        /// Its texture maps.
        textures: TexList,
    },
}

/// One volume, ready to render.
#[derive(Debug)]
pub struct Volume {
    /// Its region.
    pub bound: Bound,
    field: Field,
    /// Multiplies the field (`Density`).
    scale: f32,
    /// Ray-marching step, world units.
    pub step: f32,
    /// Medium or surface.
    pub kind: Kind,
    /// How messages name it: `Volume[id=cloud]`.
    pub label: String,
    /// Its index among the scene's volumes (`s.object_id`, `s.instance_id`).
    index: u32,
    /// The march step in the bound's own space (`s.filterwidth` of a script
    /// that is not baked).
    march_width: f32,
    /// Bounds on a medium's extinction for the path tracer's tracking;
    /// `None` for a hypertexture or a script that is not baked.
    pub majorant: Option<Majorant>,
}

/// What a volume script sees of the ray along which it is asked, beyond the
/// point: the render's context for `s.Pc`, `s.I`, `s.pixel_x`, `s.time`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Probe {
    /// The ray's time within the shutter.
    pub time: f32,
    /// The unit direction of the ray being marched, world space (a shadow
    /// ray's points to the light).
    pub dir: Vec3,
    /// The camera's frame.
    pub view: View,
    /// The pixel being rendered.
    pub pixel: [u32; 2],
}

impl Probe {
    /// A probe at `time` with no ray, camera or pixel (tests, baking).
    pub fn at(time: f32) -> Probe {
        Probe { time, ..Probe::default() }
    }
}

/// A homogeneous medium filling the inside of objects (`<Media>`,
/// `<Interior>`): the path tracer tracks it wherever a path has entered
/// such an object through its surface.
#[derive(Clone, Debug)]
pub struct Interior {
    /// σa.
    pub absorption: Vec3,
    /// σs.
    pub scattering: Vec3,
    /// Emitted radiance per unit length.
    pub emission: Vec3,
    /// Henyey–Greenstein g.
    pub anisotropy: f32,
}

/// No medium inside (in [`Volumes::interior_of`]'s table).
const NO_INTERIOR: u32 = u32::MAX;

/// The scene's volumes and their scripts.
#[derive(Debug, Default)]
pub struct Volumes {
    /// Participating media.
    pub media: Vec<Volume>,
    /// Hypertextures.
    pub surfaces: Vec<Volume>,
    /// Media filling objects.
    pub interiors: Vec<Interior>,
    /// Per object of the description: the index of its interior, or [`NO_INTERIOR`].
    object_interior: Vec<u32>,
    shaders: Option<ShaderSet>,
}

impl Volume {
    /// The density at world point `p` (0 outside is the caller's business:
    /// this is only asked inside the bound).
    #[inline]
    pub fn density(&self, v: &Volumes, p: Vec3, probe: &Probe) -> Result<f32, ShaderError> {
        let d = match &self.field {
            Field::Constant => 1.0,
            Field::Script(id) => v.call(*id, self, p, probe, ShaderSet::density)?,
            Field::Grid(g) => g.at(self.bound.to_local(p)),
        };
        Ok(d.max(0.0) * self.scale)
    }

    /// A medium's emitted radiance per unit length at world point `p`, where
    /// its density is `density`.
    #[inline]
    pub fn emission(&self, v: &Volumes, p: Vec3, probe: &Probe, density: f32) -> Result<Vec3, ShaderError> {
        let Kind::Medium { glow, .. } = &self.kind else { return Ok(Vec3::ZERO) };
        Ok(match glow {
            Glow::Constant(c) => *c * density,
            Glow::Script(id) => {
                Vec3::from_array(v.call(*id, self, p, probe, ShaderSet::emission)?).max(Vec3::ZERO)
            }
            Glow::Grid(g) => g.at(self.bound.to_local(p)).max(Vec3::ZERO),
        })
    }

    /// Whether the medium emits light anywhere.
    pub fn glows(&self) -> bool {
        match &self.kind {
            Kind::Medium { glow: Glow::Constant(c), .. } => c.max_element() > 0.0,
            Kind::Medium { .. } => true,
            Kind::Surface { .. } => false,
        }
    }

    /// The baked or loaded density grid (before `Density` scales it), in the
    /// bound's own space; `None` for a constant or an unbaked script.
    pub fn density_grid(&self) -> Option<&Grid<f32>> {
        match &self.field {
            Field::Grid(g) => Some(g),
            _ => None,
        }
    }

    /// The `Density` factor on the field.
    pub fn density_scale(&self) -> f32 {
        self.scale
    }

    /// The density of a volume whose density is the same everywhere in its
    /// bound (so transmittance through it is exact without marching).
    pub fn constant_density(&self) -> Option<f32> {
        matches!(self.field, Field::Constant).then_some(self.scale)
    }
}

impl Volumes {
    /// Whether the scene has no volume at all.
    pub fn is_empty(&self) -> bool {
        self.media.is_empty() && self.surfaces.is_empty() && self.interiors.is_empty()
    }

    /// Whether light may be absorbed or scattered between surfaces: the
    /// scene has media in bounds or inside objects.
    #[inline]
    pub fn has_media(&self) -> bool {
        !self.media.is_empty() || !self.interiors.is_empty()
    }

    /// The medium inside object `object` (an index into the description's
    /// objects), if any.
    #[inline]
    pub fn interior_of(&self, object: u32) -> Option<u32> {
        self.object_interior.get(object as usize).copied().filter(|&i| i != NO_INTERIOR)
    }

    fn call<R>(
        &self,
        id: usize,
        vol: &Volume,
        p: Vec3,
        probe: &Probe,
        f: impl FnOnce(&ShaderSet, usize, &ShadeInput) -> Result<R, ShaderError>,
    ) -> Result<R, ShaderError> {
        let set = self.shaders.as_ref().ok_or_else(|| missing_set(&vol.label))?;
        let input = ShadeInput {
            p: vol.bound.to_local(p).to_array(),
            pw: p.to_array(),
            pc: probe.view.to_camera(p).to_array(),
            i: probe.dir.to_array(),
            time: probe.time,
            filterwidth: vol.march_width,
            object_id: vol.index,
            instance_id: vol.index,
            pixel: probe.pixel,
            ..ShadeInput::default()
        };
        f(set, id, &input)
    }

    /// The module files the volume scripts have required so far.
    pub fn shader_modules(&self) -> Vec<std::path::PathBuf> {
        self.shaders.as_ref().map(ShaderSet::required_files).unwrap_or_default()
    }

    /// Builds the volumes of `desc`: compiles their scripts (sampling
    /// `images` with `texture()`), checks their entry points, bakes grids, and
    /// registers hypertextures' texture maps in `textures`.
    pub fn build(
        desc: &Description,
        textures: &mut Textures,
        images: Option<ShaderImages>,
        timeout: Duration,
    ) -> Result<Volumes, SceneError> {
        Volumes::build_baking(desc, textures, images, timeout, &Baking::default())
    }

    /// Like [`Volumes::build`], taking grids from `baking`'s cache where it
    /// has them (and keeping those it bakes there), and giving up with
    /// [`cache::CANCELLED`] once its flag is set.
    pub fn build_baking(
        desc: &Description,
        textures: &mut Textures,
        images: Option<ShaderImages>,
        timeout: Duration,
        baking: &Baking,
    ) -> Result<Volumes, SceneError> {
        let err = |v: &VolumeDesc, msg: String| SceneError::at(&desc.file, &v.loc, msg);
        let shaders = compile_scripts(desc, images, timeout)?;
        let path_traced = desc.cameras.iter().any(|c| matches!(c.renderer, RendererDesc::PathTracing(_)));
        let mut out = Volumes {
            media: Vec::new(),
            surfaces: Vec::new(),
            interiors: desc
                .media
                .iter()
                .map(|m| Interior {
                    absorption: m.absorption,
                    scattering: m.scattering,
                    emission: m.emission,
                    anisotropy: m.anisotropy,
                })
                .collect(),
            object_interior: Vec::new(),
            shaders: None,
        };
        if !desc.interiors.is_empty() {
            out.object_interior = vec![NO_INTERIOR; desc.objects.len()];
            for i in &desc.interiors {
                if let Some(slot) = out.object_interior.get_mut(i.object) {
                    *slot = i.medium as u32;
                }
            }
        }
        let mut next_script = 0;
        for (index, v) in desc.volumes.iter().enumerate() {
            // A VDB file is read first: a volume without a bound is bounded by its grids.
            let lattice = match &v.vdb {
                Some(f) => Some(vdb::load(f).map_err(|m| SceneError::at(&desc.file, &f.loc, m))?),
                None => None,
            };
            let bound = match (&v.bound, &lattice) {
                (Some(b), _) => Bound::new(b, &v.transform),
                (None, Some(l)) => Bound::new(&l.bound(), &v.transform),
                (None, None) => return Err(err(v, "needs a bound: <Sphere>, <Box> or <Ellipsoid>".into())),
            };
            let label = format!(
                "{}[id={}]",
                if matches!(v.kind, VolumeKind::Surface { .. }) { "Hypertexture" } else { "Volume" },
                v.id
            );
            let script = v.script.as_ref().map(|_| {
                next_script += 1;
                next_script - 1
            });
            if let (Some(id), Some(set)) = (script, &shaders) {
                if !set.has_density(id) {
                    return Err(err(
                        v,
                        format!(
                            "shader '{}': {} defines no density(s) function",
                            set.name(id).unwrap_or("?"),
                            v.script.as_ref().map_or(String::new(), |s| s.path.display().to_string())
                        ),
                    ));
                }
            }
            let mut step = march_step(v, &bound).map_err(|m| err(v, m))?;
            if let (Some(l), None) = (&lattice, v.step) {
                step = l.world_step(&v.transform).max(bound.diagonal() / MAX_STEPS);
            }
            let kind = match &v.kind {
                VolumeKind::Medium { absorption, scattering, emission, anisotropy, octaves } => {
                    let glow = match (script, &shaders) {
                        (Some(id), Some(set)) if set.has_emission(id) => Glow::Script(id),
                        _ => Glow::Constant(*emission),
                    };
                    Kind::Medium {
                        absorption: *absorption,
                        scattering: *scattering,
                        glow,
                        anisotropy: *anisotropy,
                        octaves: *octaves,
                    }
                }
                VolumeKind::Surface { material, threshold, textures: maps } => Kind::Surface {
                    material: *material as u32,
                    threshold: *threshold,
                    textures: textures.add_list(maps),
                },
            };
            let field = match script {
                Some(id) => Field::Script(id),
                None => Field::Constant,
            };
            // The step in the bound's space: its box's diagonal there over the world's.
            let march_width = step * bound.local_box().extent().length() / bound.diagonal();
            let mut vol = Volume {
                bound,
                field,
                scale: v.density,
                step,
                kind,
                label,
                index: index as u32,
                march_width,
                majorant: None,
            };
            if let (Some(l), Some(f)) = (lattice, &v.vdb) {
                let colour = match &v.kind {
                    VolumeKind::Medium { emission, .. } => *emission,
                    VolumeKind::Surface { .. } => Vec3::ZERO,
                };
                let (density, glow) =
                    l.grids(v.bound.as_ref(), colour).map_err(|m| SceneError::at(&desc.file, &f.loc, m))?;
                vol.field = Field::Grid(Arc::new(density));
                if let (Some(g), Kind::Medium { glow: slot, .. }) = (glow, &mut vol.kind) {
                    *slot = Glow::Grid(Arc::new(g));
                }
            }
            // The path tracer's tracking needs bounds on the density, which
            // only a constant or a grid has: its scripts are baked.
            let grid = match (v.grid, &v.kind) {
                (None, VolumeKind::Medium { .. }) if path_traced => Some(TRACKING_GRID),
                (g, _) => g,
            };
            if let (Some(n), Some(id)) = (grid, script) {
                let slot = baking.cache.and_then(|c| cache::key(desc, index, n).map(|key| (c, key)));
                if let Some(grids) = slot.as_ref().and_then(|(c, key)| c.get(key)) {
                    vol.use_grids(grids);
                } else {
                    let grids = vol.bake(shaders.as_ref(), id, n, baking).map_err(|e| err(v, e))?;
                    if let Some((c, key)) = slot {
                        let modules = shaders.as_ref().map(ShaderSet::required_files).unwrap_or_default();
                        c.put(key, &modules, grids);
                    }
                }
            }
            vol.majorant = vol.bounds();
            match vol.kind {
                Kind::Medium { .. } => out.media.push(vol),
                Kind::Surface { .. } => out.surfaces.push(vol),
            }
        }
        out.shaders = shaders;
        Ok(out)
    }
}

/// The volumes' density scripts as one set (script k is the k-th volume
/// with a script), or `None` when no volume has one.
fn compile_scripts(
    desc: &Description,
    images: Option<ShaderImages>,
    timeout: Duration,
) -> Result<Option<ShaderSet>, SceneError> {
    let err = |v: &VolumeDesc, msg: String| SceneError::at(&desc.file, &v.loc, msg);
    // Script k of the set belongs to the k-th volume with a script.
    let mut sources = Vec::new();
    // (volume index, shader name) of each source.
    let mut owners = Vec::new();
    for (i, v) in desc.volumes.iter().enumerate() {
        if let Some(s) = &v.script {
            let name = shader_name(&s.path);
            owners.push((i, name.clone()));
            let mut src = ShaderSource::new(name, s.path.clone(), s.code.clone());
            src.params = s.params.clone();
            sources.push(src);
        }
    }
    Ok(if sources.is_empty() {
        None
    } else {
        let options = ShaderOptions {
            timeout,
            images,
            module_dirs: desc.module_search_path(),
            attributes: Arc::new(crate::texture::shader::attributes::for_volumes(desc)?),
        };
        Some(ShaderSet::build(sources, options).map_err(|e| {
            // The error names the failing script's index; its volume gives the location.
            let at = e.source.and_then(|i| owners.get(i)).map_or(owners[0].0, |o| o.0);
            err(&desc.volumes[at], e.to_string())
        })?)
    })
}

/// The marching step of `v` (its `StepSize`, or a fraction of its box's
/// diagonal), refused where its box is too large to march in `f32` or the
/// step would need too many steps to cross it.
fn march_step(v: &VolumeDesc, bound: &Bound) -> Result<f32, String> {
    let per_bound = if matches!(v.kind, VolumeKind::Surface { .. }) { SURFACE_STEPS } else { MEDIUM_STEPS };
    if !bound.diagonal().is_finite() || bound.diagonal() > MAX_EXTENT {
        return Err(format!(
            "its box is {:.3e} across; at most {MAX_EXTENT:e} is supported (f32 positions that far out cannot be marched)",
            bound.diagonal()
        ));
    }
    let step = v.step.unwrap_or(bound.diagonal() / per_bound);
    let count = bound.diagonal() / step;
    if count.is_nan() || count > MAX_STEPS {
        return Err(format!(
            "<StepSize> {step} would take more than {MAX_STEPS} steps across the volume (its box is {:.3} across)",
            bound.diagonal()
        ));
    }
    Ok(step)
}

impl Volume {
    /// The majorant of a medium whose density is a constant or a grid.
    fn bounds(&self) -> Option<Majorant> {
        let Kind::Medium { absorption, scattering, glow, .. } = &self.kind else { return None };
        let sigma_t = (*absorption + *scattering).max_element().max(0.0);
        match &self.field {
            Field::Constant => Some(Majorant::Uniform(self.scale.max(0.0) * sigma_t)),
            Field::Grid(g) => {
                let glows = match glow {
                    Glow::Grid(e) => Some(&**e),
                    _ => None,
                };
                Some(Majorant::of_grid(g, self.scale.max(0.0), sigma_t, glows, 1.0 / self.step))
            }
            Field::Script(_) => None,
        }
    }

    /// Replaces the script's density (and emission) by `grids`.
    fn use_grids(&mut self, grids: cache::Baked) {
        if let Kind::Medium { glow, .. } = &mut self.kind {
            if let (Glow::Script(_), Some(g)) = (&glow, grids.emission) {
                *glow = Glow::Grid(g);
            }
        }
        self.field = Field::Grid(grids.density);
    }

    /// Replaces the script's density (and emission) by grids of `n³` samples
    /// over the bound's own box; returns them.
    fn bake(
        &mut self,
        set: Option<&ShaderSet>,
        id: usize,
        n: u32,
        baking: &Baking,
    ) -> Result<cache::Baked, String> {
        let set = set.ok_or_else(|| missing_set(&self.label).to_string())?;
        let glows = matches!(self.kind, Kind::Medium { glow: Glow::Script(_), .. });
        let per_point = if glows { 16 } else { 4 };
        let bytes = u64::from(n).pow(3) * per_point;
        if bytes > MAX_GRID_BYTES {
            return Err(format!(
                "a {n}³ grid{} takes {:.1} GB, more than the {:.1} GB allowed; use a smaller GridResolution",
                if glows { " of density and emission" } else { "" },
                bytes as f64 / 1e9,
                MAX_GRID_BYTES as f64 / 1e9
            ));
        }
        let b: Aabb = self.bound.local_box();
        let bound = &self.bound;
        // Baked once for every ray: no camera, ray or pixel; the footprint is a cell.
        let cell = (b.extent() / (n.max(2) - 1) as f32).max_element();
        let input = |q: Vec3| ShadeInput {
            p: q.to_array(),
            pw: bound.to_world(q).to_array(),
            filterwidth: cell,
            object_id: self.index,
            instance_id: self.index,
            ..ShadeInput::default()
        };
        // A cancelled bake stops at the next sample any thread takes.
        let check = || if baking.cancelled() { Err(cache::CANCELLED.to_string()) } else { Ok(()) };
        let density = Grid::bake(b, n, |q| {
            check()?;
            set.density(id, &input(q)).map_err(|e| e.to_string())
        })?;
        let emission = if matches!(self.kind, Kind::Medium { glow: Glow::Script(_), .. }) {
            Some(Arc::new(Grid::bake(b, n, |q| {
                check()?;
                set.emission(id, &input(q)).map(Vec3::from_array).map_err(|e| e.to_string())
            })?))
        } else {
            None
        };
        let grids = cache::Baked { density: Arc::new(density), emission };
        self.use_grids(grids.clone());
        Ok(grids)
    }
}

fn missing_set(label: &str) -> ShaderError {
    ShaderError::new(ShaderErrorKind::Internal, label, "volume scripts were not compiled")
}
