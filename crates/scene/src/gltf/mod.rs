//! glTF 2.0 scenes (`.gltf` with its buffers, or `.glb`), read with the
//! `gltf` crate into a plain [`Description`](crate::Description).

pub mod material;
