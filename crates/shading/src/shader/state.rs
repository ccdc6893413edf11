//! One Lua state with every shader of a [`ShaderSet`](super::ShaderSet)
//! compiled into it: built once per worker thread, then called per shading
//! point without allocating. This module builds it; `compile.rs` compiles
//! each script into it, `invoke.rs` calls the entry points, and `shade.rs`
//! writes the shading point.

use std::cell::{Cell, RefCell};
use std::sync::Arc;
use std::time::Duration;

use luster_core::text::shown;
use mlua::{Function, LightUserData, Lua, LuaOptions, StdLib, Table};

use super::call::Caller;
use super::compile::{Compiled, Makers, WRAPPERS};
use super::error::{ShaderError, ShaderErrorKind};
use super::ffi::{self, IoBlock, Shade};
use super::shade::{has_avx, object_random};
use super::{Entry, ImageSampler, MaterialOutputs, Shared, ENTRIES};

/// The trusted prelude (see its header comment).
const PRELUDE: &str = include_str!("prelude.lua");

/// Each state may hold this much Lua memory; a script that builds huge strings
/// or tables fails with a memory error instead of exhausting the machine.
pub(crate) const MEMORY_LIMIT: usize = 256 * 1024 * 1024;

/// A Lua state and the compiled shaders of one set.
pub(crate) struct ThreadState {
    pub(super) io: IoBlock,
    pub(super) shaders: Vec<Compiled>,
    pub(super) timeout: Duration,
    /// Holds and calls the wrappers; dropped before `lua`.
    pub(super) caller: Caller,
    pub(super) lua: Lua,
    /// The images `texture()` samples. Boxed so the prelude can hold its
    /// address (a thin pointer) for the life of the state; declared after
    /// `lua` so it outlives every Lua value that refers to it.
    _images: Option<Box<Arc<dyn ImageSampler>>>,
    /// LuaJIT's names for the records (`struct 97`) and luster's (`vec3`).
    pub(super) ctype_names: Vec<(String, String)>,
    /// The last object id and its `s.random` (see [`ThreadState::random`]).
    pub(super) last_random: Cell<(u32, f64)>,
    /// Whether the shading point is written with AVX ([`fill_shade`](super::shade::fill_shade)).
    pub(super) avx: bool,
    /// The record [`ShaderSet::material_with`](super::ShaderSet::material_with) writes into.
    pub(super) outputs: RefCell<MaterialOutputs>,
}

