//! Light through volumes: how the integrators' rays meet hypertexture
//! surfaces, how shadow rays are attenuated, and, for the recursive ray
//! tracer, single scattering in media by ray marching. The path tracer
//! tracks media instead ([`super::tracking`], `docs/volumes.md`); its
//! shadow rays come here and are attenuated by ratio tracking.
//!
//! # Ray marching
//!
//! Where a ray crosses media (up to the surface it hits), the crossed span is
//! cut where any medium begins or ends, and each piece is walked in equal
//! steps no longer than the smallest `StepSize` of the media there, with one
//! jittered offset per ray (turning banding into noise that more samples
//! average out). At each sample point `p`, with density `ρ` summed over the
//! media present:
//!
//! * extinction `σt = ρ (σa + σs)`; the step's transmittance `exp(−σt Δ)`;
//! * in-scattering `S = ρ σs · (Σ_lights π p_HG(cos θ) L_i T_i + A)`: each
//!   point light's `I/d²` (one sample of each area light), attenuated by the
//!   shadow transmittance `T_i` (surfaces block, media attenuate), the
//!   Henyey–Greenstein phase function times π — the course's convention,
//!   under which a diffuse reflectance of 1 returns `E cos θ` — and the
//!   scene's ambient light `A`;
//! * emission `ε` (the script's `emission(s)`, or `Emission · ρ`).
//!
//! With `ScatteringOctaves` n > 1 the light term adds n − 1 terms of the
//! multiple-scattering approximation of Wrenninge et al. ("Oz: The Great and
//! Volumetric", 2013): term k has `2⁻ᵏ σs`, sees the light through `T_i^(2⁻ᵏ)`
//! and has asymmetry `2⁻ᵏ g`, standing in for light that scattered more than
//! once — what makes thick clouds white rather than grey. It is not energy
//! conserving and not physically based; 1 (the default) is plain single
//! scattering.
//!
//! Radiance gathers `T (S + ε) (1 − e^{−σt Δ}) / σt` per step (the exact
//! integral for constant values over the step) and the transmittance `T` is
//! multiplied by the step's, so through a homogeneous medium `T` is exactly
//! `exp(−σt d)` whatever the step. The surface behind contributes `T L`.
//! Marching stops once `T` falls below [`MIN_TRANSMITTANCE`].
//!
//! Shadow rays through a homogeneous medium use that closed form; through a
//! scripted one they take midpoint steps twice as long as the medium's.

use super::{tracking, PathState};
use crate::render::scene::{Hit, HitGeom, Scene};
use crate::volume::{steps, Kind, Probe, Volume};
use luster_core::math::{Ray, Vec3};
use std::f32::consts::PI;

/// Transmittance below which a ray is considered absorbed (its remaining
/// contribution is under a thousandth of an 8-bit level for lights of the
/// course's range).
pub const MIN_TRANSMITTANCE: f32 = 1e-4;

/// The closest surface or hypertexture hit along `ray`. Inlined, so that a
/// scene without hypertextures (every path-traced course scene) pays a
/// length test, not a call, per ray.
#[inline]
pub fn trace(scene: &Scene, ray: &Ray, cull_back_faces: bool, st: &mut PathState) -> Option<Hit> {
    if scene.volumes.surfaces.is_empty() {
        // Straight into the caller's slot: a hit kept in a local and copied
        // out would be read back in wide loads before the narrow stores that
        // wrote it had landed.
        return scene.intersect(ray, st.time, cull_back_faces);
    }
    trace_surfaces(scene, ray, cull_back_faces, st)
}

/// [`trace`] in a scene with hypertexture surfaces.
#[inline(never)]
fn trace_surfaces(scene: &Scene, ray: &Ray, cull_back_faces: bool, st: &mut PathState) -> Option<Hit> {
    let vols = &scene.volumes;
    let hit = scene.intersect(ray, st.time, cull_back_faces);
    let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.t);
    match vols.surface_hit(ray, scene.intersection_epsilon, t_max, &probe(ray, st)) {
        Ok(Some(c)) => {
            let v = &vols.surfaces[c.index];
            let Kind::Surface { material, textures, .. } = v.kind else { return hit };
            Some(Hit {
                t: c.t,
                p: ray.at(c.t),
                ng: c.normal,
                ns: c.normal,
                material,
                textures,
                geom: HitGeom::Volume(c.index as u32),
            })
        }
        Ok(None) => hit,
        Err(e) => {
            st.fail(e);
            hit
        }
    }
}

/// How much light gets through along the shadow ray `ray` up to `t_max`:
/// zero when a surface or hypertexture blocks it, else the media's
/// transmittance. Inlined: without volumes it is the occlusion test alone.
#[inline]
pub fn shadow(scene: &Scene, ray: &Ray, t_max: f32, st: &mut PathState) -> Vec3 {
    st.stats.shadow += 1;
    if scene.occluded(ray, t_max, st.time) {
        return Vec3::ZERO;
    }
    let vols = &scene.volumes;
    if vols.surfaces.is_empty() && !vols.has_media() {
        return Vec3::ONE;
    }
    shadow_volumes(scene, ray, t_max, st)
}

