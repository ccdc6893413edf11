//! The state one camera sample carries along its path, shared by both
//! integrators: the ray counts for the summary, the secondary-ray budget,
//! the shutter time, the sampler, and the first shader failure.

use crate::bsdf::Lobes;
use crate::render::sampler::PixelSampler;
use luster_core::math::Vec2;
use luster_shading::shader::ShaderError;

/// Smallest path weight (largest RGB component of the product of the mirror,
/// Fresnel and transmission factors so far) that is still traced.
pub const MIN_WEIGHT: f32 = 1e-5;

/// Most reflection and refraction rays one camera ray may spawn.
pub const SECONDARY_BUDGET: u32 = 4096;

/// Per-camera-ray state: the counts for the summary, what is left of the
/// budget, the shutter time and the sampler for the rest of the path.
#[derive(Clone, Debug)]
pub struct PathState {
    /// Rays traced so far.
    pub stats: RayStats,
    budget: u32,
    /// Shutter time of this camera sample, in [0, 1).
    pub time: f32,
    /// Random dimensions for light and glossy samples.
    pub sampler: PixelSampler,
    /// Where the camera sample lies on the image, 0–1 across and down (a
    /// background texture is looked up there).
    pub screen: Vec2,
    /// Angle of the ray cone around each ray: the pixel's angular size.
    pub spread: f32,
    /// Distance the path has covered before the current ray.
    pub(crate) travelled: f32,
    /// The pixel being rendered and the camera's frame (for shaders).
    pub pixel: [u32; 2],
    /// See `pixel`.
    pub view: crate::texture::View,
    /// The first shader failure on this path, naming the object. The path
    /// then contributes black and the render loop stops (see `render_tiles`).
    pub error: Option<Box<ShaderError>>,
    /// The lobes of the last closure a shader returned, flattened where it
    /// was shaded: the vertex copies them out at once. Boxed, so that the
    /// state stays small to move; allocated once per state.
    pub(crate) lobes: Box<Lobes>,
    /// Whether shadow rays through media estimate their transmittance by
    /// ratio tracking (the path tracer, unbiased) rather than by marching
    /// (the recursive tracer, smooth).
    pub(crate) tracking: bool,
    /// The medium inside the object the current ray is in (an index into
    /// the scene's interiors): set by the path tracer as paths cross
    /// surfaces of objects with an `<Interior>`.
    pub(crate) interior: Option<u32>,
}

impl PathState {
    /// A fresh state for a new camera ray, keeping the running counts.
    pub fn new(stats: RayStats, time: f32, sampler: PixelSampler) -> Self {
        PathState {
            stats,
            budget: SECONDARY_BUDGET,
            time,
            sampler,
            screen: Vec2::ZERO,
            spread: 0.0,
            travelled: 0.0,
            pixel: [0; 2],
            view: crate::texture::View::default(),
            error: None,
            lobes: Box::default(),
            tracking: false,
            interior: None,
        }
    }

    /// The state for a camera sample at image position `screen` with ray
    /// cone spread `spread`.
    pub fn for_pixel(self, screen: Vec2, spread: f32) -> Self {
        PathState { screen, spread, ..self }
    }

    /// Readies the state for the next camera sample of a tile, at image
    /// position `screen` of pixel `pixel`, with its shutter `time`: what
    /// [`new`](Self::new) and [`for_pixel`](Self::for_pixel) give, keeping
    /// the counts, the spread and the view, without building the whole state
    /// again (copies the render loop would pay for at every sample). The
    /// sampler is set by the caller, which draws the camera's dimensions
    /// from it first.
    #[inline]
    pub fn next_sample(&mut self, time: f32, screen: Vec2, pixel: [u32; 2]) {
        self.budget = SECONDARY_BUDGET;
        self.time = time;
        self.screen = screen;
        self.travelled = 0.0;
        self.pixel = pixel;
    }

    /// Records a shader failure (the first one counts); the path then
    /// contributes black and the render stops.
    pub fn fail(&mut self, e: ShaderError) {
        if self.error.is_none() {
            self.error = Some(Box::new(e));
        }
    }

    /// Whether a secondary ray of `weight` may be traced; counts it if so.
    pub(crate) fn spawn(&mut self, weight: f32) -> bool {
        if weight < MIN_WEIGHT || self.budget == 0 {
            return false;
        }
        self.budget -= 1;
        self.stats.secondary += 1;
        true
    }
}

/// Ray counts, for the Mrays/s summary.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayStats {
    /// Camera rays.
    pub primary: u64,
    /// Reflection and refraction rays.
    pub secondary: u64,
    /// Shadow rays.
    pub shadow: u64,
}

impl RayStats {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.secondary + self.shadow
    }

    /// Adds another count.
    pub fn add(&mut self, o: &RayStats) {
        self.primary += o.primary;
        self.secondary += o.secondary;
        self.shadow += o.shadow;
    }
}
