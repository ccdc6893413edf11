//! The render scene: immutable, `Sync`, built once from a [`Description`].
//!
//! Geometry is two-level. Every mesh (inline, PLY, or a single `Triangle`) is
//! built once in its own object space with its own BVH; objects — meshes,
//! instances of meshes, spheres — are primitives of a top-level BVH, each with
//! an optional object-to-world transform. Rays are moved into object space
//! without renormalizing, so `t` means the same in both spaces. Infinite planes
//! have no box and are tested beside the BVH. Moving objects (`MotionBlur`)
//! sit in the top level with boxes swept over the shutter interval, so one
//! BVH serves every ray time.

use crate::accel::{Bvh, TriHit};
use crate::geometry::mesh::vertex_normals;
use crate::geometry::{Mesh, Plane, Sphere};
use crate::math::{Aabb, Ray, Transform, Vec2, Vec3};
use crate::render::camera::Camera;
use crate::scene::description::{Description, MeshSource, Shape};
use crate::scene::ply::read_ply;
use crate::scene::{SceneError, Warning};
use crate::shading::{AreaLight, Material, PointLight};
use crate::texture::{Image, TexFrame, TexList, Textures};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Duration;

/// What a top-level primitive is.
#[derive(Clone, Copy, Debug)]
enum Geom {
    Mesh(u32),
    Sphere(Sphere),
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
}

impl Prim {
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
    prims: Vec<Prim>,
    tlas: Bvh,
    /// Infinite planes: the plane, its material, its maps and its object index.
    planes: Vec<(Plane, u32, TexList, u32)>,
    /// Every object's name for messages, `Sphere[id=2]`, by description index.
    object_labels: Vec<String>,
    /// Images and texture maps.
    pub textures: Textures,
    /// Materials.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<PointLight>,
    /// Area lights.
    pub area_lights: Vec<AreaLight>,
    /// Ambient light.
    pub ambient: Vec3,
    /// Colour of rays that miss.
    pub background: Vec3,
    /// Offset of secondary ray origins.
    pub shadow_epsilon: f32,
    /// Smallest accepted hit distance.
    pub intersection_epsilon: f32,
    /// Bounces after the camera ray.
    pub max_depth: u32,
    /// Cameras.
    pub cameras: Vec<Camera>,
    /// Notes from building (e.g. degenerate triangles a PLY file had).
    pub warnings: Vec<Warning>,
}

/// Settings of building a scene beyond what its file says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Time limit of one shader call.
    pub shader_timeout: Duration,
}

impl Default for BuildOptions {
    fn default() -> BuildOptions {
        BuildOptions { shader_timeout: crate::shader::DEFAULT_TIMEOUT }
    }
}

impl Scene {
    /// Builds the render scene with the default [`BuildOptions`].
    pub fn build(desc: &Description) -> Result<Scene, SceneError> {
        Scene::build_with(desc, &BuildOptions::default())
    }

    /// Builds the render scene: loads PLY files and builds every BVH, meshes
    /// in parallel, and compiles the shader scripts.
    pub fn build_with(desc: &Description, opts: &BuildOptions) -> Result<Scene, SceneError> {
        // Meshes: one per Mesh or Triangle object; instances share their base's.
        let mesh_objects: Vec<usize> = desc
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| matches!(o.shape, Shape::Mesh { .. } | Shape::Triangle { .. }))
            .map(|(i, _)| i)
            .collect();
        let built: Vec<Result<(Mesh, Option<Warning>), SceneError>> =
            mesh_objects.par_iter().map(|&i| build_mesh(desc, i)).collect();
        let mut meshes = Vec::with_capacity(built.len());
        let mut warnings = Vec::new();
        let mut mesh_of_object = HashMap::new();
        for (&obj, b) in mesh_objects.iter().zip(built) {
            let (m, w) = b?;
            warnings.extend(w);
            mesh_of_object.insert(obj, meshes.len() as u32);
            meshes.push(m);
        }

