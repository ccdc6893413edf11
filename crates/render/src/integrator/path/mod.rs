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
//! | `RussianRoulette` | no depth limit but [`MAX_BOUNCES`] ([`MAX_MEDIUM_BOUNCES`] in a scene with media): a path goes on with probability `q = min(1, max(throughput))` and its estimate is divided by `q` |
//! | `MIS` (luster) | bounces drawn from the BSDF; every light sampled per hit in a scene with at most four (`AllLights`: always), else one, chosen by the light tree for the point ([`crate::light::tree`]; `OneLight`: always), its estimate divided by the chance of choosing it; light and bounce samples both count, weighed by the power heuristic `p_a² / (p_a² + p_b²)` with the light's density times the chance of choosing it; the environment light is sampled and hit alike |
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
//!
//! Through media a ray is tracked ([`tracking`]): where it really scatters
//! first, the path goes on from there (`medium.rs`: light samples weighed by
//! the phase function, a bounce drawn from it); where it passes, from the
//! surface it hits. Paths entering an object with an `<Interior>` carry its
//! medium until they leave it.

use std::mem::MaybeUninit;

use super::{is_black, surface_at, PathState, Surface};
use crate::bsdf::Specular;
use crate::integrator::media;
use crate::integrator::tracking::{self, Event};
use crate::light::{Light, LightSample};
use crate::material::Material;
use crate::render::scene::{Hit, Scene};
use luster_core::math::{Ray, Vec3, Vec3A};

mod medium;
mod next_event;
mod params;
mod vertex;
use crate::bsdf::{Bsdf, Lobes};
use next_event::{hit_weight, next_event, next_event_closure, power_heuristic};
pub use params::PathParams;
use params::{by_variant, every_light, pick_chance};
use vertex::{bounce, bounce_through, specular};

/// Bounces after which even Russian roulette stops a path (the throughput of
/// a path that long is far below anything visible).
pub const MAX_BOUNCES: u32 = 64;

/// The same in a scene with media, where light may scatter hundreds of
/// times inside a dense cloud before it leaves (surfaces still stop
/// bouncing past [`MAX_BOUNCES`]).
pub const MAX_MEDIUM_BOUNCES: u32 = 1024;

/// How the ray being traced left its last surface, which decides how much an
/// emitter it hits counts.
#[derive(Clone, Copy, Debug)]
enum Came {
    /// From the camera or a perfectly specular bounce: in full.
    Direct,
    /// From a random bounce whose density was `pdf` (solid angle), off the
    /// surface point `from` whose facing shading normal was `n` (the point
    /// and normal the light samples there were drawn for).
    Bounce { pdf: f32, n: Vec3, from: Vec3 },
    /// Scattered in a medium in a direction drawn from its phase function
    /// with density `pdf` (its light samples were drawn with no normal).
    Scatter { pdf: f32 },
}

/// Sampler calls of the first hit drawn from stratified patterns, after
/// the camera's (the light choice, the light sample, the bounce's lobe
/// choice and direction; see [`crate::render::sampler`]); deeper bounces
/// draw independent uniforms.
const STRATIFIED_FIRST_HIT: u32 = 4;

/// The sampler calls of a path's first hit that are stratified: sampling
/// every light, the first hit draws once per light that draws, then the
/// lobe and the direction.
#[inline]
fn first_hit_calls(scene: &Scene, p: PathParams) -> u32 {
    if p.mis && scene.lights.len() > 1 && every_light(scene, p) {
        2 + scene.lights.iter().filter(|l| l.draws()).count() as u32
    } else {
        STRATIFIED_FIRST_HIT
    }
}

/// Radiance arriving along the camera ray `ray`.
pub fn radiance(scene: &Scene, ray: &Ray, p: &PathParams, st: &mut PathState) -> Vec3 {
    let p = *p;
    (st.tracking, st.interior) = (true, None);
    st.sampler.stratify_first(st.sampler.calls() + first_hit_calls(scene, p));
    by_variant!(p, V => li::<V>(scene, ray, 0, Vec3::ONE, Came::Direct, p, st))
}

