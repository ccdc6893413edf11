//! Building the render scene from a [`Description`]: meshes (inline, PLY, OBJ arrays) and
//! their BVHs in parallel, images and shader scripts, then the top-level BVH.

use super::{Geom, Prim, Scene};
use crate::accel::Bvh;
use crate::geometry::mesh::{vertex_normals, welded_vertex_normals};
use crate::geometry::{Ellipsoid, Mesh, Plane, Sphere};
use crate::light::tree::LightTree;
use crate::light::{AreaLight, Environment, Light, LightMesh, LightSphere, PointLight, SpotLight};
use crate::material::Material;
use crate::render::camera::Camera;
use crate::texture::{shader, Image, TexList, Textures};
use crate::volume::{Baking, Volumes};
use luster_core::math::{Aabb, Vec2, Vec3};
use luster_scene::description::{Description, ImageEncoding, MeshSource, Shape};
use luster_scene::ply::read_ply;
use luster_scene::{SceneError, Warning};
use luster_shading::shader::{ShaderImages, ShaderOptions};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

/// Settings of building a scene beyond what its file says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Time limit of one shader call.
    pub shader_timeout: Duration,
}

impl Default for BuildOptions {
    fn default() -> BuildOptions {
        BuildOptions { shader_timeout: luster_shading::shader::DEFAULT_TIMEOUT }
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
        Scene::build_baking(desc, opts, &Baking::default())
    }

    /// Like [`Scene::build_with`], baking volume grids as `baking` says
    /// (from a cache kept across builds, cancellably: `luster watch`).
    pub fn build_baking(
        desc: &Description,
        opts: &BuildOptions,
        baking: &Baking,
    ) -> Result<Scene, SceneError> {
        let (meshes, mesh_of_object, warnings) = build_meshes(desc)?;
        let mut textures = build_textures(desc, opts)?;
        let environment = build_environment(desc, &textures)?;
        let mut lights = build_lights(desc);
        let first_emitter = lights.len();
        let light_of_object = add_emitters(desc, &meshes, &mesh_of_object, &mut lights)?;
        let emitters = lights.len() - first_emitter;
        lights.extend(environment.as_ref().map(|e| Light::Environment(Arc::clone(e))));
        let images = shader_images(desc, &textures.images);
        let volumes = Volumes::build_baking(desc, &mut textures, Some(images), opts.shader_timeout, baking)?;
        let (prims, planes, ellipsoids) =
            build_prims(desc, &meshes, &mesh_of_object, &light_of_object, &mut textures)?;
        let bounds: Vec<Aabb> = prims.iter().map(|p| prim_bounds(p, &meshes, &ellipsoids)).collect();
        // Finite input can still overflow f32 once transformed (3e38 under a
        // scaling); such an object could never be hit, so say so instead.
        if let Some((p, _)) = prims.iter().zip(&bounds).find(|(_, b)| !b.is_finite()) {
            return Err(SceneError::at(
                &desc.file,
                &desc.objects[p.object as usize].loc,
                "the object reaches beyond the range of 32-bit floating-point numbers (after its transformations)",
            ));
        }
        let tlas = Bvh::build_objects(&bounds);
        // Put primitives in the BVH's leaf order so a leaf is a contiguous range.
        let mut slots: Vec<Option<Prim>> = prims.into_iter().map(Some).collect();
        let prims = tlas.prim_order().iter().filter_map(|&i| slots[i as usize].take()).collect();

        let mut scene = Scene {
            meshes,
            ellipsoids,
            prims,
            tlas,
            planes,
            object_labels: desc.objects.iter().map(|o| object_label(&o.loc.path)).collect(),
            // Shaders' s.object_id: an instance shows its mesh's index.
            geometry_objects: desc
                .objects
                .iter()
                .enumerate()
                .map(|(i, o)| match o.shape {
                    Shape::Instance { mesh } => mesh as u32,
                    _ => i as u32,
                })
                .collect(),
            textures,
            volumes,
            materials: desc.materials.iter().map(Material::from_desc).collect(),
            lights,
            emitters,
            light_tree: LightTree::default(),
            environment_light: None,
            environment,
            ambient: desc.ambient_light,
            background: desc.background,
            shadow_epsilon: desc.shadow_ray_epsilon.unwrap_or(0.0),
            fixed_offset: desc.shadow_ray_epsilon.is_some(),
            offset_floor: 0.0,
            intersection_epsilon: desc.intersection_test_epsilon,
            max_depth: desc.max_recursion_depth,
            cameras: desc
                .cameras
                .iter()
                .map(|c| {
                    let mut camera = Camera::from_desc(c);
                    camera.display = desc.display;
                    camera
                })
                .collect(),
            warnings,
            emitting_bounds: None,
            emitters_alone: false,
            simd: simd_available(),
            axes_by_table: false,
        };
        scene.axes_by_table = scene.meshes.iter().all(|m| m.accel().bvh().node_count() <= 1);
        scene.add_shaded_lights();
        scene.emitting_bounds = scene.emitting_boxes(|p| prim_bounds(p, &scene.meshes, &scene.ellipsoids));
        scene.emitters_alone = scene.only_emitters_shine();
        let bounds = scene.tlas.bounds();
        let radius = 0.5 * (bounds.max - bounds.min).length();
        scene.offset_floor = if radius.is_finite() { radius / 16.0 } else { 0.0 };
        scene.light_tree = LightTree::build(&scene.lights, radius);
        scene.environment_light = scene.lights.iter().position(|l| matches!(l, Light::Environment(_)));
        Ok(scene)
    }
}

