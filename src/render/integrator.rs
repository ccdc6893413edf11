//! The course's recursive (Whitted) integrator.
//!
//! At a hit: ambient + for each point light that a shadow ray reaches, diffuse
//! `kd (n·l) I/d²` plus Blinn-Phong `ks (n·h)^p I/d²`; then, while the depth
//! allows, a mirror adds `km L(reflected)`, a conductor `km F_c L(reflected)`,
//! and a dielectric `F L(reflected) + (1 - F) L(refracted)` with the exact
//! Fresnel term. A ray that travelled inside a dielectric is attenuated by
//! Beer's law, `exp(-c d)`, over the distance `d` it covered there. Secondary
//! rays start `ShadowRayEpsilon` off the surface, on the side they leave from.
//!
//! Direct lighting uses the normal as the geometry gives it (the triangle's
//! winding, a sphere's outside), not one flipped towards the viewer: the
//! course lights a surface from the side its normal points to, wherever the
//! eye is. hw1 `windmill_smooth`, whose sails are seen from behind, shows it:
//! 40 dB against the reference this way, 28 dB with normals flipped to face the
//! viewer.
//!
//! Distribution effects (hw3): each camera sample carries a shutter time and
//! a [`PixelSampler`] that supplies one decorrelated 2D dimension per area
//! light sample and per glossy bounce. An area light contributes, per sample,
//! `L · A · |n_l · ω| / d²` as the irradiance of one point drawn uniformly on
//! its square (hw3 spec eq. 1), shadowed by one ray to that point. Roughness
//! `r` makes a mirror or conductor glossy and a dielectric frosted: the
//! reflected (and refracted) direction `R` is moved to
//! `R + r (ξ₁ - ½) u + r (ξ₂ - ½) v` in a frame `(u, v)` around it (the course's
//! model), and renormalized. hw3 `metal_glass_plates` shows the course applies
//! it to glass as well.
//!
//! Two guards keep a hostile scene (glass inside glass, a large
//! `MaxRecursionDepth`) from spawning `2^depth` rays per pixel: a branch whose
//! accumulated weight falls below [`MIN_WEIGHT`] is not traced (its
//! contribution cannot reach a visible fraction of an 8-bit level for any
//! plausible light), and a camera ray may spawn at most [`SECONDARY_BUDGET`]
//! reflection and refraction rays. Neither changes any course image.

/// Smallest path weight (largest RGB component of the product of the mirror,
/// Fresnel and transmission factors so far) that is still traced.
pub const MIN_WEIGHT: f32 = 1e-5;

/// Most reflection and refraction rays one camera ray may spawn.
pub const SECONDARY_BUDGET: u32 = 4096;

/// Per-camera-ray state: the counts for the summary, what is left of the
/// budget, the shutter time and the sampler for the rest of the path.
#[derive(Clone, Debug)]
pub struct PathState {
    /// Rays traced so far.
    pub stats: RayStats,
    budget: u32,
    /// Shutter time of this camera sample, in [0, 1).
    pub time: f32,
    /// Random dimensions for light and glossy samples.
    pub sampler: PixelSampler,
    /// Where the camera sample lies on the image, 0–1 across and down (a
    /// background texture is looked up there).
    pub screen: Vec2,
    /// Angle of the ray cone around each ray: the pixel's angular size.
    pub spread: f32,
    /// Distance the path has covered before the current ray.
    travelled: f32,
    /// The pixel being rendered and the camera's frame (for shaders).
    pub pixel: [u32; 2],
    /// See `pixel`.
    pub view: crate::texture::View,
    /// The first shader failure on this path, naming the object. The path
    /// then contributes black and the render loop stops (see `render_tiles`).
    pub error: Option<Box<ShaderError>>,
}

impl PathState {
    /// A fresh state for a new camera ray, keeping the running counts.
    pub fn new(stats: RayStats, time: f32, sampler: PixelSampler) -> Self {
        PathState {
            stats,
            budget: SECONDARY_BUDGET,
            time,
            sampler,
            screen: Vec2::ZERO,
            spread: 0.0,
            travelled: 0.0,
            pixel: [0; 2],
            view: crate::texture::View::default(),
            error: None,
        }
    }

    /// The state for a camera sample at image position `screen` with ray
    /// cone spread `spread`.
    pub fn for_pixel(self, screen: Vec2, spread: f32) -> Self {
        PathState { screen, spread, ..self }
    }

    /// Records a shader failure (the first one counts); the path then
    /// contributes black and the render stops.
    pub fn fail(&mut self, e: ShaderError) {
        if self.error.is_none() {
            self.error = Some(Box::new(e));
        }
    }

