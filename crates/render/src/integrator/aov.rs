//! What a camera ray's first hit gives the render passes
//! ([`crate::film::aov`]): traced apart from the beauty path, and only
//! when passes are asked for, so a render without them pays nothing.
//!
//! The albedo follows perfect mirrors and smooth glass (a material with a
//! specular part, no roughness and no diffuse colour) up to
//! [`MAX_FOLLOW`] times, as Cycles' denoising albedo does, so that a
//! denoiser sees the texture behind the glass rather than a flat colour;
//! the other passes are the first hit's.

use super::{media, surface_at, PathState, Surface};
use crate::bsdf::fresnel;
use crate::bsdf::specular::{reflect, refract};
use crate::bsdf::Specular;
use crate::film::aov::AovSample;
use crate::material::Material;
use crate::render::scene::Scene;
use luster_core::math::{Ray, Vec3};

/// Most perfectly specular surfaces the albedo is followed through.
pub const MAX_FOLLOW: u32 = 8;

/// The passes' view of the camera ray `ray`, shaded with `st` (its pixel,
/// time and view; its sampler is not drawn from). A shader failure is
/// recorded in `st` as the beauty path records it.
pub fn first_hit(scene: &Scene, ray: &Ray, st: &mut PathState) -> AovSample {
    let mut out = AovSample::BACKGROUND;
    let mut r = *ray;
    let mut tint = Vec3::ONE;
    st.travelled = 0.0;
    for depth in 0..=MAX_FOLLOW {
        let Some(hit) = media::trace(scene, &r, depth == 0, st) else { break };
        let facing = |n: Vec3| if r.d.dot(n) > 0.0 { -n } else { n };
        if depth == 0 {
            out.depth = hit.t * r.d.length();
            out.position = hit.p;
            out.object = scene.object_ids(&hit).1 + 1;
            out.normal = facing(hit.ns);
            if let Some((_, le)) = scene.emitted(&hit, r.d) {
                out.emission += le;
            }
        }
        st.travelled += hit.t * r.d.length();
        let (m, ns) = match surface_at(scene, &r, &hit, depth, st) {
            Surface::Lit(m, ns) => (*m, ns),
            Surface::Unlit(c) => {
                if depth == 0 {
                    out.emission += c;
                }
                break;
            }
            Surface::Failed => break,
        };
        let n = facing(ns);
        if depth == 0 {
            out.normal = n;
            out.emission += m.emission;
        }
        let delta = !m.closure
            && m.roughness == 0.0
            && m.diffuse == Vec3::ZERO
            && !matches!(m.kind, Specular::None)
            && depth < MAX_FOLLOW;
        if !delta {
            out.albedo = tint * albedo(&m, st);
            break;
        }
        let d = r.d.normalize();
        let ng = facing(hit.ng);
        let eps = scene.offset(hit.p, r.o);
        let (dir, origin) = match m.kind {
            Specular::Dielectric { ior, .. } => {
                let entering = d.dot(hit.ng) < 0.0;
                let (n1, n2) = if entering { (1.0, ior) } else { (ior, 1.0) };
                let cos_i = -d.dot(n);
                match fresnel::dielectric(cos_i, n1, n2) {
                    (_, Some(cos_t)) => (refract(d, n, n1 / n2, cos_i, cos_t), hit.p - ng * eps),
                    (_, None) => (reflect(d, n), hit.p + ng * eps),
                }
            }
            _ => {
                tint *= m.mirror;
                (reflect(d, n), hit.p + ng * eps)
            }
        };
        r = Ray::new(origin, dir);
    }
    out
}

/// A non-specular surface's reflectance, each channel in [0, 1]: a
/// closure's lobes' albedos for the viewer's direction, weighted; a plain
/// material's diffuse colour, or its specular colour where it has none (a
/// glossy-only surface), or its mirror colour where it has neither (a rough
/// mirror or conductor), 1 for rough glass.
fn albedo(m: &Material, st: &PathState) -> Vec3 {
    let a = if m.closure {
        let lobes = &st.lobes;
        (0..lobes.len()).fold(Vec3::ZERO, |a, k| {
            let (lobe, weight) = lobes.lobe(k);
            a + weight * lobe.albedo(lobes.wo)
        })
    } else if m.diffuse != Vec3::ZERO {
        m.diffuse
    } else if m.specular != Vec3::ZERO {
        m.specular
    } else {
        match m.kind {
            Specular::None => Vec3::ZERO,
            Specular::Dielectric { .. } => Vec3::ONE,
            Specular::Mirror | Specular::Conductor { .. } => m.mirror,
        }
    };
    a.clamp(Vec3::ZERO, Vec3::ONE)
}
