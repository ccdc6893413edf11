//! Monte Carlo path tracing (hw7): every surface sends one more ray in a
//! random direction, so light arrives after any number of bounces.
//!
//! At a hit the estimate is
//!
//! `L = Le + Σ_lights f · cos · L_l / p_l  +  f · cos · L(ω) / p(ω)`
//!
//! with one light sample per light (next-event estimation) and one bounce
//! `ω`. The course's `<RendererParams>` words choose the variant:
//!
//! | word | effect |
//! |---|---|
//! | (none) | bounces uniform over the hemisphere, `p = 1/2π`; light only where a bounce hits an emitter |
//! | `ImportanceSampling` | cosine-weighted bounces, `p = cos/π` |
//! | `NextEventEstimation` | every light sampled at every hit; an emitter a bounce then hits adds nothing (it was counted already) |
//! | `RussianRoulette` | no depth limit: a path goes on with probability `q = min(1, max(throughput))` and its estimate is divided by `q` |
//! | `MIS` (luster) | bounces drawn from the BSDF; every light sampled per hit in a scene with at most four (`AllLights`: always), else one, chosen by power ([`crate::light::pick`]; `OneLight`: always), its estimate divided by the chance of choosing it; light and bounce samples both count, weighed by the power heuristic `p_a² / (p_a² + p_b²)` with the light's density times the chance of choosing it; the environment light is sampled and hit alike |
//!
//! Without `RussianRoulette` a path ends after `MaxRecursionDepth` bounces,
//! as the course's reflections do. Mirrors, conductors and dielectrics are
//! followed as in the recursive ray tracer (a dielectric splits into its
//! reflected and refracted rays, Beer's law inside); light seen through such
//! a perfectly specular bounce always counts in full, since no light sample
//! can reach through it. Point, spot and directional lights can only be
//! sampled (nothing hits them), so only next-event estimation or MIS sees
//! them, as in the course's images; the course's square area lights are
//! likewise sampled only. The ambient term is left out: paths bring the
//! light that ambient light stood in for.

use std::mem::MaybeUninit;

use super::whitted::{glossy, reflect, reflectance};
use super::{is_black, light_reaching_inline, shadow_reach, surface_at, PathState, Surface};
use crate::bsdf::fresnel;
use crate::bsdf::sampling::{power_cosine, power_cosine_pdf};
use crate::bsdf::{diffuse_pdf, Brdf, Frame};
use crate::light::{Light, ShadedLight};
use crate::material::{Material, Specular};
use crate::math::{Ray, Vec3};
use crate::render::scene::{Hit, Scene};
use crate::render::volumes;
use crate::scene::description::LightSamples;

/// Bounces after which even Russian roulette stops a path (the throughput of
/// a path that long is far below anything visible).
pub const MAX_BOUNCES: u32 = 64;

/// The path tracer's switches (the course's `<RendererParams>` words).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathParams {
    /// Sample every light at every hit.
    pub next_event: bool,
    /// Cosine-weighted bounces instead of uniform ones.
    pub importance: bool,
    /// End paths by their throughput instead of the depth.
    pub russian_roulette: bool,
    /// Multiple importance sampling of light and BSDF samples.
    pub mis: bool,
    /// Under MIS, how many lights a hit samples.
    pub lights: LightSamples,
}

/// Under MIS, a scene with at most this many lights has every one sampled
/// at every hit ([`LightSamples::Auto`]); with more, one is chosen by power.
/// One light sample per hit leaves the noise of the choice: on the Cornell
/// box of `tools/mitsuba_cornell_check.py` (a point light and a light box)
/// sampling both removes 57% of the variance for 20% more time (docs/path-tracing.md,
/// "Lights per hit"). Each light adds a shadow ray to every hit, so the
/// count is kept small.
const EVERY_LIGHT_UP_TO: usize = 4;

