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
//! with normals flipped to face the viewer it no longer matches the reference.
//!
//! Distribution effects (hw3): each camera sample carries a shutter time and
//! a [`PixelSampler`](crate::render::sampler::PixelSampler) that supplies one decorrelated 2D dimension per area
//! light sample and per glossy bounce. An area light contributes, per sample,
//! `L · A · |n_l · ω| / d²` as the irradiance of one point drawn uniformly on
//! its square (hw3 spec eq. 1), shadowed by one ray to that point. Roughness
//! `r` makes a mirror or conductor glossy and a dielectric frosted: the
//! reflected (and refracted) direction `R` is moved to
//! `R + r (ξ₁ - ½) u + r (ξ₂ - ½) v` in a frame `(u, v)` around it (the course's
//! model), and renormalized. hw3 `metal_glass_plates` shows the course applies
//! it to glass as well. The frame is the course's, not just any orthonormal
//! pair: the offsets fill a square, whose corners reach √2 farther than its
//! edges, so at the roughness of hw3 `cornellbox_brushed_metal` (5) the
//! square's turn about `R` shows as where the sphere is lit; see
//! [`crate::bsdf::specular::glossy_frame`]. Perturbed rays that point into the surface are traced
//! as they are, as the course does (dropping them darkens that sphere).
//!
//! Back faces: a ray travelling outside every dielectric (a camera ray, a
//! mirror's reflection of one, a ray reflected off a dielectric's outside
//! or refracted out of one) does not see the back of a triangle; a ray
//! inside a dielectric sees both sides, so it can leave. Whether a ray is
//! inside follows from the side of each dielectric face it crossed (the
//! sign of `d · n` at that hit), as the course decides entering and leaving.
//! This is what lets the course's rays pass the wine glass of hw3
//! `wine_glass`, whose liquid is a second shell a few thousandths inside the
//! glass's inner wall (of the same mesh and material) with non-manifold
//! seams where they meet: a ray that skipped a gap thinner than
//! `ShadowRayEpsilon` believes itself outside while inside the liquid, and
//! without culling it is caught by the back faces there until its depth
//! runs out. With culling the liquid's top ring and the bottom of the bowl
//! match the course's image; without, they come out dark.
//!
//! Two guards keep a hostile scene (glass inside glass, a large
//! `MaxRecursionDepth`) from spawning `2^depth` rays per pixel: a branch whose
//! accumulated weight falls below [`MIN_WEIGHT`](super::MIN_WEIGHT) is not traced (its
//! contribution cannot reach a visible fraction of an 8-bit level for any
//! plausible light), and a camera ray may spawn at most [`SECONDARY_BUDGET`](super::SECONDARY_BUDGET)
//! reflection and refraction rays. Neither changes any course image.

use super::{light_reaching_inline, surface_at, PathState, Surface};
use crate::bsdf::specular::{branch_weights, glossy, reflect, refract};
use crate::bsdf::{fresnel, Bsdf, Lobes, Specular};
use crate::integrator::media;
use crate::material::Material;
use crate::render::scene::{Hit, Scene};
use luster_core::math::{Ray, Vec3};

/// Radiance arriving along `ray`, which is at recursion `depth` (0 for camera rays).
/// `weight` is the path's accumulated weight so far (1 for camera rays).
pub fn radiance(scene: &Scene, ray: &Ray, depth: u32, weight: f32, st: &mut PathState) -> Vec3 {
    traced(scene, ray, depth, weight, Medium::Outside, st)
}

/// Where a ray travels: outside every dielectric, or inside one (refracted
/// into it, or reflected inside it). A ray outside does not see the back of
/// a triangle (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Medium {
    Outside,
    Inside,
}

fn traced(scene: &Scene, ray: &Ray, depth: u32, weight: f32, medium: Medium, st: &mut PathState) -> Vec3 {
    let hit = media::trace(scene, ray, medium == Medium::Outside, st);
    // Borrowed in place: moving the hit out of the slot `trace` filled
    // would copy it in wide loads that wait on its narrow stores.
    let (t, color) = match &hit {
        Some(hit) => {
            let before = st.travelled;
            st.travelled += hit.t;
            let c = shade(scene, ray, hit, depth, weight, medium, st);
            st.travelled = before;
            (hit.t, c)
        }
        None => (f32::INFINITY, background(scene, ray, st)),
    };
    media::through_media(scene, ray, t, color, st)
}