/// Radiance along `ray`, which is bounce `depth` of a path of throughput
/// `beta` so far.
///
/// A vertex whose bounce is the last thing it adds (no specular part: most
/// vertices) continues the loop with the bounce's ray instead of
/// recursing: its colour, weight and `q` wait in the [`Walk`], and once the
/// path ends they are folded back deepest first as `c + w · L / q`, the
/// recursion's operations in its order, so the same bits. A recursive call
/// would cost each vertex a prologue, an epilogue and its arguments through
/// the stack. Other vertices, and a path longer than [`DEFERRED`], recurse.
/// In a scene with media nothing waits: each vertex (a scattering too) adds
/// its light at once, times the weights before it, so a path may be long.
fn li<const V: u8>(
    scene: &Scene,
    ray: &Ray,
    depth: u32,
    beta: Vec3,
    came: Came,
    p: PathParams,
    st: &mut PathState,
) -> Vec3 {
    let p = p.fixed::<V>();
    let mut w = Walk::new(scene, *ray, depth, beta, came, st);
    let color = w.run::<V>(scene, p, st);
    w.fold(color, st)
}

/// The radiance of two camera rays, each with its own state, their paths
/// traced in step: a vertex of one, then the same vertex of the other.
/// Each path's chain (hit, shading, sample, next ray) is serial, and the
/// processor overlaps only work that is close in the instruction stream;
/// two independent paths side by side give it that work. Each path draws
/// from its own sampler and does exactly what [`radiance`] does for it, so
/// the two answers are [`radiance`]'s, bit for bit. They come back as
/// `Vec3A`, each written and read in one 16-byte move: as `Vec3`s the
/// render loop could read the first with the second's `x` in one load,
/// which would wait for the narrower stores that wrote them.
pub fn radiance_pair(
    scene: &Scene,
    rays: [&Ray; 2],
    p: &PathParams,
    sa: &mut PathState,
    sb: &mut PathState,
) -> [Vec3A; 2] {
    let p = *p;
    (sa.tracking, sb.tracking, sa.interior, sb.interior) = (true, true, None, None);
    by_variant!(p, V => pair::<V>(scene, rays, p, sa, sb))
}

/// [`radiance_pair`] for the variant `V`.
#[inline(never)]
fn pair<const V: u8>(
    scene: &Scene,
    rays: [&Ray; 2],
    p: PathParams,
    sa: &mut PathState,
    sb: &mut PathState,
) -> [Vec3A; 2] {
    let p = p.fixed::<V>();
    let first_hit = first_hit_calls(scene, p);
    sa.sampler.stratify_first(sa.sampler.calls() + first_hit);
    sb.sampler.stratify_first(sb.sampler.calls() + first_hit);
    let mut a = Walk::new(scene, *rays[0], 0, Vec3::ONE, Came::Direct, sa);
    let mut b = Walk::new(scene, *rays[1], 0, Vec3::ONE, Came::Direct, sb);
    let (ca, cb) = loop {
        let ha = media::trace(scene, &a.ray, a.depth == 0, sa);
        let hb = media::trace(scene, &b.ray, b.depth == 0, sb);
        let ra = a.step::<V>(scene, &ha, p, sa);
        let rb = b.step::<V>(scene, &hb, p, sb);
        match (ra, rb) {
            (None, None) => {}
            (Some(ca), Some(cb)) => break (ca, cb),
            (Some(ca), None) => break (ca, b.run::<V>(scene, p, sb)),
            (None, Some(cb)) => break (a.run::<V>(scene, p, sa), cb),
        }
    };
    [a.fold(ca, sa).into(), b.fold(cb, sb).into()]
}

/// A path being followed by [`li`]: the ray to trace next, its bounce,
/// throughput and how it left its surface, and the vertices waiting for the
/// light their bounce brings.
struct Walk {
    ray: Ray,
    depth: u32,
    beta: Vec3,
    came: Came,
    /// Whether the scene has media. Then no vertex waits: each adds its
    /// light at once, times the product of the weights before it (`thr`),
    /// into `acc`, so that a path may scatter hundreds of times.
    media: bool,
    acc: Vec3,
    thr: Vec3,
    /// The medium inside the object the walk's ray is in.
    interior: Option<u32>,
    /// The distance travelled before the walk, given back at its end.
    entry: f32,
    n: usize,
    pending: [MaybeUninit<Pending>; DEFERRED],
}

