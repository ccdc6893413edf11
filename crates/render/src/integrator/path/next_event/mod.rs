//! Next-event estimation of the path tracer: at each hit, one sample of
//! every light (or, under MIS in a scene with many lights, of one chosen by
//! power), shadowed and weighed, and the weight that an emitter a bounce hits
//! gets against those samples. Reads the scene's lights and the camera's
//! `<RendererParams>` (through [`PathParams`]); the BRDF terms come from the
//! vertex's [`Bsdf`].

use super::{every_light, pick_chance, Came, LightAhead, PathParams};
use crate::bsdf::diffuse_pdf;
use crate::bsdf::{Bsdf, Flags};
use crate::integrator::media;
use crate::integrator::{aimed, is_black, light_reaching_from, shadow_ray, surface_at, PathState, Surface};
use crate::light::{Light, ShadedLight, ShadedShape};
use crate::render::scene::{Hit, Scene};
use luster_core::math::{Ray, Vec3, Vec3A};

/// One sample of every light, shadowed; with MIS each weighed against the
/// chance that the BSDF would have drawn its direction. Only picks the
/// version: both take its arguments as they are, so each is a jump (made
/// in `li` instead, the choice would cost every path there, even in a
/// variant that samples no light).
///
/// The sum comes back as a `Vec3A`: returned through memory either way, a
/// `Vec3` would be written as `x` alone and `y, z` together, and `li` reads
/// `x, y` together at once, a load the store buffer cannot forward.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(super) fn next_event(
    scene: &Scene,
    hit: &Hit,
    at: &Bsdf,
    origin: Vec3,
    depth: u32,
    p: PathParams,
    ahead: Option<LightAhead>,
    st: &mut PathState,
) -> Vec3A {
    let vols = &scene.volumes;
    let m = at.material();
    if at.f.is_some() && vols.surfaces.is_empty() && !vols.has_media() {
        if !p.mis {
            return next_event_diffuse::<false>(scene, hit, at, origin, depth, p, ahead, st);
        }
        // [`Bsdf::eval_pdf`]'s arm for a diffuse-only BRDF under MIS, with
        // every light sampled (scale 1).
        if m.traits.diffuse_only && m.brdf.is_some() && every_light(scene, p) {
            return next_event_diffuse::<true>(scene, hit, at, origin, depth, p, ahead, st);
        }
    }
    next_event_any(scene, hit, at, origin, depth, p, ahead, st)
}

/// [`next_event`] at any vertex.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn next_event_any(
    scene: &Scene,
    hit: &Hit,
    at: &Bsdf,
    origin: Vec3,
    depth: u32,
    p: PathParams,
    ahead: Option<LightAhead>,
    st: &mut PathState,
) -> Vec3A {
    let mut color = Vec3::ZERO;
    let Some((lights, scale)) = lights_to_sample(scene, p, hit.p, Some(at.n), st) else { return Vec3A::ZERO };
    for (i, light) in lights.iter().enumerate() {
        if let Light::Shaded(l) = light {
            color += shaded_sample(scene, l, hit.p, &surface(at, p), origin, depth, scale, p, st);
            continue;
        }
        // A point drawn ahead is taken only where every light is sampled
        // (`lights` is then all of them).
        let reaching = LightAhead::sample(ahead, i, light, hit.p, at.n, st)
            .and_then(|ls| light_reaching_from(scene, light, ls, origin, hit.p, at.n, st));
        let Some((ls, cos, tr)) = reaching else {
            continue;
        };
        let (f, bsdf_pdf) = at.eval_pdf(ls.wi, cos, p.strategy());
        let w =
            if p.mis && hittable(light) { power_heuristic(ls.pdf / scale, bsdf_pdf) * scale } else { scale };
        color += f * (tr * ls.e) * w;
    }
    color.into()
}

/// The lights a vertex at `x` (normal `n`, on a surface) samples and the
/// scale of each one's estimate. MIS takes every light of a scene with few
/// ([`every_light`]), else one per hit, chosen by the light tree for that
/// point (scaled by one over its chance): a shadow ray per hit whatever the
/// number of lights. The course's variant samples them all. `None` where
/// no light is chosen.
#[inline(always)]
pub(super) fn lights_to_sample<'s>(
    scene: &'s Scene,
    p: PathParams,
    x: Vec3,
    n: Option<Vec3>,
    st: &mut PathState,
) -> Option<(&'s [Light], f32)> {
    if p.mis && !every_light(scene, p) {
        let (i, pick) = scene.light_tree.choose(st.sampler.next_1d(), x, n)?;
        if pick <= 0.0 {
            return None;
        }
        Some((&scene.lights[i..=i], 1.0 / pick))
    } else {
        Some((&scene.lights[..], 1.0))
    }
}