/// What a ray that escapes sees: the environment map if there is one, else
/// the background texture at the camera sample, else the background colour.
fn background(scene: &Scene, ray: &Ray, st: &PathState) -> Vec3 {
    match &scene.environment {
        Some(env) => env.eval(ray.d.normalize()),
        None => scene.textures.background(st.screen).unwrap_or(scene.background),
    }
}

fn shade(
    scene: &Scene,
    ray: &Ray,
    hit: &Hit,
    depth: u32,
    weight: f32,
    medium: Medium,
    st: &mut PathState,
) -> Vec3 {
    // Matched in place, not moved out: a move copies the whole `Cow`, room
    // for an owned material, even when it borrows.
    let surface = surface_at(scene, ray, hit, depth, st);
    let (m, ns): (&Material, Vec3) = match &surface {
        Surface::Lit(m, ns) => (m, *ns),
        Surface::Unlit(c) => return *c,
        Surface::Failed => return Vec3::ZERO,
    };
    let entering = ray.d.dot(hit.ng) < 0.0;
    // Normals facing the side the ray came from.
    let (n, ng) = if entering { (ns, hit.ng) } else { (-ns, -hit.ng) };
    let eps = scene.offset(hit.p, ray.o);
    let inside_dielectric = !entering && matches!(m.kind, Specular::Dielectric { .. });
    // An emitter's surface shows its radiance (hw7 object lights).
    let mut color = scene.emitted(hit, ray.d).map_or(Vec3::ZERO, |(_, l)| l);
    // A shader's emission shows as it is (it lights nothing here).
    if m.emission != Vec3::ZERO {
        color += m.emission;
    }

    if m.closure {
        let lobes = *st.lobes;
        color += closure_shade(scene, ray, hit, entering, depth, weight, medium, &lobes, st);
    } else if !inside_dielectric {
        color += direct(scene, m, hit, ns, ray, st);
    }

    if depth < scene.max_depth {
        let cos_i = -ray.d.dot(n);
        let roughness = m.roughness;
        let reflected = |st: &mut PathState| {
            Ray::new(hit.p + ng * eps, glossy(reflect(ray.d, n), roughness, &mut st.sampler))
        };
        match m.kind {
            Specular::None => {}
            Specular::Mirror => {
                let w = weight * m.mirror.max_element();
                if st.spawn(w) {
                    let r = reflected(st);
                    color += m.mirror * traced(scene, &r, depth + 1, w, medium, st);
                }
            }
            Specular::Conductor { n: eta, k } => {
                let f = fresnel::conductor(cos_i, eta, k);
                let w = weight * f * m.mirror.max_element();
                if st.spawn(w) {
                    let r = reflected(st);
                    color += m.mirror * f * traced(scene, &r, depth + 1, w, medium, st);
                }
            }
            Specular::Dielectric { ior, .. } => {
                let (n1, n2) = if entering { (1.0, ior) } else { (ior, 1.0) };
                // Where the reflected ray stays and where the refracted one
                // goes, by the side of the face the ray arrived at.
                let (stays, crosses) = if entering {
                    (Medium::Outside, Medium::Inside)
                } else {
                    (Medium::Inside, Medium::Outside)
                };
                let (f, cos_t) = fresnel::dielectric(cos_i, n1, n2);
                // Both rays at one sample per pixel, one of them otherwise.
                let (wr, wt) = branch_weights(f, cos_t.is_some(), &mut st.sampler);
                if wr > 0.0 && st.spawn(weight * wr) {
                    let r = reflected(st);
                    color += wr * traced(scene, &r, depth + 1, weight * wr, stays, st);
                }
                if let (Some(cos_t), true) = (cos_t, wt > 0.0) {
                    let eta = n1 / n2;
                    let dir = glossy(refract(ray.d, n, eta, cos_i, cos_t), roughness, &mut st.sampler);
                    let w = weight * wt;
                    if st.spawn(w) {
                        let r = Ray::new(hit.p - ng * eps, dir);
                        color += wt * traced(scene, &r, depth + 1, w, crosses, st);
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

/// [`shade`] where a shader's closure is the material, approximated as the
/// recursive tracer can (`docs/closures.md`, "The recursive ray tracer"):
/// the light every lobe reflects from each light directly, a
/// mirror ray for the smooth reflecting lobes and a refracted ray for the
/// smooth transmitting ones (each weighted by its Fresnel share), and the
/// straight-through ray of a cut-out. Rough lobes reflect only the lights:
/// there is no indirect light here, as for the course's diffuse surfaces.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn closure_shade(
    scene: &Scene,
    ray: &Ray,
    hit: &Hit,
    entering: bool,
    depth: u32,
    weight: f32,
    medium: Medium,
    lobes: &Lobes,
    st: &mut PathState,
) -> Vec3 {
    let ng = if entering { hit.ng } else { -hit.ng };
    let eps = scene.offset(hit.p, ray.o);
    let n = lobes.frame.normal();
    let front = hit.p + ng * eps;
    let mut color = Vec3::ZERO;
    for light in &scene.lights {
        if lobes.is_empty() {
            light.skip_sample(&mut st.sampler);
            continue;
        }
        if let Some((ls, _, tr)) = light_reaching_inline(scene, light, front, hit.p, n, st) {
            color += lobes.eval_rough(lobes.frame.to_local(ls.wi)) * (tr * ls.e);
        }
    }
    if depth < scene.max_depth {
        let split = lobes.mirror_split();
        let w = weight * split.reflect.max_element();
        if w > 0.0 && st.spawn(w) {
            let r = Ray::new(front, reflect(ray.d, n));
            color += split.reflect * traced(scene, &r, depth + 1, w, medium, st);
        }
        let w = weight * split.refract.max_element();
        if w > 0.0 && st.spawn(w) {
            let cos_i = -ray.d.dot(n);
            let dir = if split.thin {
                Some(ray.d)
            } else {
                let (_, cos_t) = fresnel::dielectric(cos_i, 1.0, split.eta);
                cos_t.map(|cos_t| refract(ray.d, n, 1.0 / split.eta, cos_i, cos_t))
            };
            if let Some(dir) = dir {
                let crosses = match (split.thin, medium) {
                    (true, m) => m,
                    (false, Medium::Outside) => Medium::Inside,
                    (false, Medium::Inside) => Medium::Outside,
                };
                let r = Ray::new(hit.p - ng * eps, dir);
                color += split.refract * traced(scene, &r, depth + 1, w, crosses, st);
            }
        }
    }
    let w = weight * lobes.transparency.max_element();
    if w > 0.0 && st.spawn(w) {
        let r = Ray::new(hit.p - ng * eps, ray.d);
        color += lobes.transparency * traced(scene, &r, depth, w, medium, st);
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
    let eps = scene.offset(hit.p, ray.o);
    let origin = hit.p + ng * eps;
    // A surface that reflects no direct light (clear glass) moves past each
    // light's draw, so that later draws and the image are those of the full
    // computation, and traces no shadow ray for it.
    let reflects = m.brdf.is_some() || m.diffuse != Vec3::ZERO || m.specular != Vec3::ZERO;
    for light in &scene.lights {
        if !reflects {
            light.skip_sample(&mut st.sampler);
            continue;
        }
        color = light_term(scene, light, m, origin, hit.p, n, ray.d, st, color);
    }
    color
}

/// `color` plus what `light` adds at the hit, `f cos · tr · E` (the same
/// `color` when it does not reach it). Never inlined: `direct` is inlined
/// into the recursive `traced`, and the BRDFs' evaluations inlined there too
/// would double its code and stack frame. One call per light keeps its sum in
/// registers.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn light_term(
    scene: &Scene,
    light: &crate::light::Light,
    m: &Material,
    origin: Vec3,
    p: Vec3,
    n: Vec3,
    d: Vec3,
    st: &mut PathState,
    color: Vec3,
) -> Vec3 {
    match light_reaching_inline(scene, light, origin, p, n, st) {
        // The BSDF only where the light arrives: its frame is built then.
        Some((ls, cos, tr)) => color + Bsdf::new(m, n, d).f_cos(ls.wi, cos) * (tr * ls.e),
        None => color,
    }
}
