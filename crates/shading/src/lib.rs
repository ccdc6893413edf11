//! luster-shading: the procedural shading language — Lua scripts compiled by
//! LuaJIT in a sandbox with time and memory limits, their built-ins and
//! prelude — and the noise functions both the language and the course's
//! textures use.
#![warn(missing_docs)]

pub mod noise;
pub mod shader;