/// [`shadow`] past the surfaces, in a scene with volumes.
#[inline(never)]
fn shadow_volumes(scene: &Scene, ray: &Ray, t_max: f32, st: &mut PathState) -> Vec3 {
    let vols = &scene.volumes;
    if !vols.surfaces.is_empty() {
        match vols.surface_blocks(ray, scene.intersection_epsilon, t_max, &probe(ray, st)) {
            Ok(true) => return Vec3::ZERO,
            Ok(false) => {}
            Err(e) => {
                st.fail(e);
                return Vec3::ZERO;
            }
        }
    }
    media_transmittance(scene, ray, t_max, st)
}

/// The transmittance of every medium along `ray` up to `t_max`, without
/// scattering: what reaches the ray's origin of light from `t_max`.
pub fn media_transmittance(scene: &Scene, ray: &Ray, t_max: f32, st: &mut PathState) -> Vec3 {
    let mut tr = Vec3::ONE;
    // A path tracer's shadow ray stays inside the object it starts in
    // (every surface blocks it): its interior's transmittance is exact.
    if let Some(m) = st.interior.and_then(|i| scene.volumes.interiors.get(i as usize)) {
        tr = (-(m.absorption + m.scattering) * t_max).exp();
    }
    for v in &scene.volumes.media {
        tr *= transmittance(scene, v, ray, 0.0, t_max, st);
        // Tracking's estimates are unbiased as they are (they play Russian
        // roulette themselves); cutting them off would darken.
        if !st.tracking && tr.max_element() < MIN_TRANSMITTANCE {
            return Vec3::ZERO;
        }
    }
    tr
}

/// Transmittance through medium `v` along `ray` between `t_lo` and `t_hi`.
fn transmittance(scene: &Scene, v: &Volume, ray: &Ray, t_lo: f32, t_hi: f32, st: &mut PathState) -> Vec3 {
    let Some((t0, t1)) = v.bound.interval(ray) else { return Vec3::ONE };
    let (a, b) = (t0.max(t_lo), t1.min(t_hi));
    if a >= b {
        return Vec3::ONE;
    }
    let Kind::Medium { absorption, scattering, .. } = v.kind else { return Vec3::ONE };
    let sigma_t = absorption + scattering;
    if let Some(rho) = v.constant_density() {
        return (-sigma_t * (rho * (b - a))).exp();
    }
    // The path tracer's estimate must be unbiased; the recursive tracer's
    // smooth.
    if st.tracking && v.majorant.is_some() {
        return tracking::ratio_tracked(scene, v, ray, a, b, st);
    }
    let n = steps(b - a, 2.0 * v.step);
    let dt = (b - a) / n as f32;
    let mut depth = 0.0;
    let pr = probe(ray, st);
    for k in 0..n {
        match v.density(&scene.volumes, ray.at(a + (k as f32 + 0.5) * dt), &pr) {
            Ok(rho) => depth += rho * dt,
            Err(e) => {
                st.fail(e.with_object(&v.label));
                return Vec3::ZERO;
            }
        }
        if (sigma_t * depth).min_element() > -MIN_TRANSMITTANCE.ln() {
            return Vec3::ZERO;
        }
    }
    (-sigma_t * depth).exp()
}

/// The radiance arriving at `ray`'s origin when `behind` arrives from
/// `t_end` (a surface's radiance, or the background at infinity): what the
/// media in between absorb, scatter in and emit.
///
/// Inlined: without media it returns `behind`, and the call is not made.
#[inline]
pub fn through_media(scene: &Scene, ray: &Ray, t_end: f32, behind: Vec3, st: &mut PathState) -> Vec3 {
    if scene.volumes.media.is_empty() {
        return behind;
    }
    march(scene, ray, t_end, behind, st)
}

