//! The course's reflectance model (hw1–hw5): Lambertian diffuse plus a
//! Blinn-Phong highlight, `kd cos θ + ks (n·h)^p`, for materials that name
//! no BRDF.

use crate::material::Material;
use luster_core::math::Vec3;

/// Diffuse plus Blinn-Phong specular reflectance towards `l` for a viewer
/// along `-d`, with `cos = n · l` already known to be positive.
#[inline]
pub fn blinn_phong(m: &Material, n: Vec3, l: Vec3, d: Vec3, cos: f32) -> Vec3 {
    // Most course materials have no specular part: skip its `powf` (the
    // term is a finite number times zero, so the sum is the same).
    if m.specular == Vec3::ZERO {
        return m.diffuse * cos;
    }
    let h = (l - d).normalize();
    m.diffuse * cos + m.specular * phong_power(n.dot(h).max(0.0), m.phong)
}

/// `x^e` for the Blinn-Phong lobe. The course's exponents are whole numbers
/// (1 to a few thousand): for those, repeated squaring in `f64`, a handful
/// of multiplications instead of a `powf` call. Its relative error (at most 32 roundings of `2⁻⁵³`, under
/// `2⁻⁴⁷`) is far under an `f32` step, so the result is the correctly
/// rounded power unless the exact power lies that close to a rounding
/// boundary; libm's `powf` (within 0.82 of a step) differs from it only
/// near such boundaries, by one step. Other exponents go to `powf`.
#[inline]
pub fn phong_power(x: f32, e: f32) -> f32 {
    let k = e as u32;
    if k as f32 != e || k > 1 << 16 {
        return x.powf(e);
    }
    // Factors of at most 1 (as `n·h` is) keep every partial product at or
    // above the result, so nothing underflows that the result would not.
    let (mut acc, mut base, mut k) = (1.0f64, f64::from(x), k);
    while k > 0 {
        if k & 1 == 1 {
            acc *= base;
        }
        k >>= 1;
        if k > 0 {
            base *= base;
        }
    }
    acc as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_exponents_are_powers_within_a_rounding_step_of_powf() {
        let mut differ = 0;
        let mut total = 0;
        for e in [1.0f32, 2.0, 3.0, 10.0, 50.0, 100.0, 150.0, 500.0, 1000.0] {
            for i in 0..=20_000 {
                let x = i as f32 / 20_000.0;
                let (ours, libm) = (phong_power(x, e), x.powf(e));
                total += 1;
                if ours != libm {
                    differ += 1;
                    // One step apart (the bit patterns of positive floats are ordered).
                    assert_eq!(ours.to_bits().abs_diff(libm.to_bits()), 1, "{x}^{e}: {ours} vs {libm}");
                }
            }
        }
        assert!(differ * 100 < total, "{differ} of {total} differ");
        assert_eq!((phong_power(0.0, 0.0), phong_power(0.3, 0.0), phong_power(0.0, 50.0)), (1.0, 1.0, 0.0));
        assert_eq!(phong_power(1.0, 500.0), 1.0);
        // Other exponents are libm's.
        for e in [0.5f32, 2.5, 1e9, -3.0] {
            assert_eq!(phong_power(0.7, e), 0.7f32.powf(e), "{e}");
        }
    }
}