/// Whether MIS samples every light at a hit rather than one chosen by power.
#[inline]
fn every_light(scene: &Scene, p: &PathParams) -> bool {
    match p.lights {
        LightSamples::All => true,
        LightSamples::One => scene.lights.len() <= 1,
        LightSamples::Auto => scene.lights.len() <= EVERY_LIGHT_UP_TO,
    }
}

/// The chance that MIS's light sampling takes a light at a hit, whose
/// chance of being chosen by power is `by_power`: 1 where every light is
/// sampled.
#[inline]
fn pick_chance(scene: &Scene, p: &PathParams, by_power: f32) -> f32 {
    if every_light(scene, p) {
        1.0
    } else {
        by_power
    }
}

/// How the ray being traced left its last surface, which decides how much an
/// emitter it hits counts.
#[derive(Clone, Copy, Debug)]
enum Came {
    /// From the camera or a perfectly specular bounce: in full.
    Direct,
    /// From a random bounce whose density was `pdf` (solid angle), off a
    /// surface whose facing shading normal was `n` (the normal the light
    /// samples there were drawn for).
    Bounce { pdf: f32, n: Vec3 },
}

/// Sampler calls of the first hit drawn from stratified patterns, after
/// the camera's (the light choice, the light sample, the bounce's lobe
/// choice and direction; see [`crate::render::sampler`]); deeper bounces
/// draw independent uniforms.
const STRATIFIED_FIRST_HIT: u32 = 4;

/// Radiance arriving along the camera ray `ray`.
pub fn radiance(scene: &Scene, ray: &Ray, p: &PathParams, st: &mut PathState) -> Vec3 {
    // Sampling every light, the first hit draws once per light that draws,
    // then the lobe and the direction.
    let first_hit = if p.mis && scene.lights.len() > 1 && every_light(scene, p) {
        2 + scene.lights.iter().filter(|l| l.draws()).count() as u32
    } else {
        STRATIFIED_FIRST_HIT
    };
    st.sampler.stratify_first(st.sampler.calls() + first_hit);
    li(scene, ray, 0, Vec3::ONE, Came::Direct, p, st)
}

/// Radiance along `ray`, which is bounce `depth` of a path of throughput
/// `beta` so far.
///
/// A vertex whose bounce is the last thing it adds (no specular part, no
/// media: most vertices) continues the loop with the bounce's ray instead of
/// recursing: its colour, weight and `q` wait in `pending`, and once the path
/// ends they are folded back deepest first as `c + w · L / q`, the
/// recursion's operations in its order, so the same bits. A recursive call
/// cost each vertex a prologue, an epilogue and its arguments through the
/// stack. Other vertices, and a path longer than `pending`, recurse.
fn li(
    scene: &Scene,
    ray: &Ray,
    depth: u32,
    beta: Vec3,
    came: Came,
    p: &PathParams,
    st: &mut PathState,
) -> Vec3 {
    let media = !scene.volumes.media.is_empty();
    let entry = st.travelled;
    let mut pending = [MaybeUninit::<Pending>::uninit(); DEFERRED];
    let mut n = 0;
    let (mut ray, mut depth, mut beta, mut came) = (*ray, depth, beta, came);
    let mut color = loop {
        let hit = volumes::trace(scene, &ray, depth == 0, st);
        // Borrowed in place: moving the hit out of the slot `trace` filled
        // copied it in wide loads that waited on its narrow stores.
        let (t, color) = match &hit {
            Some(hit) => {
                let before = st.travelled;
                st.travelled += hit.t;
                let defer = !media && n < DEFERRED;
                match shade(scene, &ray, hit, depth, beta, came, p, defer, st) {
                    Shaded::Done(c) => {
                        st.travelled = before;
                        (hit.t, c)
                    }
                    Shaded::Bounce(c, b) => {
                        // The next vertex sees this one's distance added,
                        // as the recursive call did.
                        pending[n].write(Pending { color: c, weight: b.weight, q: b.q });
                        n += 1;
                        (ray, depth, beta, came) = (b.ray, depth + 1, b.next, b.came);
                        continue;
                    }
                }
            }
            None => (f32::INFINITY, escaped(scene, &ray, came, p, st)),
        };
        // Nothing on the way dims the light or adds to it.
        if !media {
            break color;
        }
        if past_limit(scene, depth, p) {
            // The light found past the depth limit arrives dimmed by the media
            // on the way; scattering there would be one bounce too many.
            if is_black(color) {
                break color;
            }
            break color * volumes::media_transmittance(scene, &ray, t, st);
        }
        break volumes::through_media(scene, &ray, t, color, st);
    };
    while n > 0 {
        n -= 1;
        // SAFETY: entries below `n` were all written in the loop.
        let v = unsafe { pending[n].assume_init() };
        color = v.color + v.weight * color / v.q;
    }
    st.travelled = entry;
    color
}

