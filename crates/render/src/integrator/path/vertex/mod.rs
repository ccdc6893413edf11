//! One vertex of a path: the random bounce (uniform, cosine or BSDF-drawn by
//! the vertex's [`Bsdf`], with Russian roulette) and the specular part
//! (mirrors, conductors, dielectrics) followed as the recursive tracer does.
//! Reads the camera's `<RendererParams>` (through [`PathParams`]).

use super::{across, li, past_limit, Bounce, Came, PathParams};
use crate::bsdf::specular::{branch_weights, glossy, reflect, refract};
use crate::bsdf::{fresnel, Bsdf, BsdfSample, Specular};
use crate::integrator::PathState;
use crate::material::Material;
use crate::render::scene::{Hit, Scene};
use luster_core::math::{Ray, Vec3};

/// The random bounce: a direction drawn as the variant says, its weight
/// `f cos / p`, and Russian roulette when asked for, from the surface point
/// `from` (the ray leaves from `origin`, `from` moved off the surface);
/// `None` where it brings no light (its light would count as zero). Inlined into [`shade`] (see
/// there).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn bounce(
    scene: &Scene,
    bsdf: &Bsdf,
    from: Vec3,
    origin: Vec3,
    depth: u32,
    beta: Vec3,
    p: PathParams,
    st: &mut PathState,
) -> Option<Bounce> {
    // Only an MIS bounce off a BRDF chooses a lobe; the others skip the
    // draw (a stratified one at the first hit), keeping the later ones.
    let choice = if p.mis && bsdf.material().brdf.is_some() {
        st.sampler.next_1d()
    } else {
        st.sampler.skip();
        0.0
    };
    let u = st.sampler.next_2d();
    let BsdfSample { wi, pdf, f_cos } = bsdf.sample(p.strategy(), choice, u)?;
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
    // So does the bounce to the last vertex of a course variant that
    // samples no lights: that vertex only adds the light it finds (its
    // specular rays and bounce would pass the limit). Where that light can
    // only come from emitters the ray misses, its trace would add zero.
    let to_last = !p.next_event && !p.mis && !p.russian_roulette && depth + 1 == scene.max_depth;
    if to_last && !scene.may_bring_light(&ray) {
        return None;
    }
    if !st.spawn(next.max_element()) {
        return None;
    }
    Some(Bounce { ray, weight, q, next, came: Came::Bounce { pdf, n: bsdf.n, from } })
}

/// [`bounce`] off a shader closure: a lobe is always chosen, and a
/// direction through the surface leaves from its far side (`p − off`
/// rather than `p + off`, `off` the viewer's side's offset).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(super) fn bounce_through(
    scene: &Scene,
    bsdf: &Bsdf,
    p_hit: Vec3,
    off: Vec3,
    depth: u32,
    beta: Vec3,
    p: PathParams,
    st: &mut PathState,
) -> Option<Bounce> {
    let choice = st.sampler.next_1d();
    let u = st.sampler.next_2d();
    let BsdfSample { wi, pdf, f_cos } = bsdf.sample(p.strategy(), choice, u)?;
    let weight = f_cos / pdf;
    if !weight.is_finite() || pdf <= 0.0 {
        return None;
    }
    let next = beta * weight;
    let mut q = 1.0;
    if p.russian_roulette {
        q = next.max_element().min(1.0);
        if st.sampler.next_1d() >= q {
            return None;
        }
    }
    let origin = if wi.dot(off) >= 0.0 { p_hit + off } else { p_hit - off };
    let ray = Ray::new(origin, wi);
    if past_limit(scene, depth + 1, p) && !scene.may_find_emission(&ray) {
        return None;
    }
    if !st.spawn(next.max_element()) {
        return None;
    }
    Some(Bounce { ray, weight, q, next, came: Came::Bounce { pdf, n: bsdf.n, from: p_hit } })
}

/// Mirror, conductor and dielectric rays, as the recursive ray tracer sends
/// them (with its glossy roughness), each weighted by its reflectance.
#[allow(clippy::too_many_arguments)]
pub(super) fn specular<const V: u8>(
    scene: &Scene,
    m: &Material,
    hit: &Hit,
    n: Vec3,
    ng: Vec3,
    ray: &Ray,
    entering: bool,
    depth: u32,
    beta: Vec3,
    p: PathParams,
    st: &mut PathState,
) -> Vec3 {
    let eps = scene.offset(hit.p, ray.o);
    let cos_i = -ray.d.dot(n);
    let r = m.roughness;
    let trace = |st: &mut PathState, o: Vec3, d: Vec3, k: Vec3| -> Vec3 {
        let next = beta * k;
        if !st.spawn(next.max_element()) {
            return Vec3::ZERO;
        }
        // A refracted ray enters or leaves the object's medium.
        k * across(scene, hit, ray.d, d, st, |st| {
            li::<V>(scene, &Ray::new(o, d), depth + 1, next, Came::Direct, p, st)
        })
    };
    match m.kind {
        Specular::None => Vec3::ZERO,
        Specular::Mirror => {
            let d = glossy(reflect(ray.d, n), r, &mut st.sampler);
            trace(st, hit.p + ng * eps, d, m.mirror)
        }
        Specular::Conductor { n: eta, k } => {
            let f = fresnel::conductor(cos_i, eta, k);
            let d = glossy(reflect(ray.d, n), r, &mut st.sampler);
            trace(st, hit.p + ng * eps, d, m.mirror * f)
        }
        Specular::Dielectric { ior, .. } => {
            let (n1, n2) = if entering { (1.0, ior) } else { (ior, 1.0) };
            let (f, cos_t) = fresnel::dielectric(cos_i, n1, n2);
            // One of the two rays, by Fresnel probability (both at one
            // sample per pixel): see `bsdf::specular`. Splitting would make
            // a tree of every path through glass, which Russian roulette
            // then follows in full.
            let (wr, wt) = branch_weights(f, cos_t.is_some(), &mut st.sampler);
            let mut c = Vec3::ZERO;
            if wr > 0.0 {
                let d = glossy(reflect(ray.d, n), r, &mut st.sampler);
                c = trace(st, hit.p + ng * eps, d, Vec3::splat(wr));
            }
            if let (Some(cos_t), true) = (cos_t, wt > 0.0) {
                let eta = n1 / n2;
                let d = glossy(refract(ray.d, n, eta, cos_i, cos_t), r, &mut st.sampler);
                c += trace(st, hit.p - ng * eps, d, Vec3::splat(wt));
            }
            c
        }
    }
}

#[cfg(test)]
mod tests;
