//! The anisotropic Trowbridge–Reitz (GGX) microfacet distribution shared by
//! the conductor and dielectric lobes: `D(h)`, Smith's masking `Λ`, `G1`,
//! the height-correlated `G2`, and sampling of the visible normals.
//!
//! Directions are in the lobe's local frame (`+z` the normal, `+x` the
//! tangent the anisotropy stretches along); `αx` is the width along `+x`.

use luster_core::math::{sin_cos_turns, Vec3};
use std::f32::consts::PI;

/// Narrowest lobe width: below it a lobe is a mirror in all but name, and
/// `D`'s peak (`1 / π α²`) would overflow what the pdfs can carry.
pub const MIN_ALPHA: f32 = 1e-3;

/// A GGX distribution with widths `ax` along `+x` and `ay` along `+y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Width along the tangent, at least [`MIN_ALPHA`].
    pub ax: f32,
    /// Width along the bitangent, at least [`MIN_ALPHA`].
    pub ay: f32,
}

impl Ggx {
    /// The distribution with widths `ax` and `ay`, clamped to [`MIN_ALPHA`].
    pub fn new(ax: f32, ay: f32) -> Ggx {
        Ggx { ax: ax.max(MIN_ALPHA), ay: ay.max(MIN_ALPHA) }
    }

    /// OpenPBR 1.1's mapping of roughness `r` and anisotropy `a` (both in
    /// 0–1): `α = r²`, `αx = α sqrt(2 / (1 + (1 − a)²))`, `αy = (1 − a) αx`,
    /// which keeps `αx² + αy² = 2α²` as the anisotropy grows.
    pub fn from_roughness(roughness: f32, anisotropy: f32) -> Ggx {
        let r = roughness.clamp(0.0, 1.0);
        let a = anisotropy.clamp(0.0, 1.0);
        let alpha = r * r;
        let ax = alpha * (2.0 / (1.0 + (1.0 - a) * (1.0 - a))).sqrt();
        Ggx::new(ax, (1.0 - a) * ax)
    }

    /// The root mean square of the two widths, `sqrt((αx² + αy²) / 2)`:
    /// the isotropic width with the same mean slope variance, which OpenPBR's
    /// mapping keeps at `r²` whatever the anisotropy.
    #[inline]
    pub fn alpha_rms(&self) -> f32 {
        (0.5 * (self.ax * self.ax + self.ay * self.ay)).sqrt()
    }

    /// `D(h)`, the density of microfacet normals per unit solid angle
    /// projected on the macro surface (`∫ D(h) h.z dω = 1`).
    #[inline]
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (h.x / self.ax, h.y / self.ay);
        let t = x * x + y * y + h.z * h.z;
        1.0 / (PI * self.ax * self.ay * t * t)
    }

    /// Smith's `Λ(w)`: the masked fraction of the microsurface seen from `w`,
    /// relative to the visible one. Symmetric in `w.z`'s sign.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        if z2 <= 1e-14 {
            return f32::INFINITY;
        }
        let a2t2 = (self.ax * self.ax * w.x * w.x + self.ay * self.ay * w.y * w.y) / z2;
        0.5 * ((1.0 + a2t2).sqrt() - 1.0)
    }

    /// Smith's masking `G1(w) = 1 / (1 + Λ(w))`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// The height-correlated masking-shadowing `G2 = 1 / (1 + Λ(wo) + Λ(wi))`.
    #[inline]
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// The density of the normals visible from `w` (with `w.z > 0`):
    /// `D_w(h) = G1(w) max(0, w·h) D(h) / w.z`, which
    /// [`sample_visible`](Self::sample_visible) draws.
    #[inline]
    pub fn d_visible(&self, w: Vec3, h: Vec3) -> f32 {
        let c = w.dot(h);
        if c <= 0.0 || w.z <= 0.0 {
            return 0.0;
        }
        self.g1(w) * c * self.d(h) / w.z
    }

    /// A normal drawn from the normals visible from `w` (`w.z > 0`) with
    /// density [`d_visible`](Self::d_visible): Dupuy and Benyoub's (2023)
    /// spherical caps in the distribution's stretched, hemispherical
    /// configuration, mapped back.
    #[inline]
    pub fn sample_visible(&self, w: Vec3, (u1, u2): (f32, f32)) -> Vec3 {
        let wh = Vec3::new(self.ax * w.x, self.ay * w.y, w.z).normalize();
        let (sp, cp) = sin_cos_turns(u2);
        let z = (1.0 - u1) * (1.0 + wh.z) - wh.z;
        let s = (1.0 - z * z).max(0.0).sqrt();
        let h = Vec3::new(s * cp, s * sp, z) + wh;
        Vec3::new(self.ax * h.x, self.ay * h.y, h.z.max(0.0)).normalize_or(Vec3::Z)
    }
}
