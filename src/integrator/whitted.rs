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
//! it to glass as well. The frame is the course's, not just any orthonormal
//! pair: the offsets fill a square, whose corners reach √2 farther than its
//! edges, so at the roughness of hw3 `cornellbox_brushed_metal` (5) the
//! square's turn about `R` shows as where the sphere is lit; see
//! [`glossy_frame`]. Perturbed rays that point into the surface are traced
//! as they are, as the course does (dropping them darkens that sphere by up
//! to 16 levels).
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
//! match the course's image (region means 107.5 and 84.7 against 107.5 and
//! 84.0 at 32 spp; 76 and 75 without).
//!
//! Two guards keep a hostile scene (glass inside glass, a large
//! `MaxRecursionDepth`) from spawning `2^depth` rays per pixel: a branch whose
//! accumulated weight falls below [`MIN_WEIGHT`](super::MIN_WEIGHT) is not traced (its
//! contribution cannot reach a visible fraction of an 8-bit level for any
//! plausible light), and a camera ray may spawn at most [`SECONDARY_BUDGET`](super::SECONDARY_BUDGET)
//! reflection and refraction rays. Neither changes any course image.

use super::{light_reaching_inline, surface_at, PathState, Surface};
use crate::bsdf::fresnel;
use crate::bsdf::Frame;
use crate::material::Material;
use crate::material::Specular;
use crate::math::{Ray, Vec3};
use crate::render::dielectric;
use crate::render::scene::{Hit, Scene};
use crate::render::volumes;

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
    let hit = volumes::trace(scene, ray, medium == Medium::Outside, st);
    // Borrowed in place: moving the hit out of the slot `trace` filled
    // copied it in wide loads that waited on its narrow stores.
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
                let (wr, wt) = dielectric::branch_weights(f, cos_t.is_some(), &mut st.sampler);
                if wr > 0.0 && st.spawn(weight * wr) {
                    let r = reflected(st);
                    color += wr * traced(scene, &r, depth + 1, weight * wr, stays, st);
                }
                if let (Some(cos_t), true) = (cos_t, wt > 0.0) {
                    let eta = n1 / n2;
                    let dir = glossy((ray.d * eta + n * (eta * cos_i - cos_t)).normalize(), roughness, st);
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
    // A surface that reflects no direct light (clear glass) skips each
    // light's draw, so that later draws and the image stay as they were,
    // and traces no shadow ray for it.
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

/// `color` plus what `light` adds at the hit, `reflectance · tr · E` (the
/// same `color` when it does not reach it). Never inlined: `direct` is
/// inlined into the recursive `traced`, and whether `reflectance` (with every
/// BRDF's `eval` and their `powf`s) went in too was up to how thin LTO split
/// the crate: when it did, `traced` doubled in code and stack frame and whole
/// renders of `benches/scenes/film.xml` took 10–17% more CPU
/// (docs/performance.md, session 12). One call per light, its sum in
/// registers: the light's sample and then the reflectance, each called
/// from `traced` on its own, came back through memory, read at once.
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
        Some((ls, cos, tr)) => {
            // Blinn-Phong here, not through `reflectance`: its call (with the
            // BRDFs' `eval`s) stayed out of line, and the lobe is all the
            // course's materials need.
            let r = match &m.brdf {
                None => blinn_phong(m, n, ls.wi, d, cos),
                Some(_) => reflectance(m, n, ls.wi, d, cos),
            };
            color + r * (tr * ls.e)
        }
        None => color,
    }
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
    // Most course materials have no specular part: skip its `powf` (the
    // term is a finite number times zero, so the sum is the same).
    if m.specular == Vec3::ZERO {
        return m.diffuse * cos;
    }
    let h = (l - d).normalize();
    m.diffuse * cos + m.specular * phong_power(n.dot(h).max(0.0), m.phong)
}

/// `x^e` for the Blinn-Phong lobe. The course's exponents are whole numbers
/// (1 to a few thousand): for those, repeated squaring in `f64`, a handful
/// of multiplications against a `powf` call (3.6% of the POV-Ray scene's
/// profile). Its relative error (at most 32 roundings of `2⁻⁵³`, under
/// `2⁻⁴⁷`) is far under an `f32` step, so the result is the correctly
/// rounded power unless the exact power lies that close to a rounding
/// boundary; libm's `powf` (within 0.82 of a step) differs from it only
/// near such boundaries, by one step. Other exponents go to `powf`.
#[inline]
pub(crate) fn phong_power(x: f32, e: f32) -> f32 {
    let k = e as u32;
    if k as f32 != e || k > 1 << 16 {
        return x.powf(e);
    }
    // Factors of at most 1 (as `n·h` is) keep every partial product at or
    // above the result, so nothing underflows that the result would not.
    let (mut acc, mut base, mut k) = (1.0f64, f64::from(x), k);
    while k > 0 {
        if k & 1 == 1 {
            acc *= base;
        }
        k >>= 1;
        if k > 0 {
            base *= base;
        }
    }
    acc as f32
}

