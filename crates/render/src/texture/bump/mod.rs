//! Normal mapping and bump mapping.
//!
//! A normal map's texel is a direction in the tangent frame `(T, B, N)`:
//! `T` along ∂p/∂u, `B` along ∂p/∂v, both unit length, `N` the shading normal.
//!
//! Bump mapping treats the map as a height `h` that displaces the surface
//! along its normal, `p' = p + k h n` for the map's `BumpFactor` `k`, and
//! shades with the displaced surface's normal. To first order (Blinn 1978),
//! `∂p'/∂u ≈ ∂p/∂u + k (∂h/∂u) n` and likewise for `v`, and the new normal is
//! their cross product, turned to the side of the old one.
//!
//! - For an image, the course's convention, which its references pin down:
//!   `h` is the mean channel of the texel containing the point, in 8-bit
//!   units (0–255, whatever the `Normalizer`), and `∂h/∂u`, `∂h/∂v` are
//!   forward differences to the next texel right and down — per texel, not
//!   per unit of `u` — whatever the map's `Interpolation`. hw4 `wood_box_all`
//!   matches this, and none of bilinear heights, central differences or
//!   derivatives per unit of `u`.
//!   The space the surface is displaced in is the one the course's references
//!   show per kind of object, as for Perlin noise: object space on meshes,
//!   world space (tangents `M ∂p/∂u`, normal `M⁻ᵀ n`) on spheres and
//!   ellipsoids. They differ under a non-uniform scale, where a height step
//!   tilts the normal less along a stretched tangent. hw4
//!   `bump_mapping_transformed` (an ellipsoid scaled by (-2, 1, 1) over a
//!   plane scaled by 0.05) shows it: object space everywhere makes the bumps
//!   too strong at the ellipsoid's stretched ends, world space everywhere the
//!   plane's bumps 20 times too strong.
//! - For Perlin noise, `h` is a function of the position at rest (see
//!   [`TexFrame::p_rest`]), so its gradient `g` is used directly: the
//!   component of `g` along the surface tilts the normal,
//!   `n' = normalize(n − k (g − (g·n) n))`, in the space the noise lives in
//!   (object space on meshes: hw4 `cube_perlin_bump`, scaled by 0.8, matches
//!   this rather than the world-space gradient `M⁻ᵀ g`).
//! - For a shader's `height(s)`, see [`height_bump`]: forward differences
//!   along the surface's own tangents, three calls per point.

use super::{TexFrame, Texture, TextureMap, Textures};
use luster_core::math::{Vec2, Vec3};

/// The shading normal a normal map's tangent-space direction `t` (components
/// in [-1, 1]) gives.
pub fn normal_map(f: &TexFrame, t: Vec3) -> Vec3 {
    let (tu, tv) = tangents(f);
    (tu * t.x + tv * t.y + f.n * t.z).try_normalize().unwrap_or(f.n)
}

/// Unit tangents along u and v, falling back to any frame around the normal
/// when the parameterization degenerates.
fn tangents(f: &TexFrame) -> (Vec3, Vec3) {
    match (f.dpdu.try_normalize(), f.dpdv.try_normalize()) {
        (Some(tu), Some(tv)) => (tu, tv),
        _ => luster_core::math::orthonormal_basis(f.n),
    }
}

/// The bump-mapped shading normal for `map` at `f`, in world space.
pub fn bump(tex: &Textures, map: &TextureMap, f: &TexFrame) -> Vec3 {
    let k = map.bump_factor;
    if k == 0.0 {
        return f.normal_to_world(f.n);
    }
    match map.texture {
        Texture::Perlin(p) => {
            let (_, g) = p.value_grad(f.p_rest, true);
            // The gradient's space is the noise's: tilt the normal there.
            let n = if f.rest_in_object { f.n } else { f.normal_to_world(f.n) };
            let along = g - n * g.dot(n);
            let bumped = (n - along * k).try_normalize().unwrap_or(n);
            if f.rest_in_object {
                f.normal_to_world(bumped)
            } else {
                bumped
            }
        }
        Texture::Image { image, .. } => {
            let img = &tex.images[image as usize];
            let (w, h) = img.size();
            // Heights in 8-bit units whatever the file's precision.
            let unit = if img.is_hdr() { 255.0 / 3.0 } else { 1.0 / 3.0 };
            let height = |uv: Vec2| img.nearest(uv).element_sum() * unit;
            let h0 = height(f.uv);
            let hu = height(f.uv + Vec2::new(1.0 / w as f32, 0.0)) - h0;
            let hv = height(f.uv + Vec2::new(0.0, 1.0 / h as f32)) - h0;
            match (&f.to_world, f.rest_in_object) {
                // Spheres and ellipsoids are bumped with their world-space
                // tangents and normal, meshes in object space (see above).
                (Some(xf), false) => {
                    let n = f.normal_to_world(f.n);
                    displaced_normal(xf.vector(f.dpdu), xf.vector(f.dpdv), n, k * hu, k * hv)
                }
                _ => f.normal_to_world(displaced_normal(f.dpdu, f.dpdv, f.n, k * hu, k * hv)),
            }
        }
        // Piecewise constant: no slope anywhere but on the edges.
        Texture::Checkerboard(_) => f.normal_to_world(f.n),
        // Shader maps are bumped by `Textures::apply_shader`, which can fail.
        Texture::Shader { .. } => f.normal_to_world(f.n),
    }
}