impl ThreadState {
    /// Creates the state, runs the prelude, and compiles and runs every
    /// script's top level (each under the per-call timeout).
    pub(crate) fn new(shared: &Shared) -> Result<ThreadState, ShaderError> {
        let (sources, timeout) = (&shared.sources, shared.timeout);
        let internal = |e: mlua::Error| {
            ShaderError::new(ShaderErrorKind::Internal, "(prelude)", format!("shader runtime: {e}"))
        };
        let libs = StdLib::TABLE | StdLib::STRING | StdLib::MATH | StdLib::BIT | StdLib::JIT | StdLib::FFI;
        // SAFETY (of the `unsafe_` constructor, which only marks that the FFI
        // is loaded): the FFI is used by the trusted prelude alone, which hides
        // it from user scripts; see prelude.lua and ffi.rs.
        let lua = unsafe { Lua::unsafe_new_with(libs, LuaOptions::new()) };
        // LuaJIT's allocator can be replaced, so the limit normally works; if a
        // build cannot, scripts still get string.rep's cap, and the state its
        // 64-bit LuaJIT heap.
        let _ = lua.set_memory_limit(MEMORY_LIMIT);

        let log = lua
            .create_function(|_, (name, text, x, y): (String, String, i64, i64)| {
                // The top level runs at pixel -1: its prints always show.
                // What a script prints reaches a terminal: escaped and capped.
                let (name, text) = (shown(&name, false), shown(&text, false));
                match super::debug_pixel() {
                    Some([dx, dy]) if x >= 0 && (x != i64::from(dx) || y != i64::from(dy)) => {}
                    Some(_) if x >= 0 => eprintln!("[shader {name} at pixel {x},{y}] {text}"),
                    _ => eprintln!("[shader {name}] {text}"),
                }
                Ok(())
            })
            .map_err(internal)?;
        let modules = Arc::clone(&shared.modules);
        let load_module = lua
            .create_function(move |_, name: String| {
                // (file as shown, code, canonical path) or (nil, why).
                Ok(match modules.load(&name) {
                    Ok((file, code, key)) => (Some(file), code, Some(key)),
                    Err(why) => (None, why, None),
                })
            })
            .map_err(internal)?;
        let images: Option<Box<Arc<dyn ImageSampler>>> =
            shared.images.as_ref().map(|i| Box::new(Arc::clone(&i.sampler)));
        let images_ctx = images.as_ref().map_or(std::ptr::null_mut(), |b| {
            std::ptr::from_ref::<Arc<dyn ImageSampler>>(b).cast_mut().cast::<std::ffi::c_void>()
        });
        let image_names = lua.create_table().map_err(internal)?;
        for (name, index) in shared.images.iter().flat_map(|i| i.names.iter()) {
            image_names.set(name.as_str(), *index).map_err(internal)?;
        }
        let api: Table = lua
            .load(PRELUDE)
            .set_name("@luster/prelude.lua")
            .call((
                LightUserData(ffi::builtins_address()),
                log,
                LightUserData(images_ctx),
                image_names,
                load_module,
            ))
            .map_err(internal)?;
        super::attributes::install(&lua, &api, &shared.attributes).map_err(internal)?;
        // The C declarations in the prelude must describe Rust's records.
        let sizes: Table = api.get("sizes").map_err(internal)?;
        for (k, size) in [
            ("shade", std::mem::size_of::<Shade>()),
            ("out", std::mem::size_of::<ffi::Out>()),
            ("material", std::mem::size_of::<ffi::MaterialOut>()),
            ("node", std::mem::size_of::<ffi::NodeOut>()),
            ("clock", std::mem::size_of::<ffi::Clock>()),
            ("cell", std::mem::size_of::<ffi::CellOut>()),
            ("ray", std::mem::size_of::<super::trace::RayIn>()),
            ("hit", std::mem::size_of::<super::trace::HitOut>()),
            ("derivs", std::mem::size_of::<ffi::Derivs>()),
        ] {
            if sizes.get::<usize>(k).map_err(internal)? != size {
                let msg = format!("shader runtime: luster_{k} differs between prelude.lua and ffi.rs");
                return Err(ShaderError::new(ShaderErrorKind::Internal, "(prelude)", msg));
            }
        }
        let addr = |k: &str| api.get::<f64>(k).map(|a| a as usize).map_err(internal);
        if !ffi::start_watchdog() {
            let msg = "shader runtime: cannot start the thread that enforces the time limit";
            return Err(ShaderError::new(ShaderErrorKind::Internal, "(prelude)", msg));
        }
        let addresses = ffi::Addresses {
            shade: addr("shade")?,
            shade_b: addr("shade_b")?,
            shade_c: addr("shade_c")?,
            out: addr("out")?,
            material: addr("material")?,
            clock: addr("clock")?,
            derivs: addr("derivs")?,
        };
        let io = IoBlock::new(addresses, ffi::limit_periods(timeout)).ok_or_else(|| {
            ShaderError::new(ShaderErrorKind::Internal, "(prelude)", "shader runtime: bad record addresses")
        })?;

        let ctypes: Table = api.get("ctypes").map_err(internal)?;
        let mut ctype_names = Vec::new();
        for pair in ctypes.pairs::<String, String>() {
            let (name, ctype) = pair.map_err(internal)?;
            // "ctype<struct 97>" in tostring, "'struct 97'" in messages.
            let inner = ctype.trim_start_matches("ctype<").trim_end_matches('>');
            ctype_names.push((format!("'{inner}'"), format!("'{name}'")));
            ctype_names.push((inner.to_string(), name));
        }
        let caller = Caller::new(&lua, sources.len().saturating_mul(WRAPPERS)).map_err(internal)?;
        let mut state = ThreadState {
            io,
            shaders: Vec::with_capacity(sources.len()),
            timeout,
            caller,
            lua,
            _images: images,
            ctype_names,
            last_random: Cell::new((0, object_random(0))),
            avx: has_avx(),
            outputs: RefCell::new(MaterialOutputs::default()),
        };
        let make_env = api.get("make_env").map_err(internal)?;
        let make_entry = api.get("make_entry").map_err(internal)?;
        let make_height3 = api.get("make_height3").map_err(internal)?;
        let make_material = api.get("make_material").map_err(internal)?;
        let tick: Function = api.get("tick").map_err(internal)?;
        let makers =
            Makers { env: make_env, entry: make_entry, height3: make_height3, material: make_material };
        for (index, src) in sources.iter().enumerate() {
            state.add(src, &makers, &tick).map_err(|e| e.with_source(index))?;
        }
        Ok(state)
    }

    /// A call that ran past its deadline fails even when the script caught
    /// the timeout error (with `pcall`) and returned normally: otherwise every
    /// later call could spend the whole limit again.
    pub(super) fn check_deadline(&self, shader: &str) -> Result<(), ShaderError> {
        if !self.io.timed_out() {
            return Ok(());
        }
        Err(ShaderError::new(
            ShaderErrorKind::Timeout,
            shader,
            format!(
                "stopped: the shader ran past its time limit and caught the error, or one library call \
                 outran it ({:.3} s per call; the limit is set with --shader-timeout)",
                self.timeout.as_secs_f64()
            ),
        ))
    }

    /// A Lua error as a shader error, in the author's terms. A recursion
    /// that filled Lua's stack inside compiled code is reported by LuaJIT
    /// with no location at all; it names the script's `file` then.
    pub(super) fn error(&self, shader: &str, file: &str, e: &mlua::Error) -> ShaderError {
        let mut err =
            ShaderError::from_lua(shader, e, self.io.timed_out(), self.io.bad_result(), self.timeout);
        err.message = self.in_author_terms(&err.message);
        if err.message.starts_with(super::error::RECURSION) {
            err.message = luster_core::text::shown(&format!("{file}: {}", err.message), false).into_owned();
        }
        err
    }

    /// LuaJIT's messages with luster's type names for its records (`'struct
    /// 97'` is a `vec3`) and without the word "cdata", which means nothing to
    /// a shader author.
    fn in_author_terms(&self, message: &str) -> String {
        let mut m = message.to_string();
        for (ctype, name) in &self.ctype_names {
            m = m.replace(ctype.as_str(), name);
        }
        m.replace("a cdata value", "a luster value (vec3, s or s.uv)")
            .replace("cdata", "luster value (vec3, s or s.uv)")
    }

    /// Which entry points shader `id` defines (`material` has no wrapper
    /// of its own: see [`Compiled::closure`]).
    pub(crate) fn entries(&self, id: usize) -> [bool; ENTRIES] {
        self.shaders.get(id).map_or([false; ENTRIES], |c| {
            let mut e = c.entries.map(|e| e.is_some());
            e[Entry::Material as usize] = c.closure;
            e
        })
    }
}