/// [`next_event`] at a vertex whose material is a shader's closure: the
/// light samples are drawn from the hit point, and a light behind the
/// surface counts where a lobe transmits, its shadow ray leaving from the
/// far side (`ng` is the geometric normal on the viewer's side, `eps` the
/// offset off the surface).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(super) fn next_event_closure(
    scene: &Scene,
    hit: &Hit,
    at: &Bsdf,
    ng: Vec3,
    eps: f32,
    depth: u32,
    p: PathParams,
    st: &mut PathState,
) -> Vec3 {
    let front = hit.p + ng * eps;
    let transmits = at.flags().contains(Flags::TRANSMISSION);
    let mut color = Vec3::ZERO;
    let Some((lights, scale)) = lights_to_sample(scene, p, hit.p, Some(at.n), st) else { return Vec3::ZERO };
    for light in lights {
        if let Light::Shaded(l) = light {
            color += shaded_sample(scene, l, hit.p, &surface(at, p), front, depth, scale, p, st);
            continue;
        }
        let Some(ls) = light.sample_at(hit.p, at.n, st.time, &mut st.sampler) else {
            continue;
        };
        let side = ng.dot(ls.wi);
        if is_black(ls.e) || side == 0.0 || (side < 0.0 && !transmits) {
            continue;
        }
        let origin = if side > 0.0 { front } else { hit.p - ng * eps };
        let (f, bsdf_pdf) = at.eval_pdf(ls.wi, at.n.dot(ls.wi), p.strategy());
        if is_black(f) {
            continue;
        }
        // The shadow ray leaves from the light's side of the surface.
        let (ray, reach) = shadow_ray(scene, light, origin, hit.p, &ls, st.time);
        let tr = media::shadow(scene, &ray, reach, st);
        if is_black(tr) {
            continue;
        }
        let w =
            if p.mis && hittable(light) { power_heuristic(ls.pdf / scale, bsdf_pdf) * scale } else { scale };
        color += f * (tr * ls.e) * w;
    }
    color
}

/// [`next_event`] at a vertex whose BRDF value is the same for every light
/// direction above it (`at.f`), in a scene without volumes: each light's
/// term is `f cos · E`, times, under MIS (with every light sampled), the
/// power heuristic against the cosine-weighted bounce's density; the
/// shadow ray's transmittance is exactly 1, and so are the other factors
/// [`next_event_any`] multiplies by (dropping them keeps the bits).
/// Apart, so that LLVM cannot hoist the set-up of every case of
/// [`Bsdf::eval_pdf`] (the frame's rows, the whole view direction) out of
/// [`next_event_any`]'s light loop, work this vertex never uses.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn next_event_diffuse<const MIS: bool>(
    scene: &Scene,
    hit: &Hit,
    at: &Bsdf,
    origin: Vec3,
    depth: u32,
    p: PathParams,
    ahead: Option<LightAhead>,
    st: &mut PathState,
) -> Vec3A {
    let f = Vec3::from(at.f.unwrap_or_default());
    let mut color = Vec3::ZERO;
    for (i, light) in scene.lights.iter().enumerate() {
        if let Light::Shaded(l) = light {
            color += shaded_sample(scene, l, hit.p, &surface(at, p), origin, depth, 1.0, p, st);
            continue;
        }
        // [`light_reaching_inline`] without media: the shadow ray passes or
        // not. The first light's point may have been drawn ahead.
        let Some(ls) = LightAhead::sample(ahead, i, light, hit.p, at.n, st) else {
            continue;
        };
        let cos = at.n.dot(ls.wi);
        if cos <= 0.0 || is_black(ls.e) {
            continue;
        }
        let (ray, t_max) = shadow_ray(scene, light, origin, hit.p, &ls, st.time);
        st.stats.shadow += 1;
        if scene.occluded(&ray, t_max, st.time) {
            continue;
        }
        if MIS {
            // [`Bsdf::eval_pdf`]'s density of a diffuse-only BRDF's bounce.
            let w = if hittable(light) { power_heuristic(ls.pdf, diffuse_pdf(at.wo.z, cos)) } else { 1.0 };
            color += f * cos * ls.e * w;
        } else {
            // [`Bsdf::f_cos`]'s `f cos`.
            color += f * cos * ls.e;
        }
    }
    color.into()
}

/// How a vertex scatters light arriving from `wi`: `(f · cos, density of a
/// bounce drawing wi)`, or `None` where no light arrives from there (below
/// a surface).
pub(super) type Scatters<'a> = dyn Fn(Vec3) -> Option<(Vec3, f32)> + 'a;