/// Vertices of a path that [`li`] keeps waiting for their bounce's light;
/// past them it recurses. The course's path-traced scenes stop at depth 3
/// or 6 (without Russian roulette).
const DEFERRED: usize = 8;

/// A vertex waiting for the light its bounce brings: it adds
/// `color + weight · L / q`.
#[derive(Clone, Copy)]
struct Pending {
    color: Vec3,
    weight: Vec3,
    q: f32,
}

/// A random bounce to trace: its ray, its weight `f cos / p`, the Russian
/// roulette chance `q` it survived, the path's throughput past it and how
/// the ray left the surface.
struct Bounce {
    ray: Ray,
    weight: Vec3,
    q: f32,
    next: Vec3,
    came: Came,
}

/// What [`shade`] found: the whole light of the vertex, or the light of the
/// vertex but its bounce's, with the bounce for [`li`] to follow.
enum Shaded {
    Done(Vec3),
    Bounce(Vec3, Bounce),
}

/// Whether a vertex at `depth` lies past the path's depth limit. Only MIS
/// traces a ray there: the last vertex's bounce, which finds the light its
/// direction hits so that the light samples drawn at that vertex can be
/// weighed against it (as Mitsuba's path tracer does). Counting those light
/// samples in full instead has the same mean but not the same noise: near
/// an area light, light samples alone have a variance that grows as 1/d².
#[inline]
fn past_limit(scene: &Scene, depth: u32, p: &PathParams) -> bool {
    if p.russian_roulette {
        depth > MAX_BOUNCES
    } else {
        depth > scene.max_depth
    }
}

/// What a ray that leaves the scene brings: the environment (weighed against
/// its light samples) or the background.
fn escaped(scene: &Scene, ray: &Ray, came: Came, p: &PathParams, st: &PathState) -> Vec3 {
    let Some(env) = &scene.environment else {
        return scene.textures.background(st.screen).unwrap_or(scene.background);
    };
    let d = ray.d.normalize();
    let w = match came {
        Came::Direct => 1.0,
        // The density of the environment's own sampler (importance, uniform
        // or cosine about the normal), as its light samples were drawn.
        Came::Bounce { pdf, n } if p.mis => {
            let pick = pick_chance(scene, p, scene.light_pick.environment_pmf());
            power_heuristic(pdf, env.sampling_pdf(Some(n), d) * pick)
        }
        Came::Bounce { .. } if p.next_event => 0.0,
        Came::Bounce { .. } => 1.0,
    };
    env.eval(d) * w
}