impl Walk {
    #[inline(always)]
    fn new(scene: &Scene, ray: Ray, depth: u32, beta: Vec3, came: Came, st: &PathState) -> Walk {
        Walk {
            ray,
            depth,
            beta,
            came,
            media: scene.volumes.has_media(),
            acc: Vec3::ZERO,
            thr: Vec3::ONE,
            interior: st.interior,
            entry: st.travelled,
            n: 0,
            pending: [MaybeUninit::uninit(); DEFERRED],
        }
    }

    /// Follows the path to its end: the light along the walk's ray once
    /// the vertices waiting have added theirs ([`Walk::fold`]).
    #[inline(always)]
    fn run<const V: u8>(&mut self, scene: &Scene, p: PathParams, st: &mut PathState) -> Vec3 {
        loop {
            let hit = media::trace(scene, &self.ray, self.depth == 0, st);
            if let Some(c) = self.step::<V>(scene, &hit, p, st) {
                break c;
            }
        }
    }

    /// The vertex where the walk's ray ends (`hit`, from
    /// [`media::trace`]): `None` where the path goes on from there with
    /// the bounce's ray, else the light arriving along the ray.
    #[inline(always)]
    fn step<const V: u8>(
        &mut self,
        scene: &Scene,
        hit: &Option<Hit>,
        p: PathParams,
        st: &mut PathState,
    ) -> Option<Vec3> {
        if self.media {
            return self.step_media::<V>(scene, hit, p, st);
        }
        // The ray, like the hit, is read where it lies: a copy would be
        // written in a 16- and an 8-byte store, and the direction read back
        // across both, a load the store buffer cannot forward.
        let depth = self.depth;
        // Borrowed in place: moving the hit out of the slot `trace` filled
        // would copy it in wide loads that wait on its narrow stores.
        let color = match hit {
            Some(hit) => {
                let before = st.travelled;
                st.travelled += hit.t;
                let defer = self.n < DEFERRED;
                match shade::<V>(scene, &self.ray, hit, depth, self.beta, self.came, p, defer, st) {
                    Shaded::Done(c) => {
                        st.travelled = before;
                        c
                    }
                    Shaded::Bounce(c, b) => {
                        // The next vertex sees this one's distance added,
                        // as a recursive call would.
                        self.pending[self.n].write(Pending { color: c, weight: b.weight, q: b.q });
                        self.n += 1;
                        (self.ray, self.depth, self.beta, self.came) = (b.ray, depth + 1, b.next, b.came);
                        return None;
                    }
                }
            }
            None => escaped(scene, &self.ray, self.came, past_limit(scene, depth, p), p, st),
        };
        Some(color)
    }

    /// [`Walk::step`] in a scene with media: the ray is tracked through
    /// them up to `hit` ([`tracking::track`]); where it scatters first, the
    /// path goes on from there, else from the hit as without media.
    #[inline(never)]
    fn step_media<const V: u8>(
        &mut self,
        scene: &Scene,
        hit: &Option<Hit>,
        p: PathParams,
        st: &mut PathState,
    ) -> Option<Vec3> {
        let depth = self.depth;
        let past = past_limit(scene, depth, p);
        let t_hit = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
        // What the vertex does below (light samples, recursion) starts in
        // the walk's medium.
        st.interior = self.interior;
        // Past the depth limit the ray only gathers light: it may not scatter.
        let tracked = tracking::track(scene, &self.ray, t_hit, self.beta, !past, self.interior, st);
        self.acc += self.thr * tracked.emitted;
        self.thr *= tracked.weight;
        let beta = self.beta * tracked.weight;
        let (c, b) = match (tracked.event, hit) {
            (Event::Absorbed, _) => return Some(Vec3::ZERO),
            (Event::Scatter { t, g }, _) => {
                let x = self.ray.at(t);
                let d = self.ray.d;
                let mut c = Vec3::ZERO;
                if p.next_event || p.mis {
                    c = medium::next_event_phase(scene, x, d, g, depth, p, st);
                }
                let more = p.mis || p.russian_roulette || depth < scene.max_depth;
                let b = if more { medium::scatter_bounce(scene, x, d, g, depth, beta, p, st) } else { None };
                st.travelled += t;
                (c, b)
            }
            (Event::Pass, Some(hit)) => {
                let before = st.travelled;
                st.travelled += hit.t;
                match shade::<V>(scene, &self.ray, hit, depth, beta, self.came, p, true, st) {
                    Shaded::Done(c) => {
                        st.travelled = before;
                        return Some(c);
                    }
                    Shaded::Bounce(c, b) => (c, Some(b)),
                }
            }
            (Event::Pass, None) => return Some(escaped(scene, &self.ray, self.came, past, p, st)),
        };
        let Some(b) = b else { return Some(c) };
        self.acc += self.thr * c;
        self.thr *= b.weight / b.q;
        (self.ray, self.depth, self.beta, self.came) = (b.ray, depth + 1, b.next, b.came);
        None
    }

