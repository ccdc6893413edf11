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
//! accumulated weight falls below [`MIN_WEIGHT`](super::MIN_WEIGHT) is not traced (its
//! contribution cannot reach a visible fraction of an 8-bit level for any
//! plausible light), and a camera ray may spawn at most [`SECONDARY_BUDGET`](super::SECONDARY_BUDGET)
//! reflection and refraction rays. Neither changes any course image.

use super::{light_reaching, surface_at, PathState, Surface};
use crate::bsdf::fresnel;
use crate::bsdf::Frame;
use crate::material::Material;
use crate::material::Specular;
use crate::math::{orthonormal_basis, Ray, Vec3};
use crate::render::dielectric;
use crate::render::scene::{Hit, Scene};
use crate::render::volumes;

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
    let (material, ns) = match surface_at(scene, ray, hit, depth, st) {
        Surface::Lit(m, ns) => (m, ns),
        Surface::Unlit(c) => return c,
        Surface::Failed => return Vec3::ZERO,
    };
    let m = &material;
    let entering = ray.d.dot(hit.ng) < 0.0;
    // Normals facing the side the ray came from.
    let (n, ng) = if entering { (ns, hit.ng) } else { (-ns, -hit.ng) };
    let eps = scene.shadow_epsilon;
    let inside_dielectric = !entering && matches!(m.kind, Specular::Dielectric { .. });
    // An emitter's surface shows its radiance (hw7 object lights).
    let mut color = scene.emitted(hit, ray.d).map_or(Vec3::ZERO, |(_, l)| l);
    // A shader's emission shows as it is (it lights nothing here).
    if m.emission != Vec3::ZERO {
        color += m.emission;
    }

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
pub(crate) fn direct(
    scene: &Scene,
    m: &Material,
    hit: &Hit,
    ns: Vec3,
    ray: &Ray,
    st: &mut PathState,
) -> Vec3 {
    let mut color = m.ambient * scene.ambient;
    // The winding normals, not ones flipped towards the eye: see the module doc.
    let (n, ng) = (ns, hit.ng);
    let eps = scene.shadow_epsilon;
    let origin = hit.p + ng * eps;
    for light in &scene.lights {
        if let Some((ls, cos, tr)) = light_reaching(scene, light, origin, hit.p, n, st) {
            color += reflectance(m, n, ls.wi, ray.d, cos) * (tr * ls.e);
        }
    }
    color
}

/// What the surface sends towards a viewer along `-d` per unit irradiance
/// arriving from `l` (`cos = n · l`, positive): `f(l, -d) cos` for a material
/// with a BRDF, the course's Blinn-Phong otherwise.
#[inline]
pub(crate) fn reflectance(m: &Material, n: Vec3, l: Vec3, d: Vec3, cos: f32) -> Vec3 {
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
pub(crate) fn glossy(dir: Vec3, roughness: f32, st: &mut PathState) -> Vec3 {
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