/// The light a vertex adds. Inlined into [`li`]'s loop: out of line, its
/// answer (a [`Shaded`], ray and all) went through memory.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn shade(
    scene: &Scene,
    ray: &Ray,
    hit: &Hit,
    depth: u32,
    beta: Vec3,
    came: Came,
    p: &PathParams,
    defer: bool,
    st: &mut PathState,
) -> Shaded {
    // Matched in place, not moved out: a move copies the whole `Cow`, room
    // for an owned material, even when it borrows.
    let surface = surface_at(scene, ray, hit, depth, st);
    let (m, ns): (&Material, Vec3) = match &surface {
        Surface::Lit(m, ns) => (m, *ns),
        Surface::Unlit(c) => return Shaded::Done(*c),
        Surface::Failed => return Shaded::Done(Vec3::ZERO),
    };
    let entering = ray.d.dot(hit.ng) < 0.0;
    let (n, ng) = if entering { (ns, hit.ng) } else { (-ns, -hit.ng) };
    let eps = scene.shadow_epsilon;
    let mut color = Vec3::ZERO;

    // Under the course's next-event estimation an object light that a
    // random bounce hits counts nothing (its samples counted it): skip the
    // lookup of which light it is.
    let counted = p.mis || !p.next_event || matches!(came, Came::Direct);
    let emitter = if counted { scene.emitted(hit, ray.d) } else { None };
    if let Some((li_index, le)) = emitter {
        color += le * hit_weight(scene, li_index, came, ray, hit, p, st.time);
    }
    // A shader's emission is weighed like an object light's where the object
    // is a light ([`Light::Shaded`]); where it is not (the probes found no
    // emission, or the shape cannot be sampled) only bounces find it, so it
    // counts in full.
    if m.traits.emits {
        let w = match scene.light_of(hit) {
            Some(li) if matches!(scene.lights[li], Light::Shaded(_)) => {
                hit_weight(scene, li, came, ray, hit, p, st.time)
            }
            _ => 1.0,
        };
        color += m.emission * w;
    }

    if past_limit(scene, depth, p) {
        return Shaded::Done(color);
    }
    let inside_dielectric = !entering && matches!(m.kind, Specular::Dielectric { .. });
    let origin = hit.p + ng * eps;
    if m.traits.reflects && !inside_dielectric {
        let more = depth < MAX_BOUNCES && (p.russian_roulette || depth < scene.max_depth);
        let at = At::new(m, n, ray.d);
        if p.next_event || p.mis {
            color += next_event(scene, m, hit, &at, origin, depth, p, st);
        }
        // Under MIS the last vertex's bounce is traced too, for emission
        // only (see [`past_limit`]).
        if more || p.mis {
            match bounce(scene, m, &at, origin, depth, beta, p, st) {
                // Nothing follows the bounce at this vertex (see [`li`]).
                Some(b) if defer && matches!(m.kind, Specular::None) => return Shaded::Bounce(color, b),
                Some(b) => color += b.weight * li(scene, &b.ray, depth + 1, b.next, b.came, p, st) / b.q,
                // Adding zero as the recursion did: it turns a -0.0 channel
                // into +0.0, so the output keeps its bits.
                None => color += Vec3::ZERO,
            }
        }
    }
    // A material without a specular part (most) skips the depth tests and
    // the set-up of the specular rays.
    let specular_part = !matches!(m.kind, Specular::None);
    if specular_part && (depth < scene.max_depth || (p.russian_roulette && depth < MAX_BOUNCES)) {
        color += specular(scene, m, hit, n, ng, ray, entering, depth, beta, p, st);
    }
    if inside_dielectric {
        if let Specular::Dielectric { absorption, .. } = &m.kind {
            color *= (-*absorption * hit.t).exp();
        }
    }
    Shaded::Done(color)
}

/// One sample of every light, shadowed; with MIS each weighed against the
/// chance that the BSDF would have drawn its direction. Only picks the
/// version: both take its arguments as they are, so each is a jump (the
/// choice made in `li` instead cost pd5, which samples no light, ~19
/// instructions a path in `li`'s code).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn next_event(
    scene: &Scene,
    m: &Material,
    hit: &Hit,
    at: &At,
    origin: Vec3,
    depth: u32,
    p: &PathParams,
    st: &mut PathState,
) -> Vec3 {
    let vols = &scene.volumes;
    if !p.mis && at.f.is_some() && vols.surfaces.is_empty() && vols.media.is_empty() {
        next_event_diffuse(scene, m, hit, at, origin, depth, p, st)
    } else {
        next_event_any(scene, m, hit, at, origin, depth, p, st)
    }
}

