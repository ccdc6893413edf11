//! Reading, writing and comparing images.
