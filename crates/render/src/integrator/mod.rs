//! Integrators: what radiance a camera ray brings back. Each camera names one
//! in the scene (`<Renderer>`, `<RendererParams>`, see
//! [`luster_scene::ceng795::camera::renderer`]):
//!
//! | integrator | scene | module |
//! |---|---|---|
//! | recursive (Whitted) ray tracing with direct lighting | no `<Renderer>` | [`whitted`] |
//! | Monte Carlo path tracing, the course's variants | `<Renderer>PathTracing</Renderer>`, `<RendererParams>` words | [`path`] |
//! | path tracing with multiple importance sampling | `<RendererParams>MIS</RendererParams>` | [`path`] |
//!
//! Both are pure functions of (scene, ray, per-sample state) and hand their
//! radiance to the render loop, which puts it on the film.

pub mod aov;
pub mod media;
pub mod path;
mod state;
pub mod tracking;
pub mod whitted;

pub use path::PathParams;
pub use state::{PathState, RayStats, MIN_WEIGHT, SECONDARY_BUDGET};

use std::borrow::Cow;

use crate::bsdf::closure::At;
use crate::light::{Light, LightSample};
use crate::material::Material;
use crate::render::scene::{Hit, Scene};
use crate::texture::{Applied, ShadeCtx};
use luster_core::math::{Ray, Vec3};
use luster_scene::description::RendererDesc;

/// The integrator of one camera: a closed set, matched per camera sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// The course's recursive ray tracer.
    Whitted,
    /// A path tracer.
    Path(PathParams),
}

impl Integrator {
    /// The integrator a camera's description asks for.
    pub fn from_desc(d: &RendererDesc) -> Integrator {
        match d {
            RendererDesc::Whitted => Integrator::Whitted,
            RendererDesc::PathTracing(p) => Integrator::Path(PathParams {
                next_event: p.next_event,
                importance: p.importance,
                russian_roulette: p.russian_roulette,
                mis: p.mis,
                lights: p.lights,
            }),
        }
    }

    /// Radiance arriving along the camera ray `ray`.
    #[inline]
    pub fn radiance(&self, scene: &Scene, ray: &Ray, st: &mut PathState) -> Vec3 {
        match self {
            Integrator::Whitted => whitted::radiance(scene, ray, 0, 1.0, st),
            Integrator::Path(p) => path::radiance(scene, ray, p, st),
        }
    }

    /// Whether [`Integrator::radiance_pair`] gains on two calls of
    /// [`Integrator::radiance`]: the path tracer's (see there). The
    /// recursive tracer's pair is two calls, so its render loop takes one
    /// sample at a time.
    #[inline]
    pub fn pairs(&self) -> bool {
        matches!(self, Integrator::Path(_))
    }

    /// [`Integrator::radiance`] of two camera rays, each with its state:
    /// the same two answers. The path tracer follows both paths in step
    /// ([`path::radiance_pair`]).
    #[inline]
    pub fn radiance_pair(
        &self,
        scene: &Scene,
        rays: [&Ray; 2],
        sa: &mut PathState,
        sb: &mut PathState,
    ) -> [Vec3; 2] {
        match self {
            Integrator::Whitted => [self.radiance(scene, rays[0], sa), self.radiance(scene, rays[1], sb)],
            Integrator::Path(p) => path::radiance_pair(scene, rays, p, sa, sb).map(Vec3::from),
        }
    }
}

/// What a surface is at a hit once its texture maps (and shaders) have
/// acted: its material and shading normal, or the colour an unlit map gives.
pub(crate) enum Surface<'a> {
    /// The material and unit shading normal (on the side of `ng`). A hit
    /// without maps borrows its scene material rather than copying it:
    /// most hits have none.
    Lit(Cow<'a, Material>, Vec3),
    /// A colour to show as it is.
    Unlit(Vec3),
    /// A shader failed; the failure is recorded in the path state.
    Failed,
}

/// Applies the hit object's texture maps to its material (see [`Surface`]).
/// Inlined is only the test for maps and the borrowed material of a hit
/// without any, the common case, so that such a hit costs the path tracer
/// no call.
#[inline(always)]
pub(crate) fn surface_at<'a>(
    scene: &'a Scene,
    ray: &Ray,
    hit: &Hit,
    depth: u32,
    st: &mut PathState,
) -> Surface<'a> {
    let material = &scene.materials[hit.material as usize];
    if hit.textures.is_empty() {
        return Surface::Lit(Cow::Borrowed(material), hit.ns);
    }
    textured(scene, ray, hit, depth, st)
}

