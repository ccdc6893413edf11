//! One vertex of a path: the shading frame its light samples and bounce
//! share ([`At`]), the BRDF's terms for a light sample, the random bounce
//! (uniform, cosine or BSDF-drawn, with Russian roulette) and the specular
//! part (mirrors, conductors, dielectrics) followed as the recursive tracer
//! does. Reads the material's BRDF and reflectances and the camera's
//! `<RendererParams>` (through [`PathParams`]).

use super::{li, past_limit, Bounce, Came, PathParams};
use crate::bsdf::fresnel;
use crate::bsdf::sampling::{power_cosine, power_cosine_pdf};
use crate::bsdf::{diffuse_pdf, Brdf, Frame};
use crate::integrator::whitted::{glossy, reflect, reflectance};
use crate::integrator::PathState;
use crate::material::{Material, Specular};
use crate::math::{Ray, Vec3, Vec3A};
use crate::render::dielectric::branch_weights;
use crate::render::scene::{Hit, Scene};

/// The shading point's frame, shared by its light samples and its bounce:
/// the facing shading normal `n`, the frame around it, the direction to the
/// viewer in that frame, the incoming ray's direction `d`, and for a
/// Phong-family BRDF without specular colour its value `f` for directions
/// above the surface (zero where the viewer is below it), the same for every
/// light sample and bounce. Where `f` is set, `wo` holds only its `z` (`x`
/// and `y` are zero): that BRDF's value, density and sample need no more, and
/// the two dot products cost ~25 instructions a path.
pub(super) struct At {
    pub(super) n: Vec3,
    pub(super) frame: Frame,
    pub(super) wo: Vec3,
    pub(super) d: Vec3,
    /// As `Vec3A`: read in a call right after it is written, and a `Vec3`
    /// went to memory as `x` alone and `y, z` together, which a wider read
    /// cannot be forwarded from (see [`super::next_event::next_event`]).
    pub(super) f: Option<Vec3A>,
}

impl At {
    #[inline(always)]
    pub(super) fn new(m: &Material, n: Vec3, d: Vec3) -> At {
        let frame = Frame::new(n);
        // [`PhongFamily::eval_diffuse`]'s test of the viewer's cosine. The
        // local `z` of `-d` is `-d·n`, as [`Frame::to_local`] works it out.
        let (wo, f) = match m.traits.phong_diffuse {
            Some(f) => {
                let z = (-d).dot(n);
                (Vec3::new(0.0, 0.0, z), Some(Vec3A::from(if z <= 0.0 { Vec3::ZERO } else { f })))
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
pub(super) fn light_terms(m: &Material, at: &At, wi: Vec3, cos: f32, p: PathParams) -> (Vec3, f32) {
    match &m.brdf {
        Some(b) if p.mis => {
            // Without a lobe only the cosines count: the local `z` of `wi` is
            // `n·wi`, the bits of `cos`.
            if let (true, Some(f)) = (m.traits.diffuse_only, at.f) {
                return (Vec3::from(f) * cos, diffuse_pdf(at.wo.z, cos));
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
        Some(f) => Vec3::from(f) * cos,
        None => b.eval(m.diffuse, m.specular, at.frame.to_local(wi), at.wo) * cos,
    }
}

/// The random bounce: a direction drawn as the variant says, its weight
/// `f cos / p`, and Russian roulette when asked for; `None` where it brings
/// no light (its light would count as zero). Inlined into [`shade`] (see
/// there).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn bounce(
    scene: &Scene,
    m: &Material,
    at: &At,
    origin: Vec3,
    depth: u32,
    beta: Vec3,
    p: PathParams,
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
    Some(Bounce { ray, weight, q, next, came: Came::Bounce { pdf, n } })
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
    let eps = scene.shadow_epsilon;
    let cos_i = -ray.d.dot(n);
    let r = m.roughness;
    let trace = |st: &mut PathState, o: Vec3, d: Vec3, k: Vec3| -> Vec3 {
        let next = beta * k;
        if !st.spawn(next.max_element()) {
            return Vec3::ZERO;
        }
        k * li::<V>(scene, &Ray::new(o, d), depth + 1, next, Came::Direct, p, st)
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
            // One of the two rays, by Fresnel probability (both at one
            // sample per pixel): see `render::dielectric`. Splitting made a
            // tree of every path through glass, which Russian roulette then
            // followed in full: the hw7 glass box's roulette cameras took
            // 1.5–1.8× the diffuse box's.
            let (wr, wt) = branch_weights(f, cos_t.is_some(), &mut st.sampler);
            let mut c = Vec3::ZERO;
            if wr > 0.0 {
                let d = glossy(reflect(ray.d, n), r, st);
                c = trace(st, hit.p + ng * eps, d, Vec3::splat(wr));
            }
            if let (Some(cos_t), true) = (cos_t, wt > 0.0) {
                let eta = n1 / n2;
                let d = glossy((ray.d * eta + n * (eta * cos_i - cos_t)).normalize(), r, st);
                c += trace(st, hit.p - ng * eps, d, Vec3::splat(wt));
            }
            c
        }
    }
}

#[cfg(test)]
#[path = "vertex_tests.rs"]
mod tests;