/// [`next_event`] at any vertex.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn next_event_any(
    scene: &Scene,
    m: &Material,
    hit: &Hit,
    at: &At,
    origin: Vec3,
    depth: u32,
    p: &PathParams,
    st: &mut PathState,
) -> Vec3 {
    let mut color = Vec3::ZERO;
    // MIS takes every light of a scene with few ([`every_light`]), else one
    // per hit, chosen by power: a shadow ray per hit whatever the number of
    // lights. The course's variant samples them all.
    let (lights, scale) = if p.mis && !every_light(scene, p) {
        let (i, pick) = scene.light_pick.choose(st.sampler.next_1d());
        if pick <= 0.0 {
            return color;
        }
        (&scene.lights[i..=i], 1.0 / pick)
    } else {
        (&scene.lights[..], 1.0)
    };
    for light in lights {
        if let Light::Shaded(l) = light {
            color += shaded_sample(scene, l, m, hit, at, origin, depth, scale, p, st);
            continue;
        }
        let Some((ls, cos, tr)) = light_reaching_inline(scene, light, origin, hit.p, at.n, st) else {
            continue;
        };
        let (f, bsdf_pdf) = light_terms(m, at, ls.wi, cos, p);
        let w =
            if p.mis && hittable(light) { power_heuristic(ls.pdf / scale, bsdf_pdf) * scale } else { scale };
        color += f * (tr * ls.e) * w;
    }
    color
}

/// [`next_event`] for the course's variant at a vertex whose BRDF value is
/// the same for every light direction above it (`at.f`), in a scene without
/// volumes: each light's term is `f cos · E`, the weight and the shadow
/// ray's transmittance exactly 1 (multiplying by them kept the bits).
/// Apart, because LLVM hoisted the set-up of every case of [`light_terms`]
/// (the frame's rows, the whole view direction) out of [`next_event_any`]'s
/// light loop, ~160 instructions a call that this vertex never uses.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn next_event_diffuse(
    scene: &Scene,
    m: &Material,
    hit: &Hit,
    at: &At,
    origin: Vec3,
    depth: u32,
    p: &PathParams,
    st: &mut PathState,
) -> Vec3 {
    let f = at.f.unwrap_or_default();
    let mut color = Vec3::ZERO;
    for light in &scene.lights {
        if let Light::Shaded(l) = light {
            color += shaded_sample(scene, l, m, hit, at, origin, depth, 1.0, p, st);
            continue;
        }
        // [`light_reaching_inline`] without media: the shadow ray passes or not.
        let Some(ls) = light.sample_at(origin, hit.p, at.n, st.time, &mut st.sampler) else {
            continue;
        };
        let cos = at.n.dot(ls.wi);
        if cos <= 0.0 || is_black(ls.e) {
            continue;
        }
        let t_max = shadow_reach(scene, &ls);
        st.stats.shadow += 1;
        if scene.occluded(&Ray::new(origin, ls.wi), t_max, st.time) {
            continue;
        }
        // [`brdf_cos`]'s `f cos`.
        color += f * cos * ls.e;
    }
    color
}

