//! The render scene: immutable, `Sync`, built once from a
//! [`Description`](luster_scene::description::Description).
//!
//! Geometry is two-level. Every mesh (inline, PLY, or a single `Triangle`) is
//! built once in its own object space with its own BVH; objects — meshes,
//! instances of meshes, spheres, ellipsoids — are primitives of a top-level
//! BVH, each with an optional object-to-world transform. Rays are moved into
//! object space without renormalizing, so `t` means the same in both spaces.
//! Infinite planes have no box and are tested beside the BVH. Moving objects
//! (`MotionBlur`) sit in the top level with boxes swept over the shutter
//! interval, so one BVH serves every ray time.

use crate::accel::triangle::WatertightRay;
use crate::accel::{Bvh, TriHit};
use crate::geometry::{Ellipsoid, Mesh, Plane, Sphere};
use crate::light::tree::LightTree;
use crate::light::{Environment, Light};
use crate::material::Material;
use crate::render::camera::Camera;
use crate::texture::{TexFrame, TexList, Textures};
use crate::volume::Volumes;
use luster_core::math::{Aabb, Ray, Transform, Vec2, Vec3};
use luster_scene::Warning;

/// Units in the last place of a hit's coordinates that a ray leaving it is
/// offset by in a scene without a `ShadowRayEpsilon` ([`Scene::offset`]):
/// the rounding of `o + t d` is a few of them.
pub const OFFSET_ULPS: f32 = 32.0;
use std::sync::Arc;

mod build;
mod shaded_lights;
mod tracer;
mod traverse;
pub use build::BuildOptions;

/// What a top-level primitive is.
#[derive(Clone, Copy, Debug)]
enum Geom {
    Mesh(u32),
    Sphere(Sphere),
    /// Index into [`Scene::ellipsoids`] (kept apart so this enum stays small).
    Ellipsoid(u32),
}

/// A primitive of the top-level BVH.
struct Prim {
    geom: Geom,
    material: u32,
    /// Translation over the shutter interval (zero for static objects).
    motion: Vec3,
    /// `None` when the object's transform is the identity, which skips two
    /// matrix-vector products per ray.
    xf: Option<Box<Transform>>,
    /// The object's texture maps.
    textures: TexList,
    /// Index of the object in the description (for [`Scene::object_label`]).
    object: u32,
    /// Index into [`Scene::lights`] when the object emits (`NO_LIGHT` if not).
    light: u32,
    /// No transform and no motion (see [`Prim::in_world`]), worked out at
    /// build time: the traversal asks for every object it tests.
    world: bool,
}

/// [`Prim::light`] of an object that does not emit.
const NO_LIGHT: u32 = u32::MAX;

impl Prim {
    /// Whether the object's space is world space at every time (no
    /// transform, no motion): the world ray's prepared forms serve it.
    #[inline(always)]
    fn in_world(&self) -> bool {
        self.world
    }

    /// The watertight form of the object-space ray `local`: the world ray's
    /// (`ray`'s), shared, where [`Prim::in_world`], made in `world` on first
    /// use (a shadow ray that meets no mesh never needs it); else made in
    /// `own`. The axes are looked up (`by_table`: [`Scene::axes_by_table`])
    /// or worked out, the same values either way: the lookup saves work per
    /// ray, but does not pay in a scene whose meshes have trees of their own
    /// (the wine glass), as in MeshAccel's own queries.
    #[inline(always)]
    fn watertight<'a>(
        &self,
        world: &'a mut Option<WatertightRay>,
        ray: &Ray,
        local: &Ray,
        own: &'a mut Option<WatertightRay>,
        by_table: bool,
    ) -> &'a WatertightRay {
        let make = |r: &Ray| if by_table { WatertightRay::new_lookup(r) } else { WatertightRay::new(r) };
        if self.in_world() {
            world.get_or_insert_with(|| make(ray))
        } else {
            own.insert(make(local))
        }
    }

    /// The ray at `time` in the primitive's object space (same `t` as in
    /// world space): motion blur undoes the object's translation at that time,
    /// then the inverse transform.
    #[inline]
    fn to_local(&self, ray: &Ray, time: f32) -> Ray {
        let o = ray.o - self.motion * time;
        match &self.xf {
            Some(xf) => Ray::new(xf.inv_point(o), xf.inv_vector(ray.d)),
            None => Ray::new(o, ray.d),
        }
    }
}

