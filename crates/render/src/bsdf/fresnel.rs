//! The exact Fresnel reflectances the course uses: unpolarized light, the
//! average of the s and p terms.

/// Reflectance of a dielectric boundary for light arriving with `cos_i`
/// (positive) from index `n1` into `n2`, and the cosine of the transmitted
/// direction. Total internal reflection gives reflectance 1 and no cosine.
#[inline]
pub fn dielectric(cos_i: f32, n1: f32, n2: f32) -> (f32, Option<f32>) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = n1 / n2;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return (1.0, None);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_par = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    let r_perp = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    (0.5 * (r_par * r_par + r_perp * r_perp), Some(cos_t))
}

/// Reflectance of a conductor with complex index `n + ik` for light arriving
/// with `cos_i` from air (the approximation of the course slides, exact at
/// normal incidence).
#[inline]
pub fn conductor(cos_i: f32, n: f32, k: f32) -> f32 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let nk = n * n + k * k;
    let two_nc = 2.0 * n * c;
    let rs = (nk - two_nc + c2) / (nk + two_nc + c2);
    let rp = (nk * c2 - two_nc + 1.0) / (nk * c2 + two_nc + 1.0);
    0.5 * (rs + rp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_limits() {
        // Normal incidence: ((n1 - n2) / (n1 + n2))².
        let (r, t) = dielectric(1.0, 1.0, 1.5);
        assert!((r - 0.04).abs() < 1e-6);
        assert!((t.unwrap() - 1.0).abs() < 1e-6);
        // Grazing incidence reflects everything.
        let (r, _) = dielectric(0.0, 1.0, 1.5);
        assert!((r - 1.0).abs() < 1e-6);
        // Matched indices reflect nothing.
        assert!(dielectric(0.7, 1.3, 1.3).0.abs() < 1e-7);
        // Symmetric at normal incidence.
        assert!((dielectric(1.0, 1.5, 1.0).0 - 0.04).abs() < 1e-6);
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        let critical = (1.0f32 / 1.5).asin();
        let (r, t) = dielectric((critical + 0.01).cos(), 1.5, 1.0);
        assert_eq!((r, t), (1.0, None));
        let (r, t) = dielectric((critical - 0.01).cos(), 1.5, 1.0);
        assert!(r < 1.0 && t.is_some());
    }

    #[test]
    fn reflectance_rises_monotonically_towards_grazing() {
        let mut last = 0.0;
        for i in (0..=100).rev() {
            let (r, _) = dielectric(i as f32 / 100.0, 1.0, 1.5);
            assert!(r >= last - 1e-6);
            last = r;
        }
    }

    #[test]
    fn conductor_limits() {
        // k = 0 is a dielectric at normal incidence.
        assert!((conductor(1.0, 1.5, 0.0) - 0.04).abs() < 1e-6);
        // Normal incidence: ((n-1)² + k²) / ((n+1)² + k²).
        let (n, k) = (0.37, 2.82);
        let exact = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((conductor(1.0, n, k) - exact).abs() < 1e-6);
        assert!((conductor(0.0, n, k) - 1.0).abs() < 1e-6);
        assert!((0.0..=1.0).contains(&conductor(0.5, n, k)));
    }
}