/// [`surface_at`] for a hit with texture maps.
#[inline(never)]
fn textured<'a>(scene: &'a Scene, ray: &Ray, hit: &Hit, depth: u32, st: &mut PathState) -> Surface<'a> {
    let mut material = scene.materials[hit.material as usize];
    let mut ns = hit.ns;
    // The ray cone's width here, widened by the slant of the surface.
    let cos = ray.d.dot(hit.ns).abs().max(0.05);
    let footprint = st.spread * st.travelled / cos;
    let mut frame = scene.tex_frame(hit, ray, st.time, footprint);
    let (object, instance) = scene.object_ids(hit);
    let (incident, ng, pixel, view) = (ray.d.normalize(), hit.ng, st.pixel, st.view);
    // Built apart and stored whole: otherwise the footprint reads the camera
    // axes back from the frame just after they were stored there, narrower
    // than written, a load that waits for the stores to reach the cache.
    let mut ctx = ShadeCtx { incident, ng, object, instance, depth, pixel, view, ..ShadeCtx::default() };
    ctx.set_footprint(st.spread * st.travelled);
    frame.ctx = ctx;
    match scene.textures.apply(hit.textures, &frame, &mut material, &mut ns, &mut st.lobes) {
        Ok(Applied::Lit) => {}
        Ok(Applied::Unlit(c)) => return Surface::Unlit(c),
        Err(e) => {
            if st.error.is_none() {
                st.error = Some(Box::new((*e).with_object(scene.object_label(hit))));
            }
            return Surface::Failed;
        }
    }
    if ns.dot(hit.ng) < 0.0 {
        ns = -ns;
    }
    // Maps after the closure's may have bent the normal (the lobes' frame
    // holds it facing the viewer).
    if material.closure && st.lobes.frame.normal().dot(ns).abs() < 1.0 {
        st.lobes.reframe(&At::new(ns, hit.ng, st.lobes.frame.tangent(), ray.d.normalize()));
    }
    // The maps may have changed the colours, the model or the emission.
    material.refresh();
    Surface::Lit(Cow::Owned(material), ns)
}

/// What `light` sends to the surface point `p` with normal `n`, shadow rays
/// leaving from `origin` (`p` moved off the surface): the sample, `n·wi`,
/// and the transmittance along the shadow ray. `None` when the light is behind the surface, black or blocked.
/// Always inlined into its callers (the path tracer's light samples, the
/// recursive tracer's per-light term): its result returned through memory
/// would be read back in wider loads than it was stored with, a stall per
/// light sample.
#[inline(always)]
pub(crate) fn light_reaching_inline(
    scene: &Scene,
    light: &Light,
    origin: Vec3,
    p: Vec3,
    n: Vec3,
    st: &mut PathState,
) -> Option<(LightSample, f32, Vec3)> {
    let ls = light.sample(p, Some(n), st.time, &mut st.sampler)?;
    light_reaching_from(scene, light, ls, origin, p, n, st)
}

/// [`light_reaching_inline`] for the light sample `ls` already made.
#[inline(always)]
pub(crate) fn light_reaching_from(
    scene: &Scene,
    light: &Light,
    ls: LightSample,
    origin: Vec3,
    p: Vec3,
    n: Vec3,
    st: &mut PathState,
) -> Option<(LightSample, f32, Vec3)> {
    let cos = n.dot(ls.wi);
    if cos <= 0.0 || is_black(ls.e) {
        return None;
    }
    let (ray, t_max) = shadow_ray(scene, light, origin, p, &ls, st.time);
    let tr = media::shadow(scene, &ray, t_max, st);
    (!is_black(tr)).then_some((ls, cos, tr))
}

/// The shadow ray of the light sample `ls` of `light` drawn at `p` for a
/// ray at shutter `time`, leaving from `origin` (`p` moved off its
/// surface), and how far it reaches: aimed at the sampled point itself
/// where it is at a finite distance, so that the offset moves where the ray
/// starts, never what the sample measured. Seen from the offset origin, a
/// point near a sphere light's rim may lie just behind it: the ray then
/// stops where it enters the sphere.
#[inline(always)]
pub(crate) fn shadow_ray(
    scene: &Scene,
    light: &Light,
    origin: Vec3,
    p: Vec3,
    ls: &LightSample,
    time: f32,
) -> (Ray, f32) {
    if !ls.dist.is_finite() {
        return (Ray::new(origin, ls.wi), ls.dist);
    }
    let q = p + ls.wi * ls.dist;
    let (ray, mut dist) = aimed(origin, q);
    let d = ray.d;
    if let Light::Sphere(s) = light {
        dist = s.entry(origin - s.motion * time, d).map_or(dist, |t| t.min(dist));
    }
    let eps = scene.offset(q, origin);
    (ray, shadow_reach(&LightSample { dist, ..*ls }, eps))
}

/// The ray from `origin` towards `target`, and the distance between them.
#[inline(always)]
pub(crate) fn aimed(origin: Vec3, target: Vec3) -> (Ray, f32) {
    let to = target - origin;
    let dist = to.length();
    (Ray::new(origin, to / dist), dist)
}

/// How far the shadow ray of the light sample `ls` reaches, for the offset
/// `eps` at the light's end ([`Scene::offset`]). A point
/// source's reaches a little past it, so a light lying exactly on a surface
/// (hw2 mirror_room puts one in the ceiling plane) is blocked by it
/// consistently, as in the references, not by per-pixel rounding. An area
/// light's stops short of its own plane: it is an imaginary square, not
/// geometry, and a surface it lies on must not shadow it.
#[inline(always)]
pub(crate) fn shadow_reach(ls: &LightSample, eps: f32) -> f32 {
    if ls.point_source {
        ls.dist + eps
    } else {
        ls.dist - eps
    }
}

/// `v == Vec3::ZERO` without the branches of glam's derived `PartialEq`,
/// which tests the three components one after another: the same answer
/// (`-0.0` is zero, NaN is not).
#[inline(always)]
pub(crate) fn is_black(v: Vec3) -> bool {
    (v.x == 0.0) & (v.y == 0.0) & (v.z == 0.0)
}