/// One sample of an object whose shader emits: a ray towards a point drawn
/// on it, which counts only where its first hit is that point (for a sphere,
/// any point of the object), with the shader's emission found there.
#[allow(clippy::too_many_arguments)]
fn shaded_sample(
    scene: &Scene,
    l: &ShadedLight,
    m: &Material,
    hit: &Hit,
    at: &At,
    origin: Vec3,
    depth: u32,
    scale: f32,
    p: &PathParams,
    st: &mut PathState,
) -> Vec3 {
    let u = st.sampler.next_2d();
    let Some((wi, dist, pdf)) = l.sample(origin, hit.p, st.time, u) else { return Vec3::ZERO };
    let cos = at.n.dot(wi);
    if cos <= 0.0 {
        return Vec3::ZERO;
    }
    let r = Ray::new(origin, wi);
    st.stats.shadow += 1;
    let Some(h) = scene.intersect(&r, st.time, false) else { return Vec3::ZERO };
    let eps = scene.shadow_epsilon;
    // Another part of the same mesh in front of the sampled point blocks it
    // (that part is a sample of its own).
    if scene.prim_of(&h) != Some(l.prim) || (dist.is_finite() && h.t < dist * (1.0 - 1e-3) - eps) {
        return Vec3::ZERO;
    }
    let vols = &scene.volumes;
    let tr = if vols.surfaces.is_empty() && vols.media.is_empty() {
        Vec3::ONE
    } else {
        volumes::shadow(scene, &r, h.t - eps, st)
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
    let (f, bsdf_pdf) = light_terms(m, at, wi, cos, p);
    let w = if p.mis { power_heuristic(pdf / scale, bsdf_pdf) * scale } else { scale };
    f * (tr * e.emission) * (w / pdf)
}

/// How much an emitter (light `li`) that a ray hit counts, by how the ray
/// left its last surface: in full after the camera or a specular bounce;
/// after a random bounce by the power heuristic under MIS, not at all under
/// the course's next-event estimation (the light samples counted it).
fn hit_weight(scene: &Scene, li: usize, came: Came, ray: &Ray, hit: &Hit, p: &PathParams, time: f32) -> f32 {
    match came {
        Came::Direct => 1.0,
        Came::Bounce { pdf, .. } if p.mis => {
            let pick = pick_chance(scene, p, scene.light_pick.pmf(li));
            power_heuristic(pdf, pick * light_pdf(&scene.lights[li], ray.o, hit, ray.d, time))
        }
        Came::Bounce { .. } if p.next_event => 0.0,
        Came::Bounce { .. } => 1.0,
    }
}

/// Whether a bounce can hit the light (then MIS weighs its two samples).
#[inline]
fn hittable(light: &Light) -> bool {
    matches!(light, Light::Mesh(_) | Light::Sphere(_) | Light::Environment(_) | Light::Shaded(_))
}

/// The light's density for the direction `d` of a ray from `from` at
/// shutter `time` that hit it at `hit`.
fn light_pdf(light: &Light, from: Vec3, hit: &Hit, d: Vec3, time: f32) -> f32 {
    match light {
        Light::Mesh(l) => l.pdf(from, hit.p, hit.ng),
        Light::Sphere(l) => l.pdf(from - l.motion * time, d.normalize()),
        Light::Shaded(l) => l.pdf(from, hit.p, hit.ng, d, time),
        _ => 0.0,
    }
}

/// The power heuristic with exponent 2 for a sample of density `a` against
/// the other technique's `b`.
#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 <= 0.0 || !a2.is_finite() {
        return 1.0;
    }
    a2 / (a2 + b2)
}

/// The shading point's frame, shared by its light samples and its bounce:
/// the facing shading normal `n`, the frame around it, the direction to the
/// viewer in that frame, the incoming ray's direction `d`, and for a
/// Phong-family BRDF without specular colour its value `f` for directions
/// above the surface (zero where the viewer is below it), the same for every
/// light sample and bounce. Where `f` is set, `wo` holds only its `z` (`x`
/// and `y` are zero): that BRDF's value, density and sample need no more, and
/// the two dot products cost ~25 instructions a path.
struct At {
    n: Vec3,
    frame: Frame,
    wo: Vec3,
    d: Vec3,
    f: Option<Vec3>,
}

impl At {
    #[inline(always)]
    fn new(m: &Material, n: Vec3, d: Vec3) -> At {
        let frame = Frame::new(n);
        // [`PhongFamily::eval_diffuse`]'s test of the viewer's cosine. The
        // local `z` of `-d` is `-d·n`, as [`Frame::to_local`] works it out.
        let (wo, f) = match m.traits.phong_diffuse {
            Some(f) => {
                let z = (-d).dot(n);
                (Vec3::new(0.0, 0.0, z), Some(if z <= 0.0 { Vec3::ZERO } else { f }))
            }
            None => (frame.to_local(-d), None),
        };
        At { n, frame, wo, d, f }
    }

