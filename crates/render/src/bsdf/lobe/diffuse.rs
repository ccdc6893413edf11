//! PLACEHOLDER (replaced by the lobe's implementation).

use super::LobeSample;
use luster_core::math::Vec3;

/// PLACEHOLDER.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse {}

impl Diffuse {
    /// `f |cos θi|` and the density of `wi`.
    pub fn eval(&self, _wo: Vec3, _wi: Vec3) -> (Vec3, f32) {
        (Vec3::ZERO, 0.0)
    }
    /// A direction.
    pub fn sample(&self, _wo: Vec3, _uc: f32, _u: (f32, f32)) -> Option<LobeSample> {
        None
    }
    /// The albedo.
    pub fn albedo(&self, _wo: Vec3) -> Vec3 {
        Vec3::ZERO
    }
}