/// `dir` moved by the course's glossy model: `dir + r (ξ₁ - ½) u + r (ξ₂ - ½) v`
/// in the frame `(u, v)` of [`glossy_frame`], renormalized; `dir` itself when `r` is 0.
#[inline]
pub(crate) fn glossy(dir: Vec3, roughness: f32, st: &mut PathState) -> Vec3 {
    if roughness <= 0.0 {
        return dir;
    }
    let (u, v) = glossy_frame(dir);
    let (a, b) = st.sampler.next_2d();
    (dir + (u * (a - 0.5) + v * (b - 0.5)) * roughness).normalize()
}

/// The course's frame around a unit direction `r`: `r'` is `r` with its
/// component of smallest magnitude set to 1 (the first such when two tie),
/// `u = normalize(r × r')` and `v = r × u`. Only the frame's turn about `r`
/// matters (the offsets are symmetric), and this rule fixes it: another
/// orthonormal pair (Duff et al.'s, say) turns the square of offsets and left
/// the upper right of hw3 `cornellbox_brushed_metal`'s copper sphere 4–5
/// levels brighter than the course's image over 50×50 pixels.
#[inline]
pub(crate) fn glossy_frame(r: Vec3) -> (Vec3, Vec3) {
    let a = r.abs();
    let mut rp = r;
    if a.x <= a.y && a.x <= a.z {
        rp.x = 1.0;
    } else if a.y <= a.z {
        rp.y = 1.0;
    } else {
        rp.z = 1.0;
    }
    let u = r.cross(rp).normalize();
    (u, r.cross(u))
}

/// Mirror reflection of `d` about the unit normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_exponents_are_powers_within_a_rounding_step_of_powf() {
        let mut differ = 0;
        let mut total = 0;
        for e in [1.0f32, 2.0, 3.0, 10.0, 50.0, 100.0, 150.0, 500.0, 1000.0] {
            for i in 0..=20_000 {
                let x = i as f32 / 20_000.0;
                let (ours, libm) = (phong_power(x, e), x.powf(e));
                total += 1;
                if ours != libm {
                    differ += 1;
                    // One step apart (the bit patterns of positive floats are ordered).
                    assert_eq!(ours.to_bits().abs_diff(libm.to_bits()), 1, "{x}^{e}: {ours} vs {libm}");
                }
            }
        }
        assert!(differ * 100 < total, "{differ} of {total} differ");
        assert_eq!((phong_power(0.0, 0.0), phong_power(0.3, 0.0), phong_power(0.0, 50.0)), (1.0, 1.0, 0.0));
        assert_eq!(phong_power(1.0, 500.0), 1.0);
        // Other exponents are libm's.
        for e in [0.5f32, 2.5, 1e9, -3.0] {
            assert_eq!(phong_power(0.7, e), 0.7f32.powf(e), "{e}");
        }
    }

    #[test]
    fn the_glossy_frame_is_orthonormal_and_turned_as_the_courses() {
        for r in [
            Vec3::X,
            -Vec3::Y,
            Vec3::Z,
            Vec3::new(0.81, 0.46, -0.34).normalize(),
            Vec3::new(-0.2, 0.9, 0.1).normalize(),
            Vec3::new(1e-4, -1.0, 1e-4).normalize(),
        ] {
            let (u, v) = glossy_frame(r);
            assert!((u.length() - 1.0).abs() < 1e-5 && (v.length() - 1.0).abs() < 1e-5, "{r}");
            assert!(u.dot(r).abs() < 1e-5 && v.dot(r).abs() < 1e-5 && u.dot(v).abs() < 1e-5, "{r}");
        }
        // Along z the course's square is axis-aligned; off the axes its
        // `u` lies in the plane of `r` and the axis of `r`'s smallest
        // component (here z), unlike Duff et al.'s frame.
        let (u, _) = glossy_frame(Vec3::Z);
        assert!(u.x.abs() < 1e-6 && u.z.abs() < 1e-6, "{u}");
        let r = Vec3::new(0.81, 0.46, -0.34).normalize();
        let (u, _) = glossy_frame(r);
        let (d, _) = crate::math::orthonormal_basis(r);
        let rp = Vec3::new(r.x, r.y, 1.0);
        assert!(u.dot(rp).abs() < 1e-5, "u {u} not perpendicular to r' {rp}");
        assert!(d.dot(u).abs() < 0.99, "this test cannot tell the two frames apart");
    }
}