    /// The light along the walk's first ray, given `color` arriving at its
    /// last vertex: the waiting vertices' terms added deepest first.
    #[inline(always)]
    fn fold(&self, mut color: Vec3, st: &mut PathState) -> Vec3 {
        if self.media {
            st.travelled = self.entry;
            return self.acc + self.thr * color;
        }
        let mut n = self.n;
        while n > 0 {
            n -= 1;
            // SAFETY: entries below `self.n` were all written by `step`.
            let v = unsafe { self.pending[n].assume_init() };
            color = v.color + v.weight * color / v.q;
        }
        st.travelled = self.entry;
        color
    }
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

/// The point on a light that a vertex's light samples take first, drawn
/// at the top of [`shade`]. A vertex samples its lights as soon as its hit
/// is known; drawing the point on a light mesh there (a count over the
/// triangles, a division, a square root) would put that chain between the
/// hit and the shadow ray. Drawn earlier, it is worked out while the
/// vertex's frame and emission are.
#[derive(Clone, Copy)]
struct LightAhead {
    /// The light (an index into the scene's lights): the first that draws.
    light: usize,
    /// Its point, at rest, the normal there, and the area it was drawn from.
    q: Vec3,
    n: Vec3,
    area: f32,
}

impl LightAhead {
    /// The point of the first light that draws, where it is a mesh and the
    /// light samples take every light (not one chosen by a draw of its own),
    /// for the surface point `x`.
    #[inline(always)]
    fn draw(scene: &Scene, p: PathParams, x: Vec3, st: &mut PathState) -> Option<LightAhead> {
        if p.mis && !every_light(scene, p) {
            return None;
        }
        let light = scene.lights.iter().position(Light::draws)?;
        let Light::Mesh(l) = &scene.lights[light] else { return None };
        let (q, n, area) = l.point_seen(st.sampler.next_2d(), x, st.time);
        Some(LightAhead { light, q, n, area })
    }