/// Which surface is nearest so far during traversal.
#[derive(Clone, Copy)]
enum Closest {
    Plane(usize),
    Triangle(usize, TriHit),
    Sphere(usize),
    Ellipsoid(usize),
}

/// Which surface a hit is on, for computing its texture frame on demand.
#[derive(Clone, Copy, Debug)]
pub enum HitGeom {
    /// Plane `i`.
    Plane(u32),
    /// A triangle of primitive `prim`.
    Triangle {
        /// Primitive.
        prim: u32,
        /// The mesh hit.
        hit: TriHit,
    },
    /// The sphere of primitive `prim`.
    Sphere {
        /// Primitive.
        prim: u32,
    },
    /// The ellipsoid of primitive `prim`.
    Ellipsoid {
        /// Primitive.
        prim: u32,
    },
    /// Hypertexture `i` (an index into the scene's `volumes.surfaces`).
    Volume(u32),
}

/// Everything about the closest hit that shading needs, in world space.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Position.
    pub p: Vec3,
    /// Unit geometric normal, facing where the winding (or the sphere's outside) says.
    pub ng: Vec3,
    /// Unit shading normal, on the same side as `ng`.
    pub ns: Vec3,
    /// Material index.
    pub material: u32,
    /// The object's texture maps.
    pub textures: TexList,
    /// The surface hit.
    pub geom: HitGeom,
}

/// A scene ready to render.
pub struct Scene {
    meshes: Vec<Mesh>,
    ellipsoids: Vec<Ellipsoid>,
    prims: Vec<Prim>,
    tlas: Bvh,
    /// Infinite planes: the plane, its material, its maps and its object index.
    planes: Vec<(Plane, u32, TexList, u32)>,
    /// Every object's name for messages, `Sphere[id=2]`, by description index.
    object_labels: Vec<String>,
    /// Every object's geometry: its own index, or an instance's mesh's.
    geometry_objects: Vec<u32>,
    /// Images and texture maps.
    pub textures: Textures,
    /// Participating media and hypertextures.
    pub volumes: Volumes,
    /// Materials.
    pub materials: Vec<Material>,
    /// Lights for direct lighting: point, directional, spot, area, then the
    /// environment (this order fixes which sampler dimensions each uses).
    pub lights: Vec<Light>,
    /// The environment map, which rays that escape see.
    pub environment: Option<Arc<Environment>>,
    /// How many of [`lights`](Self::lights) are emitting objects.
    pub emitters: usize,
    /// Which light the MIS path tracer samples at a point when it samples
    /// one.
    pub light_tree: LightTree,
    /// The environment's index in `lights`.
    pub environment_light: Option<usize>,
    /// Ambient light.
    pub ambient: Vec3,
    /// Colour of rays that miss.
    pub background: Vec3,
    /// Offset of secondary ray origins, where the scene sets one
    /// (`fixed_offset`); see [`Scene::offset`].
    pub shadow_epsilon: f32,
    /// Whether the scene set `shadow_epsilon`.
    pub fixed_offset: bool,
    /// The smallest coordinate size [`Scene::offset`] scales from: a
    /// sixteenth of the scene's radius.
    pub offset_floor: f32,
    /// Smallest accepted hit distance.
    pub intersection_epsilon: f32,
    /// Bounces after the camera ray.
    pub max_depth: u32,
    /// Cameras.
    pub cameras: Vec<Camera>,
    /// Notes from building (e.g. degenerate triangles a PLY file had).
    pub warnings: Vec<Warning>,
    /// Boxes around everything that can emit ([`Scene::emitting_boxes`]).
    emitting_bounds: Option<Vec<Aabb>>,
    /// Whether only those boxes' emitters give a ray light of their own
    /// ([`Scene::only_emitters_shine`]).
    emitters_alone: bool,
    /// Whether the CPU has AVX2 and FMA, detected once at build: every
    /// query asks, and the detection's cached answer would take two loads
    /// and two branches each time.
    simd: bool,
    /// Whether queries make their watertight rays with
    /// [`WatertightRay::new_lookup`] (no mesh walks more than one node) or
    /// [`WatertightRay::new`] (see [`Prim::watertight`]).
    axes_by_table: bool,
}