        let mut textures = build_textures(desc, opts)?;
        let mut prims = Vec::new();
        let mut planes = Vec::new();
        for (i, o) in desc.objects.iter().enumerate() {
            let xf = (!o.transform.is_identity()).then(|| Box::new(o.transform));
            let material = o.material as u32;
            let tex = textures.add_list(&o.textures);
            let geom = match &o.shape {
                Shape::Mesh { .. } | Shape::Triangle { .. } => Geom::Mesh(mesh_of_object[&i]),
                Shape::Instance { mesh } => match mesh_of_object.get(mesh) {
                    Some(&m) => Geom::Mesh(m),
                    None => {
                        return Err(SceneError::at(&desc.file, &o.loc, "the instance's base is not a mesh"))
                    }
                },
                Shape::Sphere { center, radius } => Geom::Sphere(Sphere { center: *center, radius: *radius }),
                Shape::Plane { point, normal } => {
                    let p = Plane {
                        point: o.transform.point(*point),
                        normal: o.transform.normal_to_world(*normal).normalize(),
                    };
                    planes.push((p, material, tex, i as u32));
                    continue;
                }
            };
            if let Geom::Mesh(m) = geom {
                if meshes[m as usize].triangle_count() == 0 {
                    continue;
                }
            }
            prims.push(Prim { geom, material, motion: o.motion, xf, textures: tex, object: i as u32 });
        }
        let bounds: Vec<Aabb> = prims.iter().map(|p| prim_bounds(p, &meshes)).collect();
        let tlas = Bvh::build(&bounds);
        // Put primitives in the BVH's leaf order so a leaf is a contiguous range.
        let mut slots: Vec<Option<Prim>> = prims.into_iter().map(Some).collect();
        let prims = tlas.prim_order().iter().filter_map(|&i| slots[i as usize].take()).collect();

