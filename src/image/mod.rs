//! Reading, writing and comparing images.

pub mod output;