impl Scene {
    /// The object a hit is on, as messages name it: `Sphere[id=2]`.
    pub fn object_label(&self, hit: &Hit) -> &str {
        let object = match hit.geom {
            HitGeom::Plane(i) => self.planes.get(i as usize).map(|p| p.3),
            HitGeom::Triangle { prim, .. } | HitGeom::Sphere { prim } | HitGeom::Ellipsoid { prim } => {
                self.prims.get(prim as usize).map(|p| p.object)
            }
            HitGeom::Volume(i) => {
                return self.volumes.surfaces.get(i as usize).map_or("a hypertexture", |v| v.label.as_str())
            }
        };
        object.and_then(|o| self.object_labels.get(o as usize)).map_or("an object", String::as_str)
    }

    /// Whether a camera sample's shutter time can change what it sees:
    /// something moves, or a shader or a volume (whose scripts may read
    /// `s.time`) is present. Without any, every time gives the same bits
    /// (`p − 0·t` is `p`), and the render loop need not draw one.
    pub fn uses_shutter_time(&self) -> bool {
        let moves = |m: Vec3| m != Vec3::ZERO;
        let light_moves = |l: &Light| match l {
            Light::Mesh(m) => moves(m.motion),
            Light::Sphere(s) => moves(s.motion),
            Light::Shaded(s) => match &s.shape {
                crate::light::ShadedShape::Mesh(m) => moves(m.motion),
                crate::light::ShadedShape::Sphere(s) => moves(s.motion),
            },
            _ => false,
        };
        self.prims.iter().any(|p| moves(p.motion))
            || self.lights.iter().any(light_moves)
            || self.textures.shaders.is_some()
            || !self.volumes.is_empty()
    }

    /// The medium (an index into the interiors of [`Scene::volumes`]) a ray
    /// going along `d` through the surface at `hit` enters: the object's
    /// interior when it goes in (against the outward geometric normal),
    /// none when it comes out. Interiors do not nest.
    pub fn medium_across(&self, hit: &Hit, d: Vec3) -> Option<u32> {
        if d.dot(hit.ng) >= 0.0 {
            return None;
        }
        let object = match hit.geom {
            HitGeom::Plane(i) => self.planes.get(i as usize).map(|p| p.3),
            HitGeom::Triangle { prim, .. } | HitGeom::Sphere { prim } | HitGeom::Ellipsoid { prim } => {
                self.prims.get(prim as usize).map(|p| p.object)
            }
            HitGeom::Volume(_) => None,
        };
        self.volumes.interior_of(object?)
    }

    /// How far off the surface a ray leaving the hit point `p` starts, for
    /// a hit found by a ray from `o`: the scene's `ShadowRayEpsilon` where
    /// it sets one; else [`OFFSET_ULPS`] units in the last place of the
    /// largest coordinate involved (`p`'s, `o`'s, or a sixteenth of the
    /// scene's radius). `p = o + t d` is rounded to a few units of that
    /// size, so the offset clears the rounding at any scale, and a shadow
    /// ray stopping that far short of its light ends off the light's
    /// surface.
    #[inline(always)]
    pub fn offset(&self, p: Vec3, o: Vec3) -> f32 {
        if self.fixed_offset {
            return self.shadow_epsilon;
        }
        let size = p.abs().max(o.abs()).max_element().max(self.offset_floor);
        size * (OFFSET_ULPS * f32::EPSILON)
    }

    /// The indices a shader sees as `s.object_id` and `s.instance_id`: the
    /// geometry's object (an instance's mesh) and the object hit itself.
    pub fn object_ids(&self, hit: &Hit) -> (u32, u32) {
        let object = match hit.geom {
            HitGeom::Plane(i) => self.planes.get(i as usize).map(|p| p.3),
            HitGeom::Triangle { prim, .. } | HitGeom::Sphere { prim } | HitGeom::Ellipsoid { prim } => {
                self.prims.get(prim as usize).map(|p| p.object)
            }
            // A hypertexture's surface is no object of the description.
            HitGeom::Volume(_) => None,
        };
        let instance = object.unwrap_or(0);
        (self.geometry_objects.get(instance as usize).copied().unwrap_or(instance), instance)
    }

    /// The light (an index into [`Scene::lights`]) a hit lies on, when it is
    /// an emitter's surface, and the radiance it sends back along `-d`.
    #[inline]
    pub fn emitted(&self, hit: &Hit, d: Vec3) -> Option<(usize, Vec3)> {
        let li = self.light_of(hit)?;
        let l = match self.lights.get(li)? {
            Light::Mesh(m) => m.radiance,
            // A sphere shines outwards only.
            Light::Sphere(s) if d.dot(hit.ng) < 0.0 => s.radiance,
            _ => return None,
        };
        Some((li, l))
    }