    /// The whole view direction in the frame, where `wo` may hold its `z`
    /// alone.
    #[inline]
    fn wo_full(&self) -> Vec3 {
        if self.f.is_some() {
            self.frame.to_local(-self.d)
        } else {
            self.wo
        }
    }
}

/// For a light sample from `wi` (`cos = n·wi > 0`): the reflectance times
/// the cosine, and the density with which [`bounce`] would draw `wi` (zero
/// unless MIS needs it), the BRDF's local directions worked out once.
#[inline(always)]
fn light_terms(m: &Material, at: &At, wi: Vec3, cos: f32, p: &PathParams) -> (Vec3, f32) {
    match &m.brdf {
        Some(b) if p.mis => {
            // Without a lobe only the cosines count: the local `z` of `wi` is
            // `n·wi`, the bits of `cos`.
            if let (true, Some(f)) = (m.traits.diffuse_only, at.f) {
                return (f * cos, diffuse_pdf(at.wo.z, cos));
            }
            let local = at.frame.to_local(wi);
            let wo = at.wo_full();
            let f = b.eval(m.diffuse, m.specular, local, wo) * cos;
            (f, b.pdf(m.diffuse, m.specular, wo, local))
        }
        Some(b) => (brdf_cos(b, m, at, wi, cos), 0.0),
        None => {
            let e = if p.importance || p.mis { 1.0 } else { 0.0 };
            (reflectance(m, at.n, wi, at.d, cos), power_cosine_pdf(e, cos))
        }
    }
}

/// `f(wi, wo) cos` for a world direction `wi` with `cos = n·wi > 0`. A
/// Phong-family BRDF without a specular colour (every material of the
/// course's path-traced boxes) is its diffuse term whatever `wi`, which it
/// only checks for `wi.z > 0`: the local `z` is `wi·n`, the same bits as
/// `cos`, so `wi` need not be brought into the frame, and the term is the
/// vertex's `at.f`.
#[inline(always)]
fn brdf_cos(b: &Brdf, m: &Material, at: &At, wi: Vec3, cos: f32) -> Vec3 {
    match at.f {
        Some(f) => f * cos,
        None => b.eval(m.diffuse, m.specular, at.frame.to_local(wi), at.wo) * cos,
    }
}