        Ok(Scene {
            meshes,
            prims,
            tlas,
            planes,
            object_labels: desc.objects.iter().map(|o| object_label(&o.loc.path)).collect(),
            textures,
            materials: desc.materials.iter().map(Material::from_desc).collect(),
            lights: desc
                .point_lights
                .iter()
                .map(|l| PointLight { position: l.position, intensity: l.intensity })
                .collect(),
            area_lights: desc.area_lights.iter().map(AreaLight::from_desc).collect(),
            ambient: desc.ambient_light,
            background: desc.background,
            shadow_epsilon: desc.shadow_ray_epsilon,
            intersection_epsilon: desc.intersection_test_epsilon,
            max_depth: desc.max_recursion_depth,
            cameras: desc.cameras.iter().map(Camera::from_desc).collect(),
            warnings,
        })
    }

    /// The object a hit is on, as messages name it: `Sphere[id=2]`.
    pub fn object_label(&self, hit: &Hit) -> &str {
        let object = match hit.geom {
            HitGeom::Plane(i) => self.planes.get(i as usize).map(|p| p.3),
            HitGeom::Triangle { prim, .. } | HitGeom::Sphere { prim } => {
                self.prims.get(prim as usize).map(|p| p.object)
            }
        };
        object.and_then(|o| self.object_labels.get(o as usize)).map_or("an object", String::as_str)
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
        let t_min = self.intersection_epsilon;
        let mut best_t = f32::INFINITY;
        let mut best = None;
        for (i, (pl, _, _, _)) in self.planes.iter().enumerate() {
            if let Some(t) = pl.intersect(ray, t_min, best_t) {
                best_t = t;
                best = Some(Closest::Plane(i));
            }
        }
        self.tlas.closest(ray, best_t, |range, t_max| {
            let mut hit = false;
            for pi in range {
                let p = &self.prims[pi];
                let local = p.to_local(ray, time);
                match p.geom {
                    Geom::Mesh(m) => {
                        let cull = if cull_back_faces { 1.0 } else { 0.0 };
                        if let Some(h) = self.meshes[m as usize].intersect(&local, t_min, *t_max, cull) {
                            *t_max = h.t;
                            best = Some(Closest::Triangle(pi, h));
                            hit = true;
                        }
                    }
                    Geom::Sphere(s) => {
                        if let Some(t) = s.intersect(&local, t_min, *t_max) {
                            *t_max = t;
                            best = Some(Closest::Sphere(pi));
                            hit = true;
                        }
                    }
                }
            }
            if hit {
                best_t = *t_max;
            }
            hit
        });
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
                let (ng, ns) = self.meshes[m as usize].normals_at(&h);
                (pi, ng, ns, HitGeom::Triangle { prim: pi as u32, hit: h })
            }
            Closest::Sphere(pi) => {
                let p = &self.prims[pi];
                let Geom::Sphere(s) = p.geom else { return None };
                let n = s.normal(p.to_local(ray, time).at(best_t));
                (pi, n, n, HitGeom::Sphere { prim: pi as u32 })
            }
        };
        let p = &self.prims[pi];
        let (ng, ns) = match &p.xf {
            Some(xf) => (xf.normal_to_world(ng), xf.normal_to_world(ns)),
            None => (ng, ns),
        };
        let ng = ng.normalize();
        let mut ns = ns.normalize();
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
                let (s, t) = crate::math::orthonormal_basis(pl.normal);
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
        };
        let to_world = prim.and_then(|p| p.xf.as_deref().copied());
        let p_rest = match &to_world {
            Some(xf) => xf.point(p_object),
            None => p_object,
        };
        TexFrame { uv, p_object, p_world: hit.p, time, p_rest, dpdu, dpdv, n, to_world, footprint }
    }

    /// Whether anything lies on `ray` at `time` between the intersection
    /// epsilon and `t_max`.
    pub fn occluded(&self, ray: &Ray, t_max: f32, time: f32) -> bool {
        let t_min = self.intersection_epsilon;
        if self.planes.iter().any(|(pl, _, _, _)| pl.intersect(ray, t_min, t_max).is_some()) {
            return true;
        }
        self.tlas.any(ray, t_max, |range, t_max| {
            range.into_iter().any(|pi| {
                let p = &self.prims[pi];
                let local = p.to_local(ray, time);
                match p.geom {
                    Geom::Mesh(m) => self.meshes[m as usize].occluded(&local, t_min, t_max),
                    Geom::Sphere(s) => s.intersect(&local, t_min, t_max).is_some(),
                }
            })
        })
    }
}

/// A frame for a hit whose primitive cannot be found (never, by construction).
fn flat_frame(hit: &Hit, footprint: f32) -> TexFrame {
    let (dpdu, dpdv) = crate::math::orthonormal_basis(hit.ns);
    TexFrame {
        uv: Vec2::ZERO,
        p_object: hit.p,
        p_world: hit.p,
        time: 0.0,
        p_rest: hit.p,
        dpdu,
        dpdv,
        n: hit.ns,
        to_world: None,
        footprint,
    }
}

/// The last segment of an element path: `Scene/Objects/Sphere[id=2]` gives
/// `Sphere[id=2]`.
fn object_label(path: &str) -> String {
    path.rsplit('/').next().unwrap_or(path).to_string()
}