/// Every Mesh and Triangle object's mesh, built in parallel (instances share
/// their base's), the index of each object's mesh, and the build's warnings.
#[allow(clippy::type_complexity)]
fn build_meshes(desc: &Description) -> Result<(Vec<Mesh>, HashMap<usize, u32>, Vec<Warning>), SceneError> {
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
    Ok((meshes, mesh_of_object, warnings))
}

/// The object lights (`LightSphere`, `LightMesh`) appended to `lights`, and
/// the light index of each emitting object.
fn add_emitters(
    desc: &Description,
    meshes: &[Mesh],
    mesh_of_object: &HashMap<usize, u32>,
    lights: &mut Vec<Light>,
) -> Result<HashMap<usize, u32>, SceneError> {
    let mut light_of_object = HashMap::new();
    for e in &desc.emitters {
        let o = &desc.objects[e.object];
        let light = match &o.shape {
            Shape::Sphere { center, radius } => {
                Light::Sphere(LightSphere::new(*center, *radius, &o.transform, e.radiance).moving(o.motion))
            }
            Shape::Mesh { .. } => {
                let m = &meshes[mesh_of_object[&e.object] as usize];
                match LightMesh::new(m.corners(), &o.transform, e.radiance) {
                    Some(mut l) => {
                        l.motion = o.motion;
                        Light::Mesh(Arc::new(l))
                    }
                    None => continue,
                }
            }
            _ => return Err(SceneError::at(&desc.file, &e.loc, "internal error: not an emitter shape")),
        };
        light_of_object.insert(e.object, lights.len() as u32);
        lights.push(light);
    }
    Ok(light_of_object)
}