    /// The sample of `light`, the `i`th of the scene's, for a surface point
    /// `p` of normal `n`: from the point drawn ahead where it is that
    /// light's, else drawn now.
    #[inline(always)]
    fn sample(
        ahead: Option<LightAhead>,
        i: usize,
        light: &Light,
        p: Vec3,
        n: Vec3,
        st: &mut PathState,
    ) -> Option<LightSample> {
        match (light, ahead) {
            (Light::Mesh(l), Some(a)) if a.light == i => l.sample_from(p, (a.q, a.n, a.area), st.time),
            _ => light.sample_at(p, n, st.time, &mut st.sampler),
        }
    }
}

/// `f` run with the path's medium set to what lies past the surface at
/// `hit`, where a ray leaving it along `d` crosses it (the ray that arrived
/// went along `incoming`); the medium is restored after. Without interiors
/// in the scene, `f` alone.
#[inline(always)]
fn across<R>(
    scene: &Scene,
    hit: &Hit,
    incoming: Vec3,
    d: Vec3,
    st: &mut PathState,
    f: impl FnOnce(&mut PathState) -> R,
) -> R {
    if scene.volumes.interiors.is_empty() || (d.dot(hit.ng) < 0.0) != (incoming.dot(hit.ng) < 0.0) {
        return f(st);
    }
    let saved = st.interior;
    st.interior = scene.medium_across(hit, d);
    let r = f(st);
    st.interior = saved;
    r
}

/// Whether a vertex at `depth` lies past the path's depth limit. Only MIS
/// traces a ray there: the last vertex's bounce, which finds the light its
/// direction hits so that the light samples drawn at that vertex can be
/// weighed against it (as Mitsuba's path tracer does). Counting those light
/// samples in full instead has the same mean but not the same noise: near
/// an area light, light samples alone have a variance that grows as 1/d².
/// Only lights count there (emitters, shaders' emission, the environment):
/// not the background, nor an unlit map's colour, which a path stopped by
/// the limit never sees.
#[inline]
fn past_limit(scene: &Scene, depth: u32, p: PathParams) -> bool {
    if p.russian_roulette {
        depth > if scene.volumes.has_media() { MAX_MEDIUM_BOUNCES } else { MAX_BOUNCES }
    } else {
        depth > scene.max_depth
    }
}

/// What a ray that leaves the scene brings: the environment (weighed against
/// its light samples) or the background. Past the depth limit (`past`) a
/// ray looks for lights alone ([`past_limit`]), and the background is none:
/// counted there, it would come only with the rays that pass an emitter's box,
/// the others being skipped untraced ([`Scene::may_find_emission`]).
fn escaped(scene: &Scene, ray: &Ray, came: Came, past: bool, p: PathParams, st: &PathState) -> Vec3 {
    let Some(env) = &scene.environment else {
        if past {
            return Vec3::ZERO;
        }
        return scene.textures.background(st.screen).unwrap_or(scene.background);
    };
    let d = ray.d.normalize();
    match came {
        Came::Direct => env.eval(d),
        // The density of the environment's own sampler (importance, uniform
        // or cosine about the normal), as its light samples were drawn.
        Came::Bounce { pdf, n, from } if p.mis => {
            let pick = scene.environment_light.map_or(0.0, |i| pick_chance(scene, p, i, from, Some(n)));
            let (le, env_pdf) = env.eval_with_pdf(Some(n), d);
            le * power_heuristic(pdf, env_pdf * pick)
        }
        Came::Scatter { pdf } if p.mis => {
            let pick = scene.environment_light.map_or(0.0, |i| pick_chance(scene, p, i, ray.o, None));
            let (le, env_pdf) = env.eval_with_pdf(None, d);
            le * power_heuristic(pdf, env_pdf * pick)
        }
        Came::Bounce { .. } | Came::Scatter { .. } if p.next_event => Vec3::ZERO,
        Came::Bounce { .. } | Came::Scatter { .. } => env.eval(d),
    }
}

/// The light a vertex adds. Inlined into [`li`]'s loop: out of line, its
/// answer (a [`Shaded`], ray and all) would go through memory.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn shade<const V: u8>(
    scene: &Scene,
    ray: &Ray,
    hit: &Hit,
    depth: u32,
    beta: Vec3,
    came: Came,
    p: PathParams,
    defer: bool,
    st: &mut PathState,
) -> Shaded {
    // Matched in place, not moved out: a move copies the whole `Cow`, room
    // for an owned material, even when it borrows.
    let surface = surface_at(scene, ray, hit, depth, st);
    let past = past_limit(scene, depth, p);
    let (m, ns): (&Material, Vec3) = match &surface {
        Surface::Lit(m, ns) => (m, *ns),
        // An unlit map's colour is no light (see [`escaped`]).
        Surface::Unlit(_) if past => return Shaded::Done(Vec3::ZERO),
        Surface::Unlit(c) => return Shaded::Done(*c),
        Surface::Failed => return Shaded::Done(Vec3::ZERO),
    };
    let entering = ray.d.dot(hit.ng) < 0.0;
    let (n, ng) = if entering { (ns, hit.ng) } else { (-ns, -hit.ng) };
    let eps = scene.offset(hit.p, ray.o);
    let mut color = Vec3::ZERO;
    let inside_dielectric = !entering && matches!(m.kind, Specular::Dielectric { .. });
    // The light samples' first draw, made as soon as the vertex is known to
    // sample lights: nothing draws between here and [`next_event`], so it
    // is the value that would be drawn there (see [`LightAhead`]).
    let samples_lights = (p.next_event || p.mis) && m.traits.reflects && !inside_dielectric;
    let ahead =
        if samples_lights && !past && !m.closure { LightAhead::draw(scene, p, hit.p, st) } else { None };

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

    if past {
        return Shaded::Done(color);
    }
    let origin = hit.p + ng * eps;
    if m.closure {
        // A closure's lobes, copied out before anything else is shaded.
        let lobes = *st.lobes;
        color += closure_vertex::<V>(scene, ray, hit, ng, &lobes, m, depth, beta, p, st);
    } else if m.traits.reflects && !inside_dielectric {
        let more = depth < MAX_BOUNCES && (p.russian_roulette || depth < scene.max_depth);
        let at = Bsdf::new(m, n, ray.d);
        if p.next_event || p.mis {
            color += Vec3::from(next_event(scene, hit, &at, origin, depth, p, ahead, st));
        }
        // Under MIS the last vertex's bounce is traced too, for emission
        // only (see [`past_limit`]).
        if more || p.mis {
            match bounce(scene, &at, hit.p, origin, depth, beta, p, st) {
                // Nothing follows the bounce at this vertex (see [`li`]).
                Some(b) if defer && matches!(m.kind, Specular::None) => return Shaded::Bounce(color, b),
                Some(b) => color += b.weight * li::<V>(scene, &b.ray, depth + 1, b.next, b.came, p, st) / b.q,
                // Adding zero as the recursion does: it turns a -0.0 channel
                // into +0.0, so the output keeps its bits.
                None => color += Vec3::ZERO,
            }
        }
    }
    // A material without a specular part (most) skips the depth tests and
    // the set-up of the specular rays.
    let specular_part = !matches!(m.kind, Specular::None);
    if specular_part && (depth < scene.max_depth || (p.russian_roulette && depth < MAX_BOUNCES)) {
        color += specular::<V>(scene, m, hit, n, ng, ray, entering, depth, beta, p, st);
    }
    if inside_dielectric {
        if let Specular::Dielectric { absorption, .. } = &m.kind {
            color *= (-*absorption * hit.t).exp();
        }
    }
    Shaded::Done(color)
}