/// Decodes the scene's images (in parallel), compiles its shader scripts and
/// builds its texture maps. Images a trilinear map reads get mipmaps.
fn build_textures(desc: &Description, opts: &BuildOptions) -> Result<Textures, SceneError> {
    use crate::scene::description::{Interpolation, TextureSource};
    let trilinear: Vec<bool> = (0..desc.images.len())
        .map(|i| {
            desc.texture_maps.iter().any(|m| {
                matches!(m.source, TextureSource::Image { image, interpolation: Interpolation::Trilinear, .. } if image == i)
            })
        })
        .collect();
    let used: Vec<bool> = (0..desc.images.len())
        .map(|i| {
            desc.texture_maps
                .iter()
                .any(|m| matches!(m.source, TextureSource::Image { image, .. } if image == i))
        })
        .collect();
    let images: Vec<Image> = desc
        .images
        .par_iter()
        .enumerate()
        .map(|(i, d)| {
            if !used[i] {
                // A listed image no map reads is not decoded (nor required to exist).
                return Image::from_rgb8(1, 1, vec![[0, 0, 0]])
                    .ok_or_else(|| SceneError::at(&desc.file, &d.loc, "internal error"));
            }
            let mut img = Image::load(&d.path).map_err(|e| SceneError::at(&desc.file, &d.loc, e))?;
            if trilinear[i] {
                img.build_mipmaps();
            }
            Ok(img)
        })
        .collect::<Result<_, _>>()?;
    let shaders = crate::texture::shader::compile(&desc.texture_maps, opts.shader_timeout)
        .map_err(|e| SceneError::at(&desc.file, &desc.texture_maps[e.map].loc, e.message))?;
    Ok(Textures::new(images, &desc.texture_maps, desc.background_texture, shaders))
}

/// World bounds over the whole shutter interval: a translation sweeps the box
/// from its place at time 0 to its place at time 1.
fn prim_bounds(p: &Prim, meshes: &[Mesh]) -> Aabb {
    let b = match p.geom {
        Geom::Mesh(m) => meshes[m as usize].bounds(),
        Geom::Sphere(s) => s.bounds(),
    };
    let b = match &p.xf {
        Some(xf) => xf.aabb(&b),
        None => b,
    };
    b.union(Aabb::new(b.min + p.motion, b.max + p.motion))
}

/// Builds the mesh of object `i` (a Mesh or a Triangle), in object space.
fn build_mesh(desc: &Description, i: usize) -> Result<(Mesh, Option<Warning>), SceneError> {
    let o = &desc.objects[i];
    match &o.shape {
        Shape::Triangle { vertices, uvs } => {
            Ok((Mesh::new(vertices.to_vec(), vec![[0, 1, 2]], None).with_uvs(uvs.map(|u| u.to_vec())), None))
        }
        Shape::Mesh { source: MeshSource::Inline { triangles: tris, tex_shift }, smooth } => {
            // Keep only the vertices this mesh uses, renumbered.
            let mut remap: HashMap<u32, u32> = HashMap::new();
            let mut positions = Vec::new();
            let local: Vec<[u32; 3]> = tris
                .iter()
                .map(|t| {
                    t.map(|g| {
                        *remap.entry(g).or_insert_with(|| {
                            positions.push(desc.vertices[g as usize]);
                            positions.len() as u32 - 1
                        })
                    })
                })
                .collect();
            let normals = smooth.then(|| vertex_normals(&positions, &local));
            // Texture coordinate of vertex g is number g + tex_shift; all or none.
            let mut globals = vec![0u32; positions.len()];
            for (&g, &l) in &remap {
                globals[l as usize] = g;
            }
            let uvs: Option<Vec<Vec2>> = globals
                .iter()
                .map(|&g| {
                    let k = g as i64 + tex_shift;
                    usize::try_from(k).ok().and_then(|k| desc.tex_coords.get(k).copied())
                })
                .collect();
            Ok((Mesh::new(positions, local, normals).with_uvs(uvs), None))
        }
        Shape::Mesh { source: MeshSource::Ply(path), smooth } => {
            let ply = read_ply(path).map_err(|e| SceneError::at(&desc.file, &o.loc, e.to_string()))?;
            let warning = (ply.skipped_degenerate > 0).then(|| Warning {
                loc: o.loc.clone(),
                message: format!(
                    "{}: {} degenerate triangle(s) skipped",
                    path.display(),
                    ply.skipped_degenerate
                ),
            });
            let normals = smooth.then(|| vertex_normals(&ply.positions, &ply.triangles));
            Ok((Mesh::new(ply.positions, ply.triangles, normals).with_uvs(ply.uvs), warning))
        }
        _ => Err(SceneError::at(&desc.file, &o.loc, "internal error: not a mesh")),
    }
}
