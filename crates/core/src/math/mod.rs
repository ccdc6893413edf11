//! Geometric maths on top of glam: rays, bounding boxes, affine transforms,
//! and an inlined `floor` for the noise and texture lookups.
//!
//! Points, directions and normals are all `Vec3`; the difference lives in
//! [`Transform`], whose `point`, `vector` and `normal` methods are the only way
//! the renderer moves them between spaces, so a normal can never be moved with
//! the matrix meant for points.

mod aabb;
mod ray;
mod transform;
mod turns;

pub use aabb::Aabb;
pub use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec3A, Vec4};
pub use ray::Ray;
pub use transform::Transform;
pub use turns::sin_cos_turns;

/// Builds an orthonormal basis around `n` (Duff et al. 2017, "Building an
/// Orthonormal Basis, Revisited"): no branches on the hot path, no singularity.
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// `x.floor()`, bit for bit (NaN, ±∞, −0.0 and |x| ≥ 2²³ included). On the
/// baseline x86-64 target `f32::floor` is a call into libm (`roundss` needs
/// SSE4.1), and the noise lookups call it per lattice axis; this is a
/// truncation, a compare and a select, inlined.
#[inline(always)]
pub fn floor(x: f32) -> f32 {
    // 2²³: from there on every f32 is an integer (and `as i32` could saturate).
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t > x {
            t - 1.0
        } else if t == x {
            // Keeps −0.0 (truncation gives +0.0).
            x
        } else {
            t
        }
    } else {
        x
    }
}

/// `x.round()` (halves away from zero), bit for bit (NaN, ±∞, −0.0 and
/// |x| ≥ 2²³ included), inlined where `f32::round` is a call into the
/// compiler's runtime on the baseline target ([`sin_cos_turns`] rounds a
/// few times a path).
#[inline(always)]
pub fn round(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        // Exact: the fraction that truncation dropped.
        let r = if (x - t).abs() >= 0.5 { t + 1.0f32.copysign(x) } else { t };
        // −0.0 for −0.5 < x ≤ −0.0, as `round` gives.
        r.copysign(x)
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_matches_libm_bit_for_bit() {
        let special = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.5,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_609.0,
            3.0e9,
            -3.0e9,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1.0e-45,
            -1.0e-45,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        same_bits_as_libm("floor", floor, f32::floor, &special);
    }

    /// `ours` against `libm` on `special` and every 997th bit pattern (all
    /// exponents and both signs): the same bits, or NaN for NaN.
    fn same_bits_as_libm(name: &str, ours: fn(f32) -> f32, libm: fn(f32) -> f32, special: &[f32]) {
        let sweep = (0..=u32::MAX / 997).map(|i| f32::from_bits(i.wrapping_mul(997)));
        for x in special.iter().copied().chain(sweep) {
            let (a, b) = (ours(x), libm(x));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{name}({x:e}): {a:e} vs {b:e}"
            );
        }
    }

    #[test]
    fn round_matches_libm_bit_for_bit() {
        let special = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            0.499_999_97,
            -0.499_999_97,
            1.5,
            -1.5,
            2.5,
            -2.5,
            8_388_607.5,
            -8_388_607.5,
            4_194_303.5,
            8_388_608.0,
            3.0e9,
            f32::MAX,
            f32::MIN,
            1.0e-45,
            -1.0e-45,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        same_bits_as_libm("round", round, f32::round, &special);
    }

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        for n in [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(1.0, 2.0, -3.0).normalize(),
            Vec3::new(0.0, 0.0, -1.0 + 1e-7).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-5);
            assert!((b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5 && t.dot(b).abs() < 1e-5);
        }
    }
}
