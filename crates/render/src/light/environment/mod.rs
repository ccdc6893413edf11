//! The environment light (`SphericalDirectionalLight`, hw5): an image of
//! radiance on the sphere at infinity. It is the background of every ray that
//! escapes and a light for direct lighting.
//!
//! Parameters (see [`luster_scene::ceng795::lights`]): `ImageId`, the `type`
//! attribute (`latlong` or `probe`) and `Sampler` (`importance`, `uniform`,
//! `cosine`).
//!
//! ## Orientation
//! Lat-long (hw5 eqs. 5–6): `u = (1 + atan2(dx, -dz)/π) / 2`,
//! `v = acos(dy)/π`. `+y` is up (the top row), `-z` is the centre of the
//! image, `+x` is three quarters across and `+z` is the left and right edge.
//! Probe (Debevec's angular map): with `a = 2u - 1`, `b = 1 - 2v`, the
//! direction at angle `π √(a² + b²)` from `-z`, towards `(a, b)` in the x-y
//! plane: again `-z` is the centre and `+y` is up; `+z` is the rim.
//!
//! ## Sampling
//! `importance` (the default) draws a texel in proportion to its luminance
//! times the solid angle it covers (`sin θ` for lat-long, `sin(πρ)/ρ` for the
//! probe), then a point in it; the pdf over solid angle is the image-plane
//! pdf divided by the mapping's Jacobian (`2π² sin θ` for lat-long,
//! `4π sin(πρ)/ρ` for the probe). `uniform` is hw5's scheme: a uniform
//! direction on the hemisphere around the normal, pdf `1/2π`; `cosine` draws
//! it cosine-weighted, pdf `cos/π`. All three are unbiased estimates of the
//! same integral, so they differ only in noise.
//!
//! Texels are looked up nearest, so the radiance is exactly piecewise constant
//! like the distribution. Values keep the file's scale (linear floats for EXR
//! and HDR, 0–255 for 8-bit images, like `BackgroundColor`), times the
//! light's strength (1 for the course's light; `--env` sets 255 × its
//! `--env-strength`, [`luster_scene::hdri`]).
//!
//! ## Rotation
//! [`Environment::placed`] turns the map about `+y` by an angle `γ`,
//! counter-clockwise seen from above: the radiance from `d` is the map's at
//! `R(−γ) d`, and a direction drawn in the map's frame is turned by `R(γ)`.
//! A rotation keeps solid angles, so the pdf of `d` is the map's pdf at
//! `R(−γ) d` and lookup, sampling and pdf agree.

use super::distribution::Distribution2D;
use crate::texture::Image;
use luster_core::math::{orthonormal_basis, sin_cos_turns, Vec2, Vec3};
use luster_scene::description::{EnvMapping, EnvSampling};
use std::f32::consts::PI;

/// An environment map ready to look up and sample.
pub struct Environment {
    width: usize,
    height: usize,
    texels: Vec<Vec3>,
    mapping: EnvMapping,
    sampling: EnvSampling,
    distribution: Distribution2D,
    /// `(cos γ, sin γ)` of the turn about `+y`; `None` for none, so the
    /// course's maps keep their exact lookups.
    turn: Option<(f32, f32)>,
}

impl std::fmt::Debug for Environment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Environment({}x{}, {:?}, {:?})", self.width, self.height, self.mapping, self.sampling)
    }
}

