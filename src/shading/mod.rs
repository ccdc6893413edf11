//! Materials and the Fresnel equations (lights are in [`crate::light`]).

pub mod fresnel;
pub mod material;

pub use material::Material;