    /// Whether a secondary ray of `weight` may be traced; counts it if so.
    fn spawn(&mut self, weight: f32) -> bool {
        if weight < MIN_WEIGHT || self.budget == 0 {
            return false;
        }
        self.budget -= 1;
        self.stats.secondary += 1;
        true
    }
}

use crate::bsdf::fresnel;
use crate::bsdf::Frame;
use crate::material::Material;
use crate::material::Specular;
use crate::math::{orthonormal_basis, Ray, Vec2, Vec3};
use crate::render::dielectric;
use crate::render::sampler::PixelSampler;
use crate::render::scene::{Hit, Scene};
use crate::render::volumes;
use crate::shader::ShaderError;
use crate::texture::{Applied, ShadeCtx};

/// Ray counts, for the Mrays/s summary.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayStats {
    /// Camera rays.
    pub primary: u64,
    /// Reflection and refraction rays.
    pub secondary: u64,
    /// Shadow rays.
    pub shadow: u64,
}

impl RayStats {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.secondary + self.shadow
    }

    /// Adds another count.
    pub fn add(&mut self, o: &RayStats) {
        self.primary += o.primary;
        self.secondary += o.secondary;
        self.shadow += o.shadow;
    }
}

/// Radiance arriving along `ray`, which is at recursion `depth` (0 for camera rays).
/// `weight` is the path's accumulated weight so far (1 for camera rays).
pub fn radiance(scene: &Scene, ray: &Ray, depth: u32, weight: f32, st: &mut PathState) -> Vec3 {
    let hit = volumes::trace(scene, ray, depth == 0, st);
    let (t, color) = match hit {
        Some(hit) => {
            let before = st.travelled;
            st.travelled += hit.t;
            let c = shade(scene, ray, &hit, depth, weight, st);
            st.travelled = before;
            (hit.t, c)
        }
        None => (f32::INFINITY, background(scene, ray, st)),
    };
    volumes::through_media(scene, ray, t, color, st)
}

/// What a ray that escapes sees: the environment map if there is one, else
/// the background texture at the camera sample, else the background colour.
fn background(scene: &Scene, ray: &Ray, st: &PathState) -> Vec3 {
    match &scene.environment {
        Some(env) => env.eval(ray.d.normalize()),
        None => scene.textures.background(st.screen).unwrap_or(scene.background),
    }
}

fn shade(scene: &Scene, ray: &Ray, hit: &Hit, depth: u32, weight: f32, st: &mut PathState) -> Vec3 {
    let mut material = scene.materials[hit.material as usize];
    let mut ns = hit.ns;
    if !hit.textures.is_empty() {
        // The ray cone's width here, widened by the slant of the surface.
        let cos = ray.d.dot(hit.ns).abs().max(0.05);
        let footprint = st.spread * st.travelled / cos;
        let mut frame = scene.tex_frame(hit, ray, st.time, footprint);
        let (object, instance) = scene.object_ids(hit);
        let (incident, ng, pixel, view) = (ray.d.normalize(), hit.ng, st.pixel, st.view);
        frame.ctx = ShadeCtx { incident, ng, object, instance, depth, pixel, view, ..ShadeCtx::default() };
        frame.ctx.set_footprint(st.spread * st.travelled);
        match scene.textures.apply(hit.textures, &frame, &mut material, &mut ns) {
            Ok(Applied::Lit) => {}
            Ok(Applied::Unlit(c)) => return c,
            Err(e) => {
                if st.error.is_none() {
                    st.error = Some(Box::new((*e).with_object(scene.object_label(hit))));
                }
                return Vec3::ZERO;
            }
        }
        if ns.dot(hit.ng) < 0.0 {
            ns = -ns;
        }
    }
    let m = &material;
    let entering = ray.d.dot(hit.ng) < 0.0;
    // Normals facing the side the ray came from.
    let (n, ng) = if entering { (ns, hit.ng) } else { (-ns, -hit.ng) };
    let eps = scene.shadow_epsilon;
    let inside_dielectric = !entering && matches!(m.kind, Specular::Dielectric { .. });
    let mut color = Vec3::ZERO;

    if !inside_dielectric {
        color += direct(scene, m, hit, ns, ray, st);
    }

    if depth < scene.max_depth {
        let cos_i = -ray.d.dot(n);
        let roughness = m.roughness;
        let reflected =
            |st: &mut PathState| Ray::new(hit.p + ng * eps, glossy(reflect(ray.d, n), roughness, st));
        match m.kind {
            Specular::None => {}
            Specular::Mirror => {
                let w = weight * m.mirror.max_element();
                if st.spawn(w) {
                    let r = reflected(st);
                    color += m.mirror * radiance(scene, &r, depth + 1, w, st);
                }
            }
            Specular::Conductor { n: eta, k } => {
                let f = fresnel::conductor(cos_i, eta, k);
                let w = weight * f * m.mirror.max_element();
                if st.spawn(w) {
                    let r = reflected(st);
                    color += m.mirror * f * radiance(scene, &r, depth + 1, w, st);
                }
            }
            Specular::Dielectric { ior, .. } => {
                let (n1, n2) = if entering { (1.0, ior) } else { (ior, 1.0) };
                let (f, cos_t) = fresnel::dielectric(cos_i, n1, n2);
                // Both rays at one sample per pixel, one of them otherwise.
                let (wr, wt) = dielectric::branch_weights(f, cos_t.is_some(), &mut st.sampler);
                if wr > 0.0 && st.spawn(weight * wr) {
                    let r = reflected(st);
                    color += wr * radiance(scene, &r, depth + 1, weight * wr, st);
                }
                if let (Some(cos_t), true) = (cos_t, wt > 0.0) {
                    let eta = n1 / n2;
                    let dir = glossy((ray.d * eta + n * (eta * cos_i - cos_t)).normalize(), roughness, st);
                    let w = weight * wt;
                    if st.spawn(w) {
                        color += wt * radiance(scene, &Ray::new(hit.p - ng * eps, dir), depth + 1, w, st);
                    }
                }
            }
        }
    }

    if let (true, Specular::Dielectric { absorption, .. }) = (inside_dielectric, m.kind) {
        // The ray reached this exit point through the medium: Beer's law over
        // the distance covered (directions are unit length, so t is distance).
        color *= (-absorption * hit.t).exp();
    }
    color
}