    /// The light (an index into [`Scene::lights`]) whose object a hit lies
    /// on: an object light's, or an emitting shader's ([`Light::Shaded`]).
    #[inline]
    pub fn light_of(&self, hit: &Hit) -> Option<usize> {
        if self.emitters == 0 {
            return None;
        }
        let li = self.prims.get(self.prim_of(hit)? as usize)?.light;
        (li != NO_LIGHT).then_some(li as usize)
    }

    /// The top-level primitive a hit is on (none for planes and
    /// hypertextures).
    #[inline]
    pub fn prim_of(&self, hit: &Hit) -> Option<u32> {
        match hit.geom {
            HitGeom::Triangle { prim, .. } | HitGeom::Sphere { prim } | HitGeom::Ellipsoid { prim } => {
                Some(prim)
            }
            HitGeom::Plane(_) | HitGeom::Volume(_) => None,
        }
    }

    /// Total triangles over all meshes (instances not counted again).
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// The closest hit along `ray` at shutter `time` in [0, 1), beyond the
    /// intersection epsilon. With `cull_back_faces`, triangles seen from the
    /// back of their winding are skipped (the course culls them for camera
    /// rays; shadow and secondary rays see both sides).
    pub fn intersect(&self, ray: &Ray, time: f32, cull_back_faces: bool) -> Option<Hit> {
        let cull = if cull_back_faces { 1.0 } else { 0.0 };
        #[cfg(target_arch = "x86_64")]
        if self.simd {
            // SAFETY: `simd` says the CPU has AVX2 and FMA.
            return unsafe { self.intersect_avx2(ray, time, cull) };
        }
        self.intersect_plain(ray, time, cull)
    }

    /// [`Scene::intersect`] without AVX2, kept out of line so that its
    /// traversal stacks do not enlarge the caller's frame.
    #[inline(never)]
    fn intersect_plain(&self, ray: &Ray, time: f32, cull: f32) -> Option<Hit> {
        self.intersect_with::<false>(ray, time, cull)
    }

