//! Warps from the unit square to directions around the local `+z` axis, with
//! their densities (per unit solid angle). Shared by every BRDF's sampler.

use luster_core::math::{orthonormal_basis, sin_cos_turns, Vec3};
use std::f32::consts::FRAC_1_PI;

/// A direction drawn with density `(e + 1) / 2π · cos^e θ` about `+z`
/// (`e = 0`: uniform, `e = 1`: cosine-weighted). `θ` never exceeds 90°.
#[inline]
pub fn power_cosine(e: f32, u: (f32, f32)) -> Vec3 {
    power_cosine_inline(e, u)
}

/// [`power_cosine`] at `e = 1`: a cosine-weighted direction, always
/// inlined. Every diffuse bounce under MIS draws one, where LLVM would
/// otherwise leave a call to [`power_cosine`].
#[inline(always)]
pub fn cosine_weighted(u: (f32, f32)) -> Vec3 {
    power_cosine_inline(1.0, u)
}

/// [`power_cosine`]'s body.
#[inline(always)]
fn power_cosine_inline(e: f32, (u1, u2): (f32, f32)) -> Vec3 {
    // Uniform and cosine-weighted bounces, the path tracer's every bounce,
    // without a libm `powf` call (`sqrt` is one instruction; it and
    // `powf(u, ½)` differ in the last bit for a few floats).
    let cos = match e {
        0.0 => u1,
        1.0 => u1.sqrt(),
        _ => u1.powf(1.0 / (e + 1.0)),
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (sp, cp) = sin_cos_turns(u2);
    Vec3::new(sin * cp, sin * sp, cos)
}

/// Density of [`power_cosine`] at a direction whose cosine to the axis is `cos`.
#[inline]
pub fn power_cosine_pdf(e: f32, cos: f32) -> f32 {
    if cos <= 0.0 {
        return 0.0;
    }
    // The uniform and cosine densities need no `powf` (a libm call on every
    // bounce): `x⁰ = 1` and `x¹ = x` exactly, so the value is the same.
    let c = match e {
        0.0 => 1.0,
        1.0 => cos,
        _ => cos.powf(e),
    };
    (e + 1.0) * 0.5 * FRAC_1_PI * c
}

/// [`power_cosine`] about an arbitrary unit `axis` instead of `+z`.
#[inline]
pub fn power_cosine_about(axis: Vec3, e: f32, u: (f32, f32)) -> Vec3 {
    let (t, b) = orthonormal_basis(axis);
    let v = power_cosine(e, u);
    t * v.x + b * v.y + axis * v.z
}

/// Mirror image of `w` about the local normal `+z`.
#[inline]
pub fn reflect_z(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// `wo` reflected about the half vector `h`.
#[inline]
pub fn reflect_about(wo: Vec3, h: Vec3) -> Vec3 {
    h * (2.0 * wo.dot(h)) - wo
}

/// Density of the direction `wi = reflect_about(wo, h)` when `h` has density
/// `pdf_h`: the Jacobian of the reflection, `1 / (4 |wo·h|)`.
#[inline]
pub fn half_vector_pdf(pdf_h: f32, wo: Vec3, h: Vec3) -> f32 {
    let c = wo.dot(h).abs();
    if c <= 0.0 {
        return 0.0;
    }
    pdf_h / (4.0 * c)
}