/// Ambient plus the light that reaches the hit directly from every light,
/// with shadow rays (see [`crate::light`] for what each light contributes).
fn direct(scene: &Scene, m: &Material, hit: &Hit, ns: Vec3, ray: &Ray, st: &mut PathState) -> Vec3 {
    let mut color = m.ambient * scene.ambient;
    // The winding normals, not ones flipped towards the eye: see the module doc.
    let (n, ng) = (ns, hit.ng);
    let eps = scene.shadow_epsilon;
    let origin = hit.p + ng * eps;
    for light in &scene.lights {
        let Some(ls) = light.sample(origin, hit.p, Some(n), &mut st.sampler) else { continue };
        let cos = n.dot(ls.wi);
        if cos <= 0.0 || ls.e == Vec3::ZERO {
            continue;
        }
        // A point source's shadow ray reaches a little past it, so a light
        // lying exactly on a surface (hw2 mirror_room puts one in the ceiling
        // plane) is blocked by it consistently, as in the references, not by
        // per-pixel rounding. An area light's stops short of its own plane:
        // it is an imaginary square, not geometry, and a surface it lies on
        // must not shadow it.
        let t_max = if ls.point_source { ls.dist + eps } else { ls.dist - eps };
        let tr = volumes::shadow(scene, &Ray::new(origin, ls.wi), t_max, st);
        if tr == Vec3::ZERO {
            continue;
        }
        color += reflectance(m, n, ls.wi, ray.d, cos) * (tr * ls.e);
    }
    color
}

/// What the surface sends towards a viewer along `-d` per unit irradiance
/// arriving from `l` (`cos = n · l`, positive): `f(l, -d) cos` for a material
/// with a BRDF, the course's Blinn-Phong otherwise.
#[inline]
fn reflectance(m: &Material, n: Vec3, l: Vec3, d: Vec3, cos: f32) -> Vec3 {
    match &m.brdf {
        None => blinn_phong(m, n, l, d, cos),
        Some(brdf) => {
            let frame = Frame::new(n);
            brdf.eval(m.diffuse, m.specular, frame.to_local(l), frame.to_local(-d)) * cos
        }
    }
}

/// Diffuse plus Blinn-Phong specular reflectance towards `l` for a viewer
/// along `-d`, with `cos = n · l` already known to be positive.
#[inline]
fn blinn_phong(m: &Material, n: Vec3, l: Vec3, d: Vec3, cos: f32) -> Vec3 {
    let h = (l - d).normalize();
    m.diffuse * cos + m.specular * n.dot(h).max(0.0).powf(m.phong)
}

/// `dir` moved by the course's glossy model: `dir + r (ξ₁ - ½) u + r (ξ₂ - ½) v`
/// in a frame `(u, v)` around it, renormalized; `dir` itself when `r` is 0.
#[inline]
fn glossy(dir: Vec3, roughness: f32, st: &mut PathState) -> Vec3 {
    if roughness <= 0.0 {
        return dir;
    }
    let (u, v) = orthonormal_basis(dir);
    let (a, b) = st.sampler.next_2d();
    (dir + (u * (a - 0.5) + v * (b - 0.5)) * roughness).normalize()
}

/// Mirror reflection of `d` about the unit normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}