/// Luminance of linear sRGB (hw5 eq. in §3.1, Rec. 709 weights).
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl Environment {
    /// From an image's texels. Fails (with a reason) on texels that are NaN,
    /// infinite or negative: radiance cannot be any of those, and one such
    /// texel would poison the sampling distribution.
    pub fn new(image: &Image, mapping: EnvMapping, sampling: EnvSampling) -> Result<Environment, String> {
        let (w, h) = image.size();
        let (width, height) = (w as usize, h as usize);
        let texels = image.texels();
        if let Some(i) = texels.iter().position(|t| !t.is_finite() || t.min_element() < 0.0) {
            let kind = if texels[i].is_nan() {
                "a NaN"
            } else if !texels[i].is_finite() {
                "an infinite"
            } else {
                "a negative"
            };
            return Err(format!(
                "the environment map has {kind} texel at ({}, {}); radiance must be finite and not negative",
                i % width,
                i / width
            ));
        }
        let mut weights = vec![0.0f32; width * height];
        for y in 0..height {
            for x in 0..width {
                weights[y * width + x] =
                    luminance(texels[y * width + x]) * texel_solid_angle(mapping, x, y, width, height);
            }
        }
        let distribution = Distribution2D::new(&weights, width, height);
        Ok(Environment { width, height, texels, mapping, sampling, distribution, turn: None })
    }

    /// This map turned by `rotation` degrees about `+y` (counter-clockwise
    /// seen from above) and its values scaled by `strength`. Fails when a
    /// scaled texel is no longer finite.
    pub fn placed(mut self, rotation: f32, strength: f32) -> Result<Environment, String> {
        if !(strength >= 0.0 && strength.is_finite() && rotation.is_finite()) {
            return Err(format!(
                "the environment's strength {strength} or rotation {rotation} is not usable"
            ));
        }
        if strength != 1.0 {
            for t in &mut self.texels {
                *t *= strength;
            }
            if let Some(i) = self.texels.iter().position(|t| !t.is_finite()) {
                return Err(format!(
                    "the environment map's texel at ({}, {}) times the strength {strength} is too bright to represent",
                    i % self.width,
                    i / self.width
                ));
            }
        }
        let turn = rotation.rem_euclid(360.0);
        self.turn = (turn != 0.0).then(|| {
            let (s, c) = turn.to_radians().sin_cos();
            (c, s)
        });
        Ok(self)
    }

    /// `d` in the map's own frame: turned back by the rotation, `R(−γ) d`.
    #[inline]
    fn world_to_map(&self, d: Vec3) -> Vec3 {
        match self.turn {
            None => d,
            Some((c, s)) => Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z),
        }
    }

    /// A direction of the map's frame in the world: `R(γ) d`.
    #[inline]
    fn map_to_world(&self, d: Vec3) -> Vec3 {
        match self.turn {
            None => d,
            Some((c, s)) => Vec3::new(c * d.x + s * d.z, d.y, c * d.z - s * d.x),
        }
    }

    /// Radiance arriving from direction `d` (unit), i.e. seen along `d`.
    pub fn eval(&self, d: Vec3) -> Vec3 {
        self.lookup(self.uv(d))
    }

    /// The radiance averaged over all directions (each texel weighed by its
    /// solid angle), for the light tree's power of the light.
    pub fn mean_radiance(&self) -> Vec3 {
        let (mut sum, mut omega) = (Vec3::ZERO, 0.0f32);
        for y in 0..self.height {
            for x in 0..self.width {
                let a = texel_solid_angle(self.mapping, x, y, self.width, self.height);
                sum += self.texels[y * self.width + x] * a;
                omega += a;
            }
        }
        if omega > 0.0 {
            sum / omega
        } else {
            Vec3::ZERO
        }
    }

    #[inline]
    fn lookup(&self, uv: Vec2) -> Vec3 {
        let x = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        self.texels[y * self.width + x]
    }

    /// Image coordinates of direction `d` (in the world, after the
    /// rotation), in `[0, 1]²`.
    pub fn uv(&self, d: Vec3) -> Vec2 {
        let d = self.world_to_map(d);
        match self.mapping {
            EnvMapping::LatLong => {
                let u = 0.5 * (1.0 + d.x.atan2(-d.z) / PI);
                let v = d.y.clamp(-1.0, 1.0).acos() / PI;
                Vec2::new(u.clamp(0.0, 1.0), v.clamp(0.0, 1.0))
            }
            EnvMapping::Probe => {
                let s = (d.x * d.x + d.y * d.y).sqrt();
                let r = if s > 0.0 { (-d.z).clamp(-1.0, 1.0).acos() / (PI * s) } else { 0.0 };
                Vec2::new(0.5 * (1.0 + d.x * r), 0.5 * (1.0 - d.y * r))
            }
        }
    }

    /// The direction (in the world, after the rotation) at image
    /// coordinates `uv`, or `None` outside a probe's circle.
    pub fn direction(&self, uv: Vec2) -> Option<Vec3> {
        self.map_direction(uv).map(|d| self.map_to_world(d))
    }

    /// The direction at `uv` in the map's own frame.
    fn map_direction(&self, uv: Vec2) -> Option<Vec3> {
        match self.mapping {
            EnvMapping::LatLong => {
                let phi = PI * (2.0 * uv.x - 1.0);
                let theta = PI * uv.y;
                let (st, ct) = theta.sin_cos();
                let (sp, cp) = phi.sin_cos();
                Some(Vec3::new(st * sp, ct, -st * cp))
            }
            EnvMapping::Probe => {
                let (a, b) = (2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y);
                let rho = (a * a + b * b).sqrt();
                if rho > 1.0 {
                    return None;
                }
                if rho == 0.0 {
                    return Some(Vec3::new(0.0, 0.0, -1.0));
                }
                let (s, c) = (PI * rho).sin_cos();
                Some(Vec3::new(a / rho * s, b / rho * s, -c))
            }
        }
    }

    /// Density over solid angle with which importance sampling draws `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        self.pdf_at(self.uv(d))
    }

    /// [`pdf`](Self::pdf) of the direction at image coordinates `uv`.
    fn pdf_at(&self, uv: Vec2) -> f32 {
        let j = jacobian(self.mapping, uv);
        if j <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf(uv) / (j * jacobian_scale(self.mapping))
    }

    /// Density over solid angle with which [`sample`](Self::sample) draws
    /// `d` at a surface with normal `n` (`None`: in a medium).
    pub fn sampling_pdf(&self, n: Option<Vec3>, d: Vec3) -> f32 {
        match (self.sampling, n) {
            (EnvSampling::Uniform, Some(n)) => {
                if n.dot(d) > 0.0 {
                    0.5 / PI
                } else {
                    0.0
                }
            }
            (EnvSampling::Cosine, Some(n)) => n.dot(d).max(0.0) / PI,
            _ => self.pdf(d),
        }
    }

    /// [`eval`](Self::eval) and [`sampling_pdf`](Self::sampling_pdf) of
    /// `d` together, for a ray that left the scene: its image coordinates
    /// (two inverse trigonometric functions) worked out once.
    pub fn eval_with_pdf(&self, n: Option<Vec3>, d: Vec3) -> (Vec3, f32) {
        match (self.sampling, n) {
            (EnvSampling::Uniform | EnvSampling::Cosine, Some(_)) => (self.eval(d), self.sampling_pdf(n, d)),
            _ => {
                let uv = self.uv(d);
                (self.lookup(uv), self.pdf_at(uv))
            }
        }
    }

    /// A direction for direct lighting at a surface with normal `n` (`None`
    /// in a medium, where importance sampling is used whatever the setting),
    /// for the uniform pair `u`: the unit direction, the radiance from it
    /// divided by its density, and the density over solid angle (that of
    /// [`sampling_pdf`](Self::sampling_pdf), from the draw itself). `None`
    /// when the draw has no density.
    pub fn sample(&self, n: Option<Vec3>, u: (f32, f32)) -> Option<(Vec3, Vec3, f32)> {
        match (self.sampling, n) {
            (EnvSampling::Uniform, Some(n)) => {
                // Uniform on the hemisphere: cos θ uniform in [0, 1].
                let z = u.0;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (sp, cp) = sin_cos_turns(u.1);
                let d = frame(n, Vec3::new(r * cp, r * sp, z));
                Some((d, self.eval(d) * (2.0 * PI), 0.5 / PI))
            }
            (EnvSampling::Cosine, Some(n)) => {
                let r = u.0.sqrt();
                let phi = 2.0 * PI * u.1;
                let z = (1.0 - u.0).max(0.0).sqrt();
                if z <= 0.0 {
                    return None;
                }
                let d = frame(n, Vec3::new(r * phi.cos(), r * phi.sin(), z));
                Some((d, self.eval(d) * (PI / z), z / PI))
            }
            _ => {
                let (uv, pdf_uv) = self.distribution.sample(u);
                let d = self.direction(uv)?;
                let j = jacobian(self.mapping, uv) * jacobian_scale(self.mapping);
                if pdf_uv <= 0.0 || j <= 0.0 {
                    return None;
                }
                let pdf = pdf_uv / j;
                Some((d, self.lookup(uv) / pdf, pdf))
            }
        }
    }
}

