//! The entry points a script may define ([`Entry`]), and what a
//! `DecalMode material` shader's outputs amount to ([`MaterialOutputs`]).

use super::closure::Closure;

/// The entry points a script may define: for surfaces (`emission` is a
/// surface's emitted radiance under `DecalMode material`) and for volumes
/// (`density`, and `emission` per unit length).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Entry {
    /// `color(s)`: a surface colour.
    Color = 0,
    /// `height(s)`: a bump height.
    Height = 1,
    /// `reflect(s)`: a mirror-reflection colour.
    Reflect = 2,
    /// `density(s)`: a volume density.
    Density = 3,
    /// `emission(s)`: emitted radiance.
    Emission = 4,
    /// `specular(s)`: a specular colour.
    Specular = 5,
    /// `roughness(s)`: a microfacet roughness.
    Roughness = 6,
    /// `metalness(s)`: how metallic a surface is.
    Metalness = 7,
    /// `material(s)`: a closure (`docs/closures.md`), called only through
    /// [`ShaderSet::material`](super::ShaderSet::material), never alone.
    Material = 8,
    /// `normal(s)`: a world-space shading normal (`DecalMode
    /// replace_normal`; `bevel()` makes one).
    Normal = 9,
}

/// How many entry points there are.
pub const ENTRIES: usize = 10;

impl Entry {
    /// Every entry point, in index order.
    pub const ALL: [Entry; ENTRIES] = [
        Entry::Color,
        Entry::Height,
        Entry::Reflect,
        Entry::Density,
        Entry::Emission,
        Entry::Specular,
        Entry::Roughness,
        Entry::Metalness,
        Entry::Material,
        Entry::Normal,
    ];

    /// The function name a script defines.
    pub fn name(self) -> &'static str {
        match self {
            Entry::Color => "color",
            Entry::Height => "height",
            Entry::Reflect => "reflect",
            Entry::Density => "density",
            Entry::Emission => "emission",
            Entry::Specular => "specular",
            Entry::Roughness => "roughness",
            Entry::Metalness => "metalness",
            Entry::Material => "material",
            Entry::Normal => "normal",
        }
    }
}

/// What a `DecalMode material` shader says about a surface point: one value
/// per output the script defines (`None` for the others). A script that
/// defines `material(s)` gives `closure` alone: its other outputs are not
/// called.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MaterialOutputs {
    /// `color(s)`: the base colour, 0–1.
    pub color: Option<[f32; 3]>,
    /// `specular(s)`: the specular colour (`F0` of the microfacet model), 0–1.
    pub specular: Option<[f32; 3]>,
    /// `roughness(s)`, 0–1.
    pub roughness: Option<f32>,
    /// `metalness(s)`, 0–1.
    pub metalness: Option<f32>,
    /// `emission(s)`: emitted radiance in output units, not negative.
    pub emission: Option<[f32; 3]>,
    /// `reflect(s)`: the mirror reflectance, 0–1.
    pub reflect: Option<[f32; 3]>,
    /// `material(s)`: the closure it returned. A script that defines
    /// `material` gives this alone; the outputs above are then `None`.
    pub closure: Option<Closure>,
}