/// [`through_media`] where the scene has media.
#[inline(never)]
fn march(scene: &Scene, ray: &Ray, t_end: f32, behind: Vec3, st: &mut PathState) -> Vec3 {
    let media = &scene.volumes.media;
    // Spans of each medium on the ray, and every place one begins or ends.
    let mut spans: Vec<(f32, f32, usize)> = Vec::new();
    let mut cuts: Vec<f32> = Vec::new();
    for (i, v) in media.iter().enumerate() {
        if let Some((t0, t1)) = v.bound.interval(ray) {
            let (a, b) = (t0.max(0.0), t1.min(t_end));
            if a < b {
                spans.push((a, b, i));
                cuts.extend([a, b]);
            }
        }
    }
    if spans.is_empty() {
        return behind;
    }
    cuts.sort_by(f32::total_cmp);
    cuts.dedup();
    let jitter = st.sampler.next_1d();
    let pr = probe(ray, st);
    let mut radiance = Vec3::ZERO;
    let mut tr = Vec3::ONE;
    let mut active: Vec<usize> = Vec::with_capacity(spans.len());
    // Per scattering medium at a sample point: σs·ρ, g, octaves (reused).
    let mut scatter: Vec<(Vec3, f32, u32)> = Vec::with_capacity(spans.len());
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        active.clear();
        active.extend(spans.iter().filter(|s| s.0 <= a && s.1 >= b).map(|s| s.2));
        if active.is_empty() {
            continue;
        }
        let step = active.iter().map(|&i| media[i].step).fold(f32::INFINITY, f32::min);
        let n = steps(b - a, step);
        let dt = (b - a) / n as f32;
        for k in 0..n {
            let p = ray.at(a + (k as f32 + jitter) * dt);
            let (sigma_t, source) = match point(scene, &active, &mut scatter, p, &pr, st) {
                Some(x) => x,
                None => return Vec3::ZERO,
            };
            let step_tr = (-sigma_t * dt).exp();
            // ∫₀^Δ e^{−σt s} ds, per channel; Δ where σt vanishes.
            let weight = Vec3::select(
                sigma_t.cmpgt(Vec3::splat(1e-6)),
                (Vec3::ONE - step_tr) / sigma_t,
                Vec3::splat(dt),
            );
            radiance += tr * source * weight;
            tr *= step_tr;
            if tr.max_element() < MIN_TRANSMITTANCE {
                return radiance;
            }
        }
    }
    radiance + tr * behind
}

/// Extinction and source (in-scattering plus emission) at `p` for a ray
/// travelling along `d`, summed over the `active` media; `None` after a
/// script failed (recorded in `st`).
fn point(
    scene: &Scene,
    active: &[usize],
    scatter: &mut Vec<(Vec3, f32, u32)>,
    p: Vec3,
    pr: &Probe,
    st: &mut PathState,
) -> Option<(Vec3, Vec3)> {
    let d = pr.dir;
    let vols = &scene.volumes;
    let mut sigma_t = Vec3::ZERO;
    let mut emitted = Vec3::ZERO;
    scatter.clear();
    for &i in active {
        let v = &vols.media[i];
        let Kind::Medium { absorption, scattering, anisotropy, octaves, .. } = v.kind else { continue };
        let rho = match v.density(vols, p, pr).and_then(|rho| Ok((rho, v.emission(vols, p, pr, rho)?))) {
            Ok((rho, e)) => {
                emitted += e;
                rho
            }
            Err(e) => {
                st.fail(e.with_object(&v.label));
                return None;
            }
        };
        if rho <= 0.0 {
            continue;
        }
        sigma_t += (absorption + scattering) * rho;
        let s = scattering * rho;
        if s.max_element() > 0.0 {
            scatter.push((s, anisotropy, octaves));
        }
    }
    let scatter = &scatter[..];
    let total_s = scatter.iter().map(|s| s.0).sum::<Vec3>();
    if total_s.max_element() <= 0.0 {
        return Some((sigma_t, emitted));
    }
    let mut inscatter = total_s * scene.ambient;
    let eps = scene.offset(p, p);
    let mut light = |l: Vec3, dist: f32, e: Vec3, st: &mut PathState| {
        let tr = shadow(scene, &Ray::new(p, l), dist - eps, st);
        if tr.max_element() <= 0.0 {
            return;
        }
        let cos = l.dot(d);
        let mut f = Vec3::ZERO;
        for &(s, g, octaves) in scatter {
            f += s * (PI * henyey_greenstein(cos, g)) * tr;
            // The multiple-scattering approximation: octave k scatters 2⁻ᵏ as
            // much, sees 2⁻ᵏ of the optical depth to the light, and is 2⁻ᵏ as
            // anisotropic.
            let mut k_scale = 1.0;
            for _ in 1..octaves {
                k_scale *= 0.5;
                f += s * (k_scale * PI * henyey_greenstein(cos, g * k_scale)) * tr.powf(k_scale);
            }
        }
        inscatter += f * e;
    };
    for l in &scene.lights {
        if let Some(ls) = l.sample(p, None, st.time, &mut st.sampler) {
            light(ls.wi, ls.dist, ls.e, st);
        }
    }
    if st.error.is_some() {
        return None;
    }
    Some((sigma_t, inscatter + emitted))
}

/// What the volume scripts see of `ray`, marched for the camera sample of `st`.
#[inline]
fn probe(ray: &Ray, st: &PathState) -> Probe {
    // Rays are unit length here (camera, reflected, refracted and shadow rays are made so).
    Probe { time: st.time, dir: ray.d, view: st.view, pixel: st.pixel }
}

/// The Henyey–Greenstein phase function of the scattering angle θ, normalized
/// over the sphere. Light arrives travelling along −l (l points to the light)
/// and leaves towards the eye along −d (d is the ray's direction), so
/// `cos θ = l · d`: forward scattering (g > 0) brightens a medium seen with
/// the light behind it.
#[inline]
pub fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}