/// The primitives of the top-level BVH (meshes, spheres, ellipsoids, each
/// with its transform, material, maps and light), the planes (outside the
/// BVH: they are unbounded) and the ellipsoids' shapes.
#[allow(clippy::type_complexity)]
fn build_prims(
    desc: &Description,
    meshes: &[Mesh],
    mesh_of_object: &HashMap<usize, u32>,
    light_of_object: &HashMap<usize, u32>,
    textures: &mut Textures,
) -> Result<(Vec<Prim>, Vec<(Plane, u32, TexList, u32)>, Vec<Ellipsoid>), SceneError> {
    let mut prims = Vec::new();
    let mut planes = Vec::new();
    let mut ellipsoids = Vec::new();
    for (i, o) in desc.objects.iter().enumerate() {
        let xf = (!o.transform.is_identity()).then(|| Box::new(o.transform));
        let material = o.material as u32;
        let tex = textures.add_list(&o.textures);
        let geom = match &o.shape {
            Shape::Mesh { .. } | Shape::Triangle { .. } => Geom::Mesh(mesh_of_object[&i]),
            Shape::Instance { mesh } => match mesh_of_object.get(mesh) {
                Some(&m) => Geom::Mesh(m),
                None => return Err(SceneError::at(&desc.file, &o.loc, "the instance's base is not a mesh")),
            },
            Shape::Sphere { center, radius } => Geom::Sphere(Sphere { center: *center, radius: *radius }),
            Shape::Ellipsoid { center, radii, rotation } => {
                ellipsoids.push(Ellipsoid::new(*center, *radii, *rotation));
                Geom::Ellipsoid(ellipsoids.len() as u32 - 1)
            }
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
        let light = light_of_object.get(&i).copied().unwrap_or(super::NO_LIGHT);
        let world = xf.is_none() && o.motion == Vec3::ZERO;
        let (motion, object) = (o.motion, i as u32);
        prims.push(Prim { geom, material, motion, xf, textures: tex, object, light, world });
    }
    Ok((prims, planes, ellipsoids))
}

/// The environment light's map, checked and with its sampling distribution.
fn build_environment(
    desc: &Description,
    textures: &Textures,
) -> Result<Option<Arc<Environment>>, SceneError> {
    let Some(e) = &desc.environment_light else { return Ok(None) };
    let at = |msg: String| SceneError::at(&desc.file, &e.loc, msg);
    let image = textures.images.get(e.image).ok_or_else(|| at("internal error: no such image".into()))?;
    let path = desc.images.get(e.image).map(|i| i.path.display().to_string()).unwrap_or_default();
    let env = Environment::new(image, e.mapping, e.sampling)
        .and_then(|env| env.placed(e.rotation, e.strength))
        .map_err(|m| at(format!("{path}: {m}")))?;
    Ok(Some(Arc::new(env)))
}

/// The lights in the order the integrator visits them: point lights,
/// directional and spot lights (which draw no samples), area lights; the
/// caller adds the emitting objects, then the environment, so that in scenes
/// without the hw5 and hw7 lights the others draw the same dimensions.
fn build_lights(desc: &Description) -> Vec<Light> {
    let mut lights: Vec<Light> = desc
        .point_lights
        .iter()
        .map(|l| Light::Point(PointLight { position: l.position, intensity: l.intensity }))
        .collect();
    lights.extend(
        desc.directional_lights
            .iter()
            .map(|d| Light::Directional { direction: d.direction, radiance: d.radiance }),
    );
    lights.extend(desc.spot_lights.iter().map(|s| Light::Spot(SpotLight::from_desc(s))));
    lights.extend(desc.area_lights.iter().map(|a| Light::Area(AreaLight::from_desc(a))));
    lights
}

/// The last segment of an element path: `Scene/Objects/Sphere[id=2]` gives
/// `Sphere[id=2]`.
fn object_label(path: &str) -> String {
    path.rsplit('/').next().unwrap_or(path).to_string()
}

/// Decodes the scene's images (in parallel), compiles its shader scripts and
/// builds its texture maps. Images a trilinear map reads get mipmaps. Under a
/// display transform's linear workflow, 8-bit images are sRGB-decoded unless
/// they carry `degamma` or only normal and bump maps read them (those hold
/// data, not colour).
fn build_textures(desc: &Description, opts: &BuildOptions) -> Result<Textures, SceneError> {
    use luster_scene::description::{DecalMode, Interpolation, TextureSource};
    let data_only: Vec<bool> = (0..desc.images.len())
        .map(|i| {
            let mut readers = desc
                .texture_maps
                .iter()
                .filter(|m| matches!(m.source, TextureSource::Image { image, .. } if image == i))
                .peekable();
            readers.peek().is_some()
                && readers.all(|m| matches!(m.decal, DecalMode::ReplaceNormal | DecalMode::BumpNormal))
        })
        .collect();
    let trilinear: Vec<bool> = (0..desc.images.len())
        .map(|i| {
            desc.texture_maps.iter().any(|m| {
                matches!(m.source, TextureSource::Image { image, interpolation: Interpolation::Trilinear, .. } if image == i)
            })
        })
        .collect();
    // A shader may sample any image with texture(), so with shaders every
    // listed image is decoded.
    let any_shader = desc.texture_maps.iter().any(|m| matches!(m.source, TextureSource::Shader { .. }))
        || desc.volumes.iter().any(|v| v.script.is_some());
    let used: Vec<bool> = (0..desc.images.len())
        .map(|i| {
            any_shader
                || desc.environment_light.as_ref().is_some_and(|e| e.image == i)
                || desc
                    .texture_maps
                    .iter()
                    .any(|m| matches!(m.source, TextureSource::Image { image, .. } if image == i))
        })
        .collect();
    let images: Arc<[Image]> = desc
        .images
        .par_iter()
        .enumerate()
        .map(|(i, d)| {
            if !used[i] {
                // A listed image no map reads is not decoded (nor required to exist).
                return Image::from_rgb8(1, 1, vec![[0, 0, 0]])
                    .ok_or_else(|| SceneError::at(&desc.file, &d.loc, "internal error"));
            }
            let mut img = load_image(d).map_err(|e| SceneError::at(&desc.file, &d.loc, e))?;
            match d.encoding {
                _ if d.degamma => img.degamma(),
                ImageEncoding::Scene => {
                    if desc.display.is_linear_workflow() && !img.is_hdr() && !data_only[i] {
                        img.srgb_decode();
                    }
                }
                ImageEncoding::Srgb if !img.is_hdr() => img.srgb_decode(),
                ImageEncoding::Srgb | ImageEncoding::Linear | ImageEncoding::Alpha => {}
                ImageEncoding::GlNormal { scale } => img.gl_normal(scale),
            }
            if trilinear[i] {
                img.build_mipmaps();
            }
            Ok(img)
        })
        .collect::<Result<_, _>>()?;
    let options = ShaderOptions {
        timeout: opts.shader_timeout,
        images: Some(shader_images(desc, &images)),
        module_dirs: desc.module_search_path(),
        attributes: Arc::new(shader::attributes::for_objects(desc)?),
    };
    let shaders = shader::compile_with(&desc.texture_maps, options)
        .map_err(|e| SceneError::at(&desc.file, &desc.texture_maps[e.map].loc, e.message))?;
    Ok(Textures::new(images, &desc.texture_maps, desc.background_texture, shaders))
}

/// Decodes image `d` from its file or its bytes, in the channels its encoding reads.
fn load_image(d: &luster_scene::description::ImageDesc) -> Result<Image, String> {
    use crate::texture::image::Channels;
    let channels = if d.encoding == ImageEncoding::Alpha { Channels::Alpha } else { Channels::Rgb };
    match &d.bytes {
        Some(bytes) => Image::decode_bytes(bytes, &d.path.display().to_string(), channels),
        None => Image::load_channels(&d.path, channels),
    }
}

/// The scene's images as shaders sample them with `texture()`.
fn shader_images(desc: &Description, images: &Arc<[Image]>) -> ShaderImages {
    ShaderImages {
        names: shader::image_names(&desc.images),
        sampler: Arc::new(shader::SceneImages(Arc::clone(images))),
    }
}

/// World bounds over the whole shutter interval: a translation sweeps the box
/// from its place at time 0 to its place at time 1.
fn prim_bounds(p: &Prim, meshes: &[Mesh], ellipsoids: &[Ellipsoid]) -> Aabb {
    let b = match p.geom {
        Geom::Mesh(m) => meshes[m as usize].bounds(),
        Geom::Sphere(s) => s.bounds(),
        Geom::Ellipsoid(e) => ellipsoids[e as usize].bounds(),
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
        Shape::Mesh { source: MeshSource::Arrays(a), smooth } => {
            let normals = smooth.then(|| {
                a.normals.clone().unwrap_or_else(|| welded_vertex_normals(&a.positions, &a.triangles))
            });
            let mesh = Mesh::new(a.positions.clone(), a.triangles.clone(), normals);
            Ok((mesh.with_uvs(a.uvs.clone()), None))
        }
        _ => Err(SceneError::at(&desc.file, &o.loc, "internal error: not a mesh")),
    }
}

/// Whether this CPU runs the traversal's AVX2 and FMA code ([`Scene::simd`]).
fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    let simd = crate::accel::bvh::fused_available();
    #[cfg(not(target_arch = "x86_64"))]
    let simd = false;
    simd
}
