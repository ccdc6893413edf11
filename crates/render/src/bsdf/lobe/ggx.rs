//! PLACEHOLDER.

/// Narrowest lobe width.
pub const MIN_ALPHA: f32 = 1e-3;