/// `local` (z along `n`) in world space.
#[inline]
fn frame(n: Vec3, local: Vec3) -> Vec3 {
    let (t, b) = orthonormal_basis(n);
    (t * local.x + b * local.y + n * local.z).normalize()
}

/// Solid angle per unit image area at `uv`, up to [`jacobian_scale`].
#[inline]
fn jacobian(mapping: EnvMapping, uv: Vec2) -> f32 {
    match mapping {
        EnvMapping::LatLong => (PI * uv.y).sin().max(0.0),
        EnvMapping::Probe => {
            let (a, b) = (2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y);
            let rho = (a * a + b * b).sqrt();
            if rho > 1.0 {
                0.0
            } else if rho < 1e-6 {
                PI
            } else {
                ((PI * rho).sin() / rho).max(0.0)
            }
        }
    }
}

/// A texel's weight for its solid angle (up to [`jacobian_scale`] and the
/// texel's area). Lat-long: `sin θ` at the texel's centre. Probe: the mean
/// Jacobian over a 4×4 grid in the texel, and at least a small floor for
/// any texel that reaches into the circle: a texel straddling the rim must
/// keep a non-zero density, or the light it holds would never be sampled
/// (a visible bias for a small probe under a constant sky).
fn texel_solid_angle(mapping: EnvMapping, x: usize, y: usize, w: usize, h: usize) -> f32 {
    let (w, h) = (w as f32, h as f32);
    match mapping {
        EnvMapping::LatLong => jacobian(mapping, Vec2::new((x as f32 + 0.5) / w, (y as f32 + 0.5) / h)),
        EnvMapping::Probe => {
            // The texel's point nearest the centre, in a, b ∈ [-1, 1].
            let near = |lo: f32, hi: f32| {
                if lo > 0.0 {
                    lo
                } else if hi < 0.0 {
                    hi
                } else {
                    0.0
                }
            };
            let a = near(2.0 * x as f32 / w - 1.0, 2.0 * (x + 1) as f32 / w - 1.0);
            let b = near(2.0 * y as f32 / h - 1.0, 2.0 * (y + 1) as f32 / h - 1.0);
            if a * a + b * b >= 1.0 {
                return 0.0;
            }
            let mut sum = 0.0;
            for j in 0..4 {
                for i in 0..4 {
                    let uv = Vec2::new(
                        (x as f32 + (i as f32 + 0.5) / 4.0) / w,
                        (y as f32 + (j as f32 + 0.5) / 4.0) / h,
                    );
                    sum += jacobian(mapping, uv);
                }
            }
            (sum / 16.0).max(1e-3)
        }
    }
}

/// The constant factor of the Jacobian: `dω = scale · jacobian · du dv`.
#[inline]
fn jacobian_scale(mapping: EnvMapping) -> f32 {
    match mapping {
        EnvMapping::LatLong => 2.0 * PI * PI,
        EnvMapping::Probe => 4.0 * PI,
    }
}

#[cfg(test)]
mod tests;