/// What a vertex whose material is a shader's closure adds besides its
/// emission: its light samples, its bounce (through the surface too, where
/// a lobe transmits) and, where the closure lets light straight through,
/// the light behind it along the same ray. Out of line: closures are the
/// rarer case, and their lobes are large.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn closure_vertex<const V: u8>(
    scene: &Scene,
    ray: &Ray,
    hit: &Hit,
    ng: Vec3,
    lobes: &Lobes,
    m: &Material,
    depth: u32,
    beta: Vec3,
    p: PathParams,
    st: &mut PathState,
) -> Vec3 {
    let eps = scene.offset(hit.p, ray.o);
    let mut color = Vec3::ZERO;
    let at = Bsdf::closure(m, lobes, ray.d);
    if !lobes.is_empty() {
        if p.next_event || p.mis {
            color += next_event_closure(scene, hit, &at, ng, eps, depth, p, st);
        }
        let more = depth < MAX_BOUNCES && (p.russian_roulette || depth < scene.max_depth);
        if more || p.mis {
            if let Some(b) = bounce_through(scene, &at, hit.p, ng * eps, depth, beta, p, st) {
                let l = across(scene, hit, ray.d, b.ray.d, st, |st| {
                    li::<V>(scene, &b.ray, depth + 1, b.next, b.came, p, st)
                });
                color += b.weight * l / b.q;
            }
        }
    }
    // A cut-out: the ray goes on as if the surface were not there. Shadow
    // rays stop at the surface, so no light sample reached what the ray
    // finds beyond it: an emitter there counts in full.
    if !is_black(lobes.transparency) && depth < MAX_BOUNCES {
        let next = beta * lobes.transparency;
        if st.spawn(next.max_element()) {
            let on = Ray::new(hit.p - ng * eps, ray.d);
            let l = across(scene, hit, ray.d, ray.d, st, |st| {
                li::<V>(scene, &on, depth, next, Came::Direct, p, st)
            });
            color += lobes.transparency * l;
        }
    }
    color
}