    /// [`Scene::intersect`] compiled for AVX2 and FMA, the hit's normals
    /// worked out in the same function as the traversal: returned from a
    /// function of their own, the traversal's results would go through
    /// memory and be read back in wider loads than they were written with,
    /// waiting for the stores. The same operations, so the same bits.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn intersect_avx2(&self, ray: &Ray, time: f32, cull: f32) -> Option<Hit> {
        self.intersect_with::<true>(ray, time, cull)
    }

    #[inline(always)]
    fn intersect_with<const AVX: bool>(&self, ray: &Ray, time: f32, cull: f32) -> Option<Hit> {
        let (best_t, best) = self.closest_with::<AVX>(ray, time, cull);
        let (pi, ng, ns, geom) = match best? {
            Closest::Plane(i) => {
                let (pl, material, textures, _) = self.planes[i];
                return Some(Hit {
                    t: best_t,
                    p: ray.at(best_t),
                    ng: pl.normal,
                    ns: pl.normal,
                    material,
                    textures,
                    geom: HitGeom::Plane(i as u32),
                });
            }
            Closest::Triangle(pi, h) => {
                let p = &self.prims[pi];
                let Geom::Mesh(m) = p.geom else { return None };
                let mesh = &self.meshes[m as usize];
                let geom = HitGeom::Triangle { prim: pi as u32, hit: h };
                // A flat-shaded mesh in world space: its normal, normalized
                // once at build time, is what the steps below would give
                // (`ns` equals `ng`, so the flip never applies).
                if let (None, Some(n)) = (&p.xf, mesh.unit_normal(h.prim)) {
                    let (material, textures) = (p.material, p.textures);
                    return Some(Hit {
                        t: best_t,
                        p: ray.at(best_t),
                        ng: n,
                        ns: n,
                        material,
                        textures,
                        geom,
                    });
                }
                let (ng, ns) = mesh.normals_at(&h);
                (pi, ng, ns, geom)
            }
            Closest::Sphere(pi) => {
                let p = &self.prims[pi];
                let Geom::Sphere(s) = p.geom else { return None };
                let n = s.normal(p.to_local(ray, time).at(best_t));
                (pi, n, n, HitGeom::Sphere { prim: pi as u32 })
            }
            Closest::Ellipsoid(pi) => {
                let p = &self.prims[pi];
                let Geom::Ellipsoid(e) = p.geom else { return None };
                let n = self.ellipsoids[e as usize].normal(p.to_local(ray, time).at(best_t));
                (pi, n, n, HitGeom::Ellipsoid { prim: pi as u32 })
            }
        };
        let p = &self.prims[pi];
        let (ng, ns) = match &p.xf {
            Some(xf) => (xf.normal_to_world(ng), xf.normal_to_world(ns)),
            None => (ng, ns),
        };
        // Flat triangles and spheres have one normal: normalized once.
        let flat = ng == ns;
        let ng = ng.normalize();
        let mut ns = if flat { ng } else { ns.normalize() };
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        Some(Hit { t: best_t, p: ray.at(best_t), ng, ns, material: p.material, textures: p.textures, geom })
    }

    /// The texture frame at a hit of `ray` (at shutter `time`): texture
    /// coordinates, object-space position, derivatives and shading normal.
    /// `footprint` is the pixel's width there.
    pub fn tex_frame(&self, hit: &Hit, ray: &Ray, time: f32, footprint: f32) -> TexFrame {
        let (uv, p_object, dpdu, dpdv, n, prim) = match hit.geom {
            HitGeom::Plane(i) => {
                let (pl, _, _, _) = &self.planes[i as usize];
                let (s, t) = luster_core::math::orthonormal_basis(pl.normal);
                let d = hit.p - pl.point;
                (Vec2::new(d.dot(s), d.dot(t)), hit.p, s, t, pl.normal, None)
            }
            HitGeom::Triangle { prim, hit: h } => {
                let p = &self.prims[prim as usize];
                let Geom::Mesh(m) = p.geom else { return flat_frame(hit, footprint) };
                let mesh = &self.meshes[m as usize];
                let f = mesh.uv_frame(&h);
                let (ng, ns) = mesh.normals_at(&h);
                let ns = if ns.dot(ng) < 0.0 { -ns } else { ns };
                (f.uv, f.p, f.dpdu, f.dpdv, ns.normalize(), Some(p))
            }
            HitGeom::Sphere { prim } => {
                let p = &self.prims[prim as usize];
                let Geom::Sphere(s) = p.geom else { return flat_frame(hit, footprint) };
                let local = p.to_local(ray, time).at(hit.t);
                let (uv, dpdu, dpdv) = s.uv_frame(local);
                (uv, local, dpdu, dpdv, s.normal(local), Some(p))
            }
            HitGeom::Ellipsoid { prim } => {
                let p = &self.prims[prim as usize];
                let Geom::Ellipsoid(e) = p.geom else { return flat_frame(hit, footprint) };
                let e = &self.ellipsoids[e as usize];
                let local = p.to_local(ray, time).at(hit.t);
                let (uv, dpdu, dpdv) = e.uv_frame(local);
                (uv, local, dpdu, dpdv, e.normal(local), Some(p))
            }
            HitGeom::Volume(i) => {
                let Some(v) = self.volumes.surfaces.get(i as usize) else {
                    return flat_frame(hit, footprint);
                };
                return v.bound.tex_frame(hit.p, hit.ns, time, footprint);
            }
        };
        let to_world = prim.and_then(|p| p.xf.as_deref().copied());
        // Noise lives in object space on meshes, in world space on spheres
        // and ellipsoids (see `TexFrame::p_rest`).
        let rest_in_object = matches!(hit.geom, HitGeom::Triangle { .. });
        let p_rest = match &to_world {
            Some(xf) if !rest_in_object => xf.point(p_object),
            _ => p_object,
        };
        TexFrame {
            uv,
            p_object,
            p_world: hit.p,
            time,
            p_rest,
            rest_in_object,
            dpdu,
            dpdv,
            n,
            to_world,
            footprint,
            ctx: Default::default(),
        }
    }
}

/// A frame for a hit whose primitive cannot be found (never, by construction).
fn flat_frame(hit: &Hit, footprint: f32) -> TexFrame {
    let (dpdu, dpdv) = luster_core::math::orthonormal_basis(hit.ns);
    TexFrame {
        uv: Vec2::ZERO,
        p_object: hit.p,
        p_world: hit.p,
        time: 0.0,
        p_rest: hit.p,
        rest_in_object: false,
        dpdu,
        dpdv,
        n: hit.ns,
        to_world: None,
        footprint,
        ctx: Default::default(),
    }
}