/// The random bounce: a direction drawn as the variant says, its weight
/// `f cos / p`, and Russian roulette when asked for; `None` where it brings
/// no light (its light would count as zero). Inlined into [`shade`] (see
/// there).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn bounce(
    scene: &Scene,
    m: &Material,
    at: &At,
    origin: Vec3,
    depth: u32,
    beta: Vec3,
    p: &PathParams,
    st: &mut PathState,
) -> Option<Bounce> {
    let (n, frame) = (at.n, &at.frame);
    // Only an MIS bounce off a BRDF chooses a lobe; the others skip the
    // draw (a stratified one at the first hit), keeping the later ones.
    let choice = if p.mis && m.brdf.is_some() {
        st.sampler.next_1d()
    } else {
        st.sampler.skip();
        0.0
    };
    let u = st.sampler.next_2d();
    // Each arm tests the direction (`n·wi > 0`, `p > 0`) before its
    // `f cos`: the same tests as one after the match, without carrying an
    // optional value out of it.
    let (wi, pdf, f_cos) = match (&m.brdf, p.mis) {
        (Some(b), true) => {
            let only = if m.traits.diffuse_only { b.assume_diffuse_only() } else { None };
            let s = match only {
                // Only the mixture's fallback (a choice not below 1) needs
                // more of the view direction than its `z` (see [`At`]).
                Some(d) if choice < 1.0 => d.sample(m.diffuse, m.specular, at.wo, choice, u),
                Some(d) => d.sample(m.diffuse, m.specular, at.wo_full(), choice, u),
                None => b.sample(m.diffuse, m.specular, at.wo_full(), choice, u),
            };
            let s = s?;
            // The BRDF's sample carries its value: no second evaluation.
            let wi = frame.to_world(s.wi);
            let cos = n.dot(wi);
            if cos <= 0.0 || s.pdf <= 0.0 {
                return None;
            }
            (wi, s.pdf, s.f * cos)
        }
        (b, _) => {
            // The exponent a constant in each arm: its tests fold away.
            let (local, pdf) = if p.importance || p.mis {
                let local = power_cosine(1.0, u);
                (local, power_cosine_pdf(1.0, local.z))
            } else {
                let local = power_cosine(0.0, u);
                (local, power_cosine_pdf(0.0, local.z))
            };
            let wi = frame.to_world(local);
            let cos = n.dot(wi);
            if cos <= 0.0 || pdf <= 0.0 {
                return None;
            }
            let f_cos = match b {
                // The frame and view direction [`reflectance`] would build again.
                Some(b) => brdf_cos(b, m, at, wi, cos),
                None => reflectance(m, n, wi, at.d, cos),
            };
            (wi, pdf, f_cos)
        }
    };
    let weight = f_cos / pdf;
    let next = beta * weight;
    let mut q = 1.0;
    if p.russian_roulette {
        q = next.max_element().min(1.0);
        if st.sampler.next_1d() >= q {
            return None;
        }
    }
    let ray = Ray::new(origin, wi);
    // Past the depth limit the bounce looks for emitters alone.
    if past_limit(scene, depth + 1, p) && !scene.may_find_emission(&ray) {
        return None;
    }
    if !st.spawn(next.max_element()) {
        return None;
    }
    Some(Bounce { ray, weight, q, next, came: Came::Bounce { pdf, n } })
}

/// Mirror, conductor and dielectric rays, as the recursive ray tracer sends
/// them (with its glossy roughness), each weighted by its reflectance.
#[allow(clippy::too_many_arguments)]
fn specular(
    scene: &Scene,
    m: &Material,
    hit: &Hit,
    n: Vec3,
    ng: Vec3,
    ray: &Ray,
    entering: bool,
    depth: u32,
    beta: Vec3,
    p: &PathParams,
    st: &mut PathState,
) -> Vec3 {
    let eps = scene.shadow_epsilon;
    let cos_i = -ray.d.dot(n);
    let r = m.roughness;
    let trace = |st: &mut PathState, o: Vec3, d: Vec3, k: Vec3| -> Vec3 {
        let next = beta * k;
        if !st.spawn(next.max_element()) {
            return Vec3::ZERO;
        }
        k * li(scene, &Ray::new(o, d), depth + 1, next, Came::Direct, p, st)
    };
    match m.kind {
        Specular::None => Vec3::ZERO,
        Specular::Mirror => {
            let d = glossy(reflect(ray.d, n), r, st);
            trace(st, hit.p + ng * eps, d, m.mirror)
        }
        Specular::Conductor { n: eta, k } => {
            let f = fresnel::conductor(cos_i, eta, k);
            let d = glossy(reflect(ray.d, n), r, st);
            trace(st, hit.p + ng * eps, d, m.mirror * f)
        }
        Specular::Dielectric { ior, .. } => {
            let (n1, n2) = if entering { (1.0, ior) } else { (ior, 1.0) };
            let (f, cos_t) = fresnel::dielectric(cos_i, n1, n2);
            let d = glossy(reflect(ray.d, n), r, st);
            let mut c = trace(st, hit.p + ng * eps, d, Vec3::splat(f));
            if let Some(cos_t) = cos_t {
                let eta = n1 / n2;
                let d = glossy((ray.d * eta + n * (eta * cos_i - cos_t)).normalize(), r, st);
                c += trace(st, hit.p - ng * eps, d, Vec3::splat(1.0 - f));
            }
            c
        }
    }
}
