//! Objects whose `DecalMode material` shader defines `emission(s)` become
//! lights ([`Light::Shaded`]) that the path tracer samples like a
//! `LightMesh` (meshes, by area) or a `LightSphere` (spheres, by the cone
//! they subtend); ellipsoids and planes stay lit by bounces only.
//!
//! Which objects: the shader is probed when the scene is built, at
//! [`PROBES`] points spread over the surface at rest (shutter time 0, the
//! camera's first sample context). An object whose shader returned no
//! emission at any of them is left out, so a zero-emission shader costs
//! nothing beyond the path tracer's `emission != 0` check at hits. Emission
//! too fine for the probes to see then reaches the image through bounces
//! alone, at full weight: unbiased either way, only noisier.

use super::{Geom, Prim, Scene, NO_LIGHT};
use crate::integrator::{surface_at, PathState, RayStats, Surface};
use crate::light::{Light, LightMesh, LightSphere, ShadedLight, ShadedShape};
use crate::render::sampler::PixelSampler;
use crate::texture::TexList;
use crate::texture::Texture;
use luster_core::math::{Aabb, Ray, Transform, Vec3};
use luster_scene::description::DecalMode;
use luster_shading::shader::ShaderSet;
use std::sync::Arc;

/// Points at which each candidate's shader is asked for its emission.
pub const PROBES: u32 = 256;

impl Scene {
    /// Adds every object whose shader emits somewhere the probes find, after
    /// every other light (so that in scenes without one the others draw the
    /// same dimensions).
    pub(super) fn add_shaded_lights(&mut self) {
        let Some(shaders) = &self.textures.shaders else { return };
        let mut found = Vec::new();
        for (pi, p) in self.prims.iter().enumerate() {
            if !self.shader_emits(shaders, p.textures) || p.light != NO_LIGHT {
                continue;
            }
            let xf = p.xf.as_deref().copied().unwrap_or(Transform::IDENTITY);
            let shape = match p.geom {
                Geom::Mesh(m) => match LightMesh::new(self.meshes[m as usize].corners(), &xf, Vec3::ZERO) {
                    Some(mut l) => {
                        l.motion = p.motion;
                        ShadedShape::Mesh(l)
                    }
                    None => continue,
                },
                Geom::Sphere(s) => ShadedShape::Sphere(
                    LightSphere::new(s.center, s.radius, &xf, Vec3::ZERO).moving(p.motion),
                ),
                Geom::Ellipsoid(_) => continue,
            };
            found.push(ShadedLight { shape, prim: pi as u32, probed_max: 0.0 });
        }
        for mut l in found {
            l.probed_max = self.probe(&l);
            if l.probed_max > 0.0 {
                self.prims[l.prim as usize].light = self.lights.len() as u32;
                self.lights.push(Light::Shaded(Arc::new(l)));
                self.emitters += 1;
            }
        }
    }

    /// Whether the maps `tex` hold a material shader that defines
    /// `emission(s)` or returns a closure (which may hold an emission).
    fn shader_emits(&self, shaders: &ShaderSet, tex: TexList) -> bool {
        self.textures.maps_of(tex).any(|m| match (m.texture, m.decal) {
            (Texture::Shader { id }, DecalMode::Material) => {
                shaders.has_emission(id as usize) || shaders.has_closure(id as usize)
            }
            _ => false,
        })
    }

    /// The world boxes (swept over the shutter, by `bounds_of`) of every
    /// object a ray can find emitting: object lights and objects whose
    /// shader defines `emission(s)`, whether or not the probes saw it. `None`
    /// where light can come from anywhere a ray goes: an environment,
    /// volumes, or an infinite plane whose shader emits.
    pub(super) fn emitting_boxes(&self, bounds_of: impl Fn(&Prim) -> Aabb) -> Option<Vec<Aabb>> {
        if self.environment.is_some() || !self.volumes.is_empty() {
            return None;
        }
        let shaders = self.textures.shaders.as_ref();
        let emits = |tex: TexList| shaders.is_some_and(|s| self.shader_emits(s, tex));
        if self.planes.iter().any(|p| emits(p.2)) {
            return None;
        }
        let boxes = self.prims.iter().filter(|p| p.light != NO_LIGHT || emits(p.textures)).map(|p| {
            let b = bounds_of(p);
            // Wider by more than rounding, so that no ray the full trace
            // would find on an emitter's edge misses its box.
            let pad = Vec3::splat(1e-4 * (b.max - b.min).max_element() + 4.0 * self.intersection_epsilon);
            Aabb::new(b.min - pad, b.max + pad)
        });
        Some(boxes.collect())
    }

    /// Whether `ray` could meet an emitting surface: false only when every
    /// such surface is bounded (`Scene::emitting_boxes`) and the ray
    /// misses all their boxes. The MIS path tracer's bounce past the depth
    /// limit looks for nothing else, so it skips its trace then. (A ray in
    /// a slab's plane gives NaN there, which the slab test's min/max drop:
    /// that axis then does not rule the box out.)
    #[inline]
    pub fn may_find_emission(&self, ray: &Ray) -> bool {
        let Some(boxes) = &self.emitting_bounds else { return true };
        let inv = Vec3::ONE / ray.d;
        boxes.iter().any(|b| b.hit(ray.o, inv, f32::INFINITY).is_some())
    }

    /// Whether a ray that ends on a surface without lighting it, or finds
    /// nothing, can bring light: false only where every emitter is bounded
    /// ([`Scene::emitting_boxes`]), the background is black without a
    /// texture, and no object or plane has texture maps (a `replace_all`
    /// map shows its colour unlit, and a shader may fail, which the render
    /// reports).
    pub(super) fn only_emitters_shine(&self) -> bool {
        self.emitting_bounds.is_some()
            && self.background == Vec3::ZERO
            && self.textures.background.is_none()
            && self.prims.iter().all(|p| p.textures.is_empty())
            && self.planes.iter().all(|p| p.2.is_empty())
    }

    /// Whether a ray whose end adds nothing but the light found there (no
    /// lighting, no bounce: the last vertex of the course's path tracer
    /// without light samples) can bring any: false only where only the
    /// emitters shine (`Scene::only_emitters_shine`) and the ray misses
    /// their boxes ([`Scene::may_find_emission`]).
    #[inline]
    pub fn may_bring_light(&self, ray: &Ray) -> bool {
        !self.emitters_alone || self.may_find_emission(ray)
    }

    /// The largest emission component the shader gives at the probe points
    /// (infinite when it fails there: the render will report the failure,
    /// and until then the object counts as a light).
    fn probe(&self, l: &ShadedLight) -> f32 {
        let mut st = PathState::new(RayStats::default(), 0.0, PixelSampler::new(0, 0, 0, 0, 1));
        let mut max = 0.0f32;
        for (q, n) in l.probe_points(PROBES) {
            // Start just off the surface, far enough for the hit to clear
            // the intersection epsilon at the point's magnitude.
            let delta = (q.abs().max_element() * 1e-4).max(4.0 * self.intersection_epsilon).max(1e-4);
            for side in [1.0f32, -1.0] {
                let ray = Ray::new(q + n * (delta * side), n * -side);
                let Some(hit) = self.intersect(&ray, 0.0, false) else { continue };
                if self.prim_of(&hit) != Some(l.prim) {
                    continue;
                }
                match surface_at(self, &ray, &hit, 0, &mut st) {
                    Surface::Lit(m, _) => max = max.max(m.emission.max_element()),
                    Surface::Unlit(_) => {}
                    Surface::Failed => return f32::INFINITY,
                }
                break;
            }
        }
        max
    }
}