/// A surface's [`Scatters`]: its BSDF above its normal.
fn surface<'a>(at: &'a Bsdf, p: PathParams) -> impl Fn(Vec3) -> Option<(Vec3, f32)> + 'a {
    move |wi| {
        let cos = at.n.dot(wi);
        (cos > 0.0).then(|| at.eval_pdf(wi, cos, p.strategy()))
    }
}

/// One sample of an object whose shader emits, seen from `x` (a surface
/// point or a point in a medium) that scatters by `f`: a ray towards a
/// point drawn on it, which counts only where its first hit is that point
/// (for a sphere, any point of the object), with the shader's emission
/// found there.
#[allow(clippy::too_many_arguments)]
pub(super) fn shaded_sample(
    scene: &Scene,
    l: &ShadedLight,
    x: Vec3,
    f: &Scatters,
    origin: Vec3,
    depth: u32,
    scale: f32,
    p: PathParams,
    st: &mut PathState,
) -> Vec3 {
    let u = st.sampler.next_2d();
    let Some((wi, dist, pdf)) = l.sample(x, st.time, u) else { return Vec3::ZERO };
    let Some((f, bsdf_pdf)) = f(wi) else { return Vec3::ZERO };
    // Aimed at the sampled point from the offset origin.
    let (r, dist) = aimed(origin, x + wi * dist);
    st.stats.shadow += 1;
    let Some(h) = scene.intersect(&r, st.time, false) else { return Vec3::ZERO };
    let eps = scene.offset(h.p, origin);
    // Another part of the same mesh in front of the sampled point blocks it
    // (that part is a sample of its own); a sphere's rim may come first.
    let mesh = matches!(l.shape, ShadedShape::Mesh(_));
    if scene.prim_of(&h) != Some(l.prim) || (mesh && h.t < dist * (1.0 - 1e-3) - eps) {
        return Vec3::ZERO;
    }
    let vols = &scene.volumes;
    let tr = if vols.surfaces.is_empty() && !vols.has_media() {
        Vec3::ONE
    } else {
        media::shadow(scene, &r, h.t - eps, st)
    };
    if is_black(tr) {
        return Vec3::ZERO;
    }
    let before = st.travelled;
    st.travelled += h.t;
    let s = surface_at(scene, &r, &h, depth + 1, st);
    st.travelled = before;
    let Surface::Lit(e, _) = s else { return Vec3::ZERO };
    if !e.traits.emits {
        return Vec3::ZERO;
    }
    let w = if p.mis { power_heuristic(pdf / scale, bsdf_pdf) * scale } else { scale };
    f * (tr * e.emission) * (w / pdf)
}

/// How much an emitter (light `li`) that a ray hit counts, by how the ray
/// left its last surface: in full after the camera or a specular bounce;
/// after a random bounce by the power heuristic under MIS, not at all under
/// the course's next-event estimation (the light samples counted it).
pub(super) fn hit_weight(
    scene: &Scene,
    li: usize,
    came: Came,
    ray: &Ray,
    hit: &Hit,
    p: PathParams,
    time: f32,
) -> f32 {
    match came {
        Came::Direct => 1.0,
        Came::Bounce { pdf, .. } | Came::Scatter { pdf } if p.mis => {
            // Measured from the point the light samples were drawn at.
            let (from, n) =
                if let Came::Bounce { from, n, .. } = came { (from, Some(n)) } else { (ray.o, None) };
            let pick = pick_chance(scene, p, li, from, n);
            power_heuristic(pdf, pick * light_pdf(&scene.lights[li], from, hit, ray.d, time))
        }
        Came::Bounce { .. } | Came::Scatter { .. } if p.next_event => 0.0,
        Came::Bounce { .. } | Came::Scatter { .. } => 1.0,
    }
}

/// Whether a bounce can hit the light (then MIS weighs its two samples).
#[inline]
pub(super) fn hittable(light: &Light) -> bool {
    matches!(light, Light::Mesh(_) | Light::Sphere(_) | Light::Environment(_) | Light::Shaded(_))
}

/// The light's density for the direction `d` of a ray from `from` at
/// shutter `time` that hit it at `hit`.
fn light_pdf(light: &Light, from: Vec3, hit: &Hit, d: Vec3, time: f32) -> f32 {
    match light {
        Light::Mesh(l) => l.pdf(from, hit.p, hit.ng, time),
        Light::Sphere(l) => l.pdf(from - l.motion * time, d.normalize()),
        Light::Shaded(l) => l.pdf(from, hit.p, hit.ng, d, time),
        _ => 0.0,
    }
}

/// The power heuristic with exponent 2 for a sample of density `a` against
/// the other technique's `b`.
#[inline]
pub(super) fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 <= 0.0 || !a2.is_finite() {
        return 1.0;
    }
    a2 / (a2 + b2)
}

#[cfg(test)]
pub(super) mod tests;
