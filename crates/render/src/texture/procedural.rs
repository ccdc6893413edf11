//! The course's procedural textures, functions of the object-space position:
//! Perlin noise and the 3D checkerboard.
//!
//! Perlin noise is the course's variant ([`luster_shading::noise::course`]): its
//! gradient table is each implementer's own shuffle, so a course reference
//! image can be matched in look (scale, contrast, veins or patches) but not
//! texel for texel. With `NumOctaves` above 1 the octaves are summed with
//! halving weights and doubling frequencies and the sum is renormalized to
//! the single octave's range; `absval` takes the absolute value of each
//! octave (Perlin's turbulence), `linear` maps the sum to [0, 1].

use luster_core::math::Vec3;
use luster_scene::description::NoiseConversion;
use luster_shading::noise::course;

/// A Perlin noise texture.
#[derive(Clone, Copy, Debug)]
pub struct Perlin {
    /// Position multiplier.
    pub scale: f32,
    /// From noise to value.
    pub conversion: NoiseConversion,
    /// Octaves summed.
    pub octaves: u32,
}

impl Perlin {
    /// The value in [0, 1] at `p`.
    pub fn value(&self, p: Vec3) -> f32 {
        self.value_grad(p, false).0
    }

    /// The value and, when `grad`, its gradient with respect to `p` (else zero).
    pub fn value_grad(&self, p: Vec3, grad: bool) -> (f32, Vec3) {
        let mut sum = 0.0;
        let mut g = Vec3::ZERO;
        let mut weight = 1.0;
        let mut total = 0.0;
        let mut freq = self.scale;
        for _ in 0..self.octaves.max(1) {
            let q = p * freq;
            let (n, dn) = if grad {
                let (n, d) = course::noise_grad(q.x, q.y, q.z);
                (n, Vec3::from_array(d) * freq)
            } else {
                (course::noise(q.x, q.y, q.z), Vec3::ZERO)
            };
            match self.conversion {
                NoiseConversion::AbsVal => {
                    sum += weight * n.abs();
                    g += dn * (weight * n.signum());
                }
                NoiseConversion::Linear => {
                    sum += weight * n;
                    g += dn * weight;
                }
            }
            total += weight;
            weight *= 0.5;
            freq *= 2.0;
        }
        let (s, g) = (sum / total, g / total);
        match self.conversion {
            NoiseConversion::AbsVal => (s, g),
            NoiseConversion::Linear => ((s + 1.0) * 0.5, g * 0.5),
        }
    }
}

/// The hw4 checkerboard: alternating colours on a 3D grid of cubes of edge
/// `1 / scale`, shifted by `offset`.
#[derive(Clone, Copy, Debug)]
pub struct Checkerboard {
    /// Cubes per unit.
    pub scale: f32,
    /// Shift of the pattern.
    pub offset: f32,
    /// One colour.
    pub black: Vec3,
    /// The other.
    pub white: Vec3,
}

impl Checkerboard {
    /// The colour at `p`, exactly as the hw4 pseudo-code computes it: C's
    /// truncating cast and remainder, so the squares next to zero are twice as
    /// wide as the rest (a property of the course's images).
    pub fn value(&self, p: Vec3) -> Vec3 {
        let odd = |c: f32| ((c + self.offset) * self.scale) as i64 % 2 != 0;
        let xor_xy = odd(p.x) != odd(p.y);
        if xor_xy != odd(p.z) {
            self.black
        } else {
            self.white
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_alternates_and_follows_the_course_pseudo_code() {
        let c = Checkerboard { scale: 1.0, offset: 0.0, black: Vec3::ZERO, white: Vec3::ONE };
        assert_eq!(c.value(Vec3::new(0.5, 0.5, 0.5)), Vec3::ONE);
        assert_eq!(c.value(Vec3::new(1.5, 0.5, 0.5)), Vec3::ZERO);
        assert_eq!(c.value(Vec3::new(1.5, 1.5, 0.5)), Vec3::ONE);
        assert_eq!(c.value(Vec3::new(1.5, 1.5, 1.5)), Vec3::ZERO);
        // Truncation towards zero: (-0.5, 0.5) lies in the same square as (0.5, 0.5).
        assert_eq!(c.value(Vec3::new(-0.5, 0.5, 0.5)), c.value(Vec3::new(0.5, 0.5, 0.5)));
        let shifted = Checkerboard { offset: 1.0, ..c };
        assert_eq!(shifted.value(Vec3::new(0.5, 0.5, 0.5)), Vec3::ZERO);
        let fine = Checkerboard { scale: 4.0, ..c };
        assert_eq!(fine.value(Vec3::new(0.3, 0.1, 0.1)), Vec3::ZERO);
    }

    #[test]
    fn perlin_values_are_in_range_and_gradients_match_differences() {
        for conversion in [NoiseConversion::Linear, NoiseConversion::AbsVal] {
            for octaves in [1, 3] {
                let t = Perlin { scale: 1.7, conversion, octaves };
                let mut seed = 12345u32;
                let mut rnd = || {
                    seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
                    (seed >> 8) as f32 / (1u32 << 24) as f32 * 20.0 - 10.0
                };
                for _ in 0..2000 {
                    let p = Vec3::new(rnd(), rnd(), rnd());
                    let (v, g) = t.value_grad(p, true);
                    assert!((0.0..=1.0).contains(&v), "{v} at {p}");
                    assert_eq!(v, t.value(p));
                    // |n| has a kink wherever an octave's noise crosses zero.
                    let near_kink = (0..octaves).any(|o| {
                        let q = p * (1.7 * 2f32.powi(o as i32));
                        course::noise(q.x, q.y, q.z).abs() < 0.02
                    });
                    if conversion == NoiseConversion::AbsVal && near_kink {
                        continue;
                    }
                    let h = 1e-3;
                    let fd = Vec3::new(
                        t.value(p + Vec3::X * h) - t.value(p - Vec3::X * h),
                        t.value(p + Vec3::Y * h) - t.value(p - Vec3::Y * h),
                        t.value(p + Vec3::Z * h) - t.value(p - Vec3::Z * h),
                    ) / (2.0 * h);
                    assert!((fd - g).length() < 0.02 * (1.0 + g.length()), "{fd} vs {g} at {p}");
                }
            }
        }
    }
}
