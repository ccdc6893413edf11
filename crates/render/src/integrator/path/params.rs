//! The path tracer's switches, the course's `<RendererParams>` words and
//! luster's `MIS` ([`PathParams`]), and the copies of the path tracer
//! compiled for them: one per variant, chosen per camera ([`by_variant`]),
//! each with its words as constants ([`PathParams::fixed`]). Also how many
//! lights an MIS hit samples (`AllLights`, `OneLight`).

use crate::bsdf::Strategy;
use crate::render::scene::Scene;
use luster_core::math::Vec3;
use luster_scene::description::LightSamples;

/// The path tracer's switches (the course's `<RendererParams>` words).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathParams {
    /// Sample every light at every hit.
    pub next_event: bool,
    /// Cosine-weighted bounces instead of uniform ones.
    pub importance: bool,
    /// End paths by their throughput instead of the depth.
    pub russian_roulette: bool,
    /// Multiple importance sampling of light and BSDF samples.
    pub mis: bool,
    /// Under MIS, how many lights a hit samples.
    pub lights: LightSamples,
}

impl PathParams {
    /// How a bounce is drawn: from the BSDF under MIS, cosine-weighted under
    /// `ImportanceSampling`, uniformly otherwise.
    #[inline(always)]
    pub fn strategy(self) -> Strategy {
        if self.mis {
            Strategy::Brdf
        } else if self.importance {
            Strategy::Cosine
        } else {
            Strategy::Uniform
        }
    }

    /// The bits of this camera's variant, as [`PathParams::fixed`] reads
    /// them. Under MIS the course's `NextEventEstimation` and
    /// `ImportanceSampling` change nothing (every test of them is behind a
    /// test of MIS) and are left out, so ten copies cover every camera:
    /// 0–7, 8 and 12.
    #[inline]
    pub(super) fn key(self) -> u8 {
        let roulette = u8::from(self.russian_roulette) << 2;
        if self.mis {
            8 | roulette
        } else {
            u8::from(self.next_event) | u8::from(self.importance) << 1 | roulette
        }
    }

    /// These switches with the four words fixed to the bits of `V` (1
    /// next-event estimation, 2 importance sampling, 4 Russian roulette,
    /// 8 MIS), which are this camera's: the path tracer is compiled once
    /// per variant ([`by_variant`]), and each copy reads its switches
    /// through here, as constants: with the words known LLVM drops the other
    /// variants' code and keeps more of a vertex in registers. The switches
    /// travel by value: behind a reference LLVM loads them again after each
    /// out-of-line call (which might, for all it knows, have written them).
    #[inline(always)]
    pub(super) fn fixed<const V: u8>(self) -> PathParams {
        let p = PathParams {
            next_event: V & 1 != 0,
            importance: V & 2 != 0,
            russian_roulette: V & 4 != 0,
            mis: V & 8 != 0,
            lights: self.lights,
        };
        debug_assert_eq!(self.key(), V);
        p
    }
}

/// Evaluates `$call` with the const `$v` set to the variant of the switches
/// `$p` ([`PathParams::key`]): one arm per copy.
macro_rules! by_variant {
    ($p:expr, $v:ident => $call:expr) => {
        by_variant!(@arms $p.key(), $v, $call, [0 1 2 3 4 5 6 7 8] 12)
    };
    (@arms $key:expr, $v:ident, $call:expr, [$($k:literal)*] $last:literal) => {
        match $key {
            $($k => {
                const $v: u8 = $k;
                $call
            })*
            _ => {
                const $v: u8 = $last;
                $call
            }
        }
    };
}
pub(super) use by_variant;

/// Under MIS, a scene with at most this many lights has every one sampled
/// at every hit ([`LightSamples::Auto`]); with more, one is chosen by the light tree.
/// One light sample per hit leaves the noise of the choice: on the Cornell
/// box of `tools/mitsuba_cornell_check.py` (a point light and a light box)
/// sampling both removes most of the variance for little more time
/// (docs/path-tracing.md, "Lights per hit"). Each light adds a shadow ray to
/// every hit, so the count is kept small.
const EVERY_LIGHT_UP_TO: usize = 4;

/// Whether MIS samples every light at a hit rather than one chosen by the light tree.
#[inline]
pub(super) fn every_light(scene: &Scene, p: PathParams) -> bool {
    match p.lights {
        LightSamples::All => true,
        LightSamples::One => scene.lights.len() <= 1,
        LightSamples::Auto => scene.lights.len() <= EVERY_LIGHT_UP_TO,
    }
}

/// The chance that MIS's light sampling takes light `i` (an index into the
/// scene's lights) at a vertex at `x` whose light samples were drawn for
/// the normal `n`: 1 where every light is sampled, else the light tree's
/// chance there.
#[inline]
pub(super) fn pick_chance(scene: &Scene, p: PathParams, i: usize, x: Vec3, n: Option<Vec3>) -> f32 {
    if every_light(scene, p) {
        1.0
    } else {
        scene.light_tree.pmf(i, x, n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every combination of the words reaches the copy of its own switches;
    /// under MIS the two course words it overrides are dropped.
    #[test]
    fn each_variant_runs_with_its_own_switches() {
        for bits in 0u8..16 {
            let p = PathParams {
                next_event: bits & 1 != 0,
                importance: bits & 2 != 0,
                russian_roulette: bits & 4 != 0,
                mis: bits & 8 != 0,
                lights: LightSamples::One,
            };
            let got = by_variant!(p, V => p.fixed::<V>());
            let want = if p.mis { PathParams { next_event: false, importance: false, ..p } } else { p };
            assert_eq!(got, want, "words {bits:04b}");
        }
    }
}