/// Bump mapping from a height function of object-space points (a shader's
/// `height`), scaled by `k`: the object-space normal of the displaced surface
/// `p + k h(p) n`, or `None` when the height has no slope here (the caller
/// then keeps its normal bit for bit). `h3` gets three (point, texture
/// coordinates) pairs and returns the three heights, so a shader can evaluate
/// them in one call.
///
/// The method: forward differences along the surface's own tangents. With
/// steps `a = δu ∂p/∂u` and `b = δv ∂p/∂v` (texture coordinates moved by
/// `δu`, `δv` with them, so a height written in `uv` works too) the height
/// changes by `Δa = k (h(p+a) − h(p))` and `Δb = k (h(p+b) − h(p))`. The
/// gradient `g` in the plane of `a` and `b` with `g·a = Δa`, `g·b = Δb` is
/// the slope; its part across the shading normal `n` tilts it,
/// `n' = normalize(n − (g − (g·n) n))`. On a flat surface this is the normal
/// of Blinn's displaced tangents `a + Δa n`, `b + Δb n`; on a smooth-shaded
/// mesh, whose `n` is interpolated while `a` and `b` lie in the flat
/// triangle, it tilts the interpolated normal rather than rebuilding the
/// triangle's (which would turn such meshes faceted).
///
/// Three calls of `height`, against the six of the central differences along
/// x, y, z that the shading-language papers use, or four for tetrahedral
/// differences; only the tangential part of the gradient tilts the normal,
/// so the two tangent directions suffice. The error is first order,
/// `|Δg| ≈ ε/2 · |h''|`, small next to the tilt the bump itself gives
/// (`bump/tests.rs` checks it against central differences). Where the
/// parameterization degenerates (a sphere's poles) any orthonormal frame
/// around `n` is used, with `uv` fixed.
///
/// `eps` is the step length in object space; [`bump_step`] chooses it.
pub fn height_bump<E>(
    f: &TexFrame,
    k: f32,
    eps: f32,
    h3: impl FnOnce([(Vec3, Vec2); 3]) -> Result<[f32; 3], E>,
) -> Result<Option<Vec3>, E> {
    let (lu, lv) = (f.dpdu.length(), f.dpdv.length());
    let usable = lu > 1e-12 && lv > 1e-12 && f.dpdu.cross(f.dpdv).length() > 1e-6 * lu * lv;
    let (a, ua, b, ub) = if usable {
        let (du, dv) = (eps / lu, eps / lv);
        (f.dpdu * du, Vec2::new(du, 0.0), f.dpdv * dv, Vec2::new(0.0, dv))
    } else {
        let (t, s) = luster_core::math::orthonormal_basis(f.n);
        (t * eps, Vec2::ZERO, s * eps, Vec2::ZERO)
    };
    let [h0, ha, hb] = h3([(f.p_object, f.uv), (f.p_object + a, f.uv + ua), (f.p_object + b, f.uv + ub)])?;
    let (da, db) = (k * (ha - h0), k * (hb - h0));
    if da == 0.0 && db == 0.0 {
        return Ok(None);
    }
    Ok(Some(tilt(f.n, a, b, da, db)))
}

/// The unit normal `n` tilted by the gradient `g` in the plane of `a` and `b`
/// that has `g·a = da` and `g·b = db` (solved in the dual basis of `a`, `b`).
fn tilt(n: Vec3, a: Vec3, b: Vec3, da: f32, db: f32) -> Vec3 {
    let (aa, ab, bb) = (a.dot(a), a.dot(b), b.dot(b));
    let det = aa * bb - ab * ab;
    if det.abs() <= f32::MIN_POSITIVE {
        return n;
    }
    let (ca, cb) = ((da * bb - db * ab) / det, (db * aa - da * ab) / det);
    let g = a * ca + b * cb;
    let along = g - n * g.dot(n);
    (n - along).try_normalize().unwrap_or(n)
}

/// The object-space step of [`height_bump`] at a frame: half the pixel's
/// footprint, carried into object space, so the differences see the detail
/// one pixel can show and no finer (a finer step would alias sub-pixel
/// bumps into noise); but at least 10⁻⁴ of the point's distance from the
/// object's origin (and 10⁻⁴ absolute), where `f32` positions still resolve
/// the step to a few parts in a thousand.
pub fn bump_step(f: &TexFrame) -> f32 {
    let world_per_object = match &f.to_world {
        Some(xf) => {
            let t = f.dpdu.normalize_or_zero();
            let t = if t == Vec3::ZERO { luster_core::math::orthonormal_basis(f.n).0 } else { t };
            xf.vector(t).length().max(1e-12)
        }
        None => 1.0,
    };
    let floor = 1e-4 * f.p_object.abs().max_element().max(1.0);
    (0.5 * f.footprint / world_per_object).max(floor)
}

/// The normal of the surface with tangents `dpdu`, `dpdv` and unit normal
/// `n` displaced by a height with derivatives `(hu, hv)` in texture
/// coordinates (already scaled by the bump factor), all in one space.
fn displaced_normal(dpdu: Vec3, dpdv: Vec3, n: Vec3, hu: f32, hv: f32) -> Vec3 {
    let pu = dpdu + n * hu;
    let pv = dpdv + n * hv;
    let m = pu.cross(pv);
    let m = if m.dot(n) < 0.0 { -m } else { m };
    m.try_normalize().unwrap_or(n)
}

#[cfg(test)]
mod tests;
