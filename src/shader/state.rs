//! One Lua state with every shader of a [`ShaderSet`](super::ShaderSet)
//! compiled into it: built once per worker thread, then called per shading
//! point without allocating.

use std::time::Duration;

use mlua::{Function, LightUserData, Lua, LuaOptions, StdLib, Table, Value};

use std::cell::Cell;
use std::os::raw::c_int;

use super::call::{Caller, Slot};
use super::error::{ShaderError, ShaderErrorKind};
use super::ffi::{self, IoBlock, Shade};
use super::instrument::{instrument, ScanError};
use super::params;
use super::threads::MISS;
use super::{Entry, ImageSampler, ParamValue, ShadeInput, ShaderSource, Shared, ENTRIES};
use std::sync::Arc;

/// The trusted prelude (see its header comment).
const PRELUDE: &str = include_str!("prelude.lua");

/// Each state may hold this much Lua memory; a script that builds huge strings
/// or tables fails with a memory error instead of exhausting the machine.
pub(crate) const MEMORY_LIMIT: usize = 256 * 1024 * 1024;

/// The entry wrappers of one compiled shader, as kept by the state's [`Caller`].
struct Compiled {
    name: String,
    entries: [Option<Slot>; ENTRIES],
    /// `height` at three points in one call, for bump mapping.
    height3: Option<Slot>,
    /// Every material output in one call (`DecalMode material`).
    material: Option<Slot>,
}

/// Wrappers kept per shader: one per entry point, `height3` and `material`.
const WRAPPERS: usize = ENTRIES + 2;

/// The entry wrappers of one shader as the prelude made them.
struct Wrappers {
    name: String,
    entries: [Option<Function>; ENTRIES],
    height3: Option<Function>,
    material: Option<Function>,
}

/// A Lua state and the compiled shaders of one set.
pub(crate) struct ThreadState {
    io: IoBlock,
    shaders: Vec<Compiled>,
    timeout: Duration,
    /// Holds and calls the wrappers; dropped before `lua`.
    caller: Caller,
    lua: Lua,
    /// The images `texture()` samples. Boxed so the prelude can hold its
    /// address (a thin pointer) for the life of the state; declared after
    /// `lua` so it outlives every Lua value that refers to it.
    _images: Option<Box<Arc<dyn ImageSampler>>>,
    /// LuaJIT's names for the records (`struct 97`) and luster's (`vec3`).
    ctype_names: Vec<(String, String)>,
    /// The last object id and its `s.random` (see [`ThreadState::random`]).
    last_random: Cell<(u32, f64)>,
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
        // The C declarations in the prelude must describe Rust's records.
        let sizes: Table = api.get("sizes").map_err(internal)?;
        for (k, size) in [
            ("shade", std::mem::size_of::<Shade>()),
            ("out", std::mem::size_of::<ffi::Out>()),
            ("material", std::mem::size_of::<ffi::MaterialOut>()),
            ("clock", std::mem::size_of::<ffi::Clock>()),
            ("cell", std::mem::size_of::<ffi::CellOut>()),
        ] {
            if sizes.get::<usize>(k).map_err(internal)? != size {
                let msg = format!("shader runtime: luster_{k} differs between prelude.lua and ffi.rs");
                return Err(ShaderError::new(ShaderErrorKind::Internal, "(prelude)", msg));
            }
        }
        let addr = |k: &str| api.get::<f64>(k).map(|a| a as usize).map_err(internal);
        let timeout_ns = u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX);
        let io = IoBlock::new(
            addr("shade")?,
            addr("shade_b")?,
            addr("shade_c")?,
            addr("out")?,
            addr("material")?,
            addr("clock")?,
            timeout_ns,
        )
        .ok_or_else(|| {
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
        };
        let make_env: Function = api.get("make_env").map_err(internal)?;
        let make_entry: Function = api.get("make_entry").map_err(internal)?;
        let make_height3: Function = api.get("make_height3").map_err(internal)?;
        let make_material: Function = api.get("make_material").map_err(internal)?;
        let tick: Function = api.get("tick").map_err(internal)?;
        for src in sources {
            let makers = [&make_entry, &make_height3, &make_material];
            let compiled = state.compile(src, &make_env, &makers, &tick)?;
            let compiled = state.keep(compiled)?;
            state.shaders.push(compiled);
        }
        Ok(state)
    }

    fn compile(
        &self,
        src: &ShaderSource,
        make_env: &Function,
        [make_entry, make_height3, make_material]: &[&Function; 3],
        tick: &Function,
    ) -> Result<Wrappers, ShaderError> {
        let name = src.name.as_str();
        let file = src.path.display().to_string();
        let lua_err = |e: mlua::Error| self.error(name, &e);
        let code = match instrument(&src.code) {
            Ok(code) => code,
            Err(ScanError::Reserved { line, name: word }) => {
                return Err(ShaderError::new(
                    ShaderErrorKind::Syntax,
                    name,
                    format!("{file}:{line}: the name '{word}' is reserved for the shader runtime"),
                ))
            }
            Err(ScanError::Unterminated { line }) => {
                // Lua's own message is the better one; the scanner's is the
                // fallback should Lua ever accept what the scanner cannot close.
                self.lua.load(&src.code).set_name(format!("@{file}")).into_function().map_err(lua_err)?;
                return Err(ShaderError::new(
                    ShaderErrorKind::Syntax,
                    name,
                    format!("{file}:{line}: a string or comment opened here does not close"),
                ));
            }
        };

        let params = self.lua.create_table().map_err(lua_err)?;
        for (key, value) in &src.params {
            let v = match value {
                ParamValue::Number(x) => Value::Number(*x),
                ParamValue::Text(s) => Value::String(self.lua.create_string(s).map_err(lua_err)?),
                ParamValue::Vec3(v) => Value::Table(self.lua.create_sequence_from(*v).map_err(lua_err)?),
            };
            params.set(key.as_str(), v).map_err(lua_err)?;
        }
        let (env, declared): (Table, Function) = make_env.call((name, params)).map_err(lua_err)?;
        // Lua shortens long chunk names from the left, keeping the file name.
        let chunk = self
            .lua
            .load(&code)
            .set_name(format!("@{file}"))
            .set_environment(env.clone())
            .into_function()
            .map_err(lua_err)?;
        self.io.begin(|s| *s = Shade { pixel_x: -1, pixel_y: -1, ..Shade::default() });
        chunk.call::<()>(tick.clone()).map_err(lua_err)?;
        self.check_deadline(name)?;
        if !declared.call::<bool>(()).map_err(lua_err)? {
            params::check_undeclared(src)
                .map_err(|m| ShaderError::new(ShaderErrorKind::Parameter, name, format!("{file}: {m}")))?;
        }

        let mut entries: [Option<Function>; ENTRIES] = Default::default();
        for entry in Entry::ALL {
            entries[entry as usize] = make_entry.call((env.clone(), entry.name(), name)).map_err(lua_err)?;
        }
        if entries.iter().all(Option::is_none) {
            return Err(ShaderError::new(
                ShaderErrorKind::NoEntryPoint,
                name,
                format!(
                    "{file}: defines none of the functions color, height, reflect, specular, roughness, \
                     metalness, emission or density"
                ),
            ));
        }
        let height3 = make_height3.call((env.clone(), name)).map_err(lua_err)?;
        let material = make_material.call((env, name)).map_err(lua_err)?;
        Ok(Wrappers { name: name.to_string(), entries, height3, material })
    }

    /// Puts a shader's wrappers on the caller's stack.
    fn keep(&mut self, w: Wrappers) -> Result<Compiled, ShaderError> {
        let (lua, caller) = (&self.lua, &mut self.caller);
        let internal = |e: mlua::Error| {
            ShaderError::new(ShaderErrorKind::Internal, &w.name, format!("shader runtime: {e}"))
        };
        let mut keep = |f: &Option<Function>| f.as_ref().map(|f| caller.keep(lua, f)).transpose();
        let mut entries = [None; ENTRIES];
        for (slot, f) in entries.iter_mut().zip(&w.entries) {
            *slot = keep(f).map_err(internal)?;
        }
        let height3 = keep(&w.height3).map_err(internal)?;
        let material = keep(&w.material).map_err(internal)?;
        Ok(Compiled { name: w.name, entries, height3, material })
    }

    /// A call that ran past its deadline fails even when the script caught
    /// the timeout error (with `pcall`) and returned normally: otherwise every
    /// later call could spend the whole limit again.
    fn check_deadline(&self, shader: &str) -> Result<(), ShaderError> {
        if !self.io.timed_out() {
            return Ok(());
        }
        Err(ShaderError::new(
            ShaderErrorKind::Timeout,
            shader,
            format!(
                "stopped: the shader ran past its time limit and caught the error ({:.3} s per call; \
                 the limit is set with --shader-timeout)",
                self.timeout.as_secs_f64()
            ),
        ))
    }

    fn error(&self, shader: &str, e: &mlua::Error) -> ShaderError {
        let mut err =
            ShaderError::from_lua(shader, e, self.io.timed_out(), self.io.bad_result(), self.timeout);
        err.message = self.in_author_terms(&err.message);
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

    /// Which entry points shader `id` defines.
    pub(crate) fn entries(&self, id: usize) -> [bool; ENTRIES] {
        self.shaders.get(id).map_or([false; ENTRIES], |c| c.entries.map(|e| e.is_some()))
    }

    /// Calls one entry point; the result's channels (a height in `[0]`).
    pub(crate) fn call(&self, id: usize, entry: Entry, input: &ShadeInput) -> Result<[f64; 3], ShaderError> {
        let mut rgb = [0.0; 3];
        match self.call_fast(id, entry, input, &mut rgb) {
            0 => Ok(rgb),
            code => self.finish(id, entry, input, code),
        }
    }

    /// The common case of a call (a defined entry, a clean return within
    /// the time limit, no `--debug-pixel`): 0, with the result's channels in
    /// `rgb`. Otherwise a code for [`ThreadState::finish`]: [`MISS`] when
    /// the call did not run (no such entry), or [`RAN`] with the call's
    /// status. A bare code, so the hot path moves no error-sized value.
    #[inline]
    pub(crate) fn call_fast(&self, id: usize, entry: Entry, input: &ShadeInput, rgb: &mut [f64; 3]) -> u32 {
        let Some(f) = self.shaders.get(id).and_then(|s| s.entries[entry as usize]) else {
            return MISS;
        };
        let random = self.random(input.instance_id);
        self.io.begin(|s| write_shade(s, input, random));
        let status = self.caller.call(f);
        if status == mlua::ffi::LUA_OK && !self.io.timed_out() && super::debug_pixel().is_none() {
            let o = self.io.out();
            *rgb = [o.r, o.g, o.b];
            return 0;
        }
        ran(status)
    }

    /// What a code from [`ThreadState::call_fast`] amounts to.
    #[cold]
    #[inline(never)]
    pub(crate) fn finish(
        &self,
        id: usize,
        entry: Entry,
        input: &ShadeInput,
        code: u32,
    ) -> Result<[f64; 3], ShaderError> {
        match status_of(code) {
            Some(status) => self.finish_call(id, entry, input, status),
            None => Err(self.no_entry(id, entry.name())),
        }
    }

    /// [`object_random`] of `id`, remembered for the next call: a pixel's
    /// points mostly lie on one object.
    #[inline]
    fn random(&self, id: u32) -> f64 {
        let (last, r) = self.last_random.get();
        if last == id {
            return r;
        }
        let r = object_random(id);
        self.last_random.set((id, r));
        r
    }

    /// [`ThreadState::call`] past its fast path: an error, a timeout the
    /// script caught, or a call to show for `--debug-pixel`.
    #[cold]
    #[inline(never)]
    fn finish_call(
        &self,
        id: usize,
        entry: Entry,
        input: &ShadeInput,
        status: c_int,
    ) -> Result<[f64; 3], ShaderError> {
        let shader = &self.shaders[id];
        let result = self.outcome(&shader.name, status).map(|()| {
            let o = self.io.out();
            [o.r, o.g, o.b]
        });
        if super::debug_pixel() == Some(input.pixel) {
            let out = match &result {
                Ok(c)
                    if matches!(
                        entry,
                        Entry::Height | Entry::Density | Entry::Roughness | Entry::Metalness
                    ) =>
                {
                    format!("{}", c[0])
                }
                Ok(c) => format!("{} {} {}", c[0], c[1], c[2]),
                Err(e) => format!("error: {}", e.message),
            };
            eprintln!(
                "[shader {} at pixel {},{}] {}(s) -> {out}\n  s = {}",
                shader.name,
                input.pixel[0],
                input.pixel[1],
                entry.name(),
                describe(input)
            );
        }
        result
    }

    /// What a finished call amounts to: its error (popped off the call
    /// thread), a caught timeout, or success.
    fn outcome(&self, shader: &str, status: c_int) -> Result<(), ShaderError> {
        if status != mlua::ffi::LUA_OK {
            let e = self.caller.pop_error(&self.lua, status);
            return Err(self.error(shader, &e));
        }
        self.check_deadline(shader)
    }

    /// The usage error for a missing shader or entry point.
    #[cold]
    #[inline(never)]
    fn no_entry(&self, id: usize, entry: &str) -> ShaderError {
        match self.shaders.get(id) {
            None => ShaderError::new(
                ShaderErrorKind::Usage,
                &format!("#{id}"),
                format!("no shader with id {id} (the set has {})", self.shaders.len()),
            ),
            Some(shader) if entry == "material" => ShaderError::new(
                ShaderErrorKind::Usage,
                &shader.name,
                "the script defines none of the material outputs (color, specular, roughness, metalness, \
                 emission, reflect)",
            ),
            Some(shader) => ShaderError::new(
                ShaderErrorKind::Usage,
                &shader.name,
                format!("the script defines no {entry}() function"),
            ),
        }
    }

    /// Calls every material output shader `id` defines, in one Lua call.
    pub(crate) fn call_material(
        &self,
        id: usize,
        input: &ShadeInput,
    ) -> Result<ffi::MaterialOut, ShaderError> {
        let Some(f) = self.shaders.get(id).and_then(|s| s.material) else {
            return Err(self.no_entry(id, "material"));
        };
        self.io.begin_material(|s| write_shade(s, input, self.random(input.instance_id)));
        let status = self.caller.call(f);
        let shader = &self.shaders[id];
        let result = self.outcome(&shader.name, status).map(|()| self.io.material());
        if super::debug_pixel() == Some(input.pixel) {
            let out = match &result {
                Ok(m) => format!("{m:?}"),
                Err(e) => format!("error: {}", e.message),
            };
            eprintln!(
                "[shader {} at pixel {},{}] material(s) -> {out}\n  s = {}",
                shader.name,
                input.pixel[0],
                input.pixel[1],
                describe(input)
            );
        }
        result
    }

    /// Calls `height` at three points in one Lua call (bump mapping).
    pub(crate) fn call_height3(&self, id: usize, inputs: &[ShadeInput; 3]) -> Result<[f64; 3], ShaderError> {
        let mut h = [0.0; 3];
        match self.call_height3_fast(id, inputs, &mut h) {
            0 => Ok(h),
            code => self.finish_height3(id, code),
        }
    }

    /// [`ThreadState::call_fast`] for [`ThreadState::call_height3`].
    #[inline]
    pub(crate) fn call_height3_fast(&self, id: usize, inputs: &[ShadeInput; 3], h: &mut [f64; 3]) -> u32 {
        let Some(f) = self.shaders.get(id).and_then(|s| s.height3) else {
            return MISS;
        };
        let random = inputs.map(|i| self.random(i.instance_id));
        self.io.begin3(|k, s| write_shade(s, &inputs[k], random[k]));
        let status = self.caller.call(f);
        if status == mlua::ffi::LUA_OK && !self.io.timed_out() {
            let o = self.io.out();
            *h = [o.r, o.g, o.b];
            return 0;
        }
        ran(status)
    }

    /// What a code from [`ThreadState::call_height3_fast`] amounts to.
    #[cold]
    #[inline(never)]
    pub(crate) fn finish_height3(&self, id: usize, code: u32) -> Result<[f64; 3], ShaderError> {
        let Some(status) = status_of(code) else {
            return Err(self.no_entry(id, "height"));
        };
        self.outcome(&self.shaders[id].name, status).map(|()| {
            let o = self.io.out();
            [o.r, o.g, o.b]
        })
    }
}

/// A code from a fast call (`call_fast`) that ran and needs finishing: the
/// call's status, marked so that it differs from 0 and from [`MISS`].
pub(crate) const RAN: u32 = 1 << 31;

fn ran(status: c_int) -> u32 {
    RAN | (status as u32 & 0xffff)
}

/// The Lua status in a [`RAN`] code; `None` for [`MISS`].
fn status_of(code: u32) -> Option<c_int> {
    (code != MISS && code & RAN != 0).then_some((code & 0xffff) as c_int)
}

/// Writes one shading point into the record the prelude reads, in place.
/// The record is destructured whole so that a field added to it cannot be
/// left unwritten.
#[inline(always)]
fn write_shade(s: &mut Shade, i: &ShadeInput, random_value: f64) {
    let v = |a: [f32; 3]| ffi::Vec3 { x: a[0].into(), y: a[1].into(), z: a[2].into() };
    let int = |x: u32| i32::try_from(x).unwrap_or(i32::MAX);
    let Shade {
        p,
        pw,
        pc,
        n,
        ng,
        i: incident,
        v: view,
        dpdu,
        dpdv,
        dpdx,
        dpdy,
        uv,
        time,
        filterwidth,
        random,
        object_id,
        instance_id,
        depth,
        pixel_x,
        pixel_y,
        pad,
    } = s;
    *p = v(i.p);
    *pw = v(i.pw);
    *pc = v(i.pc);
    *n = v(i.n);
    *ng = v(i.ng);
    *incident = v(i.i);
    *view = v(i.i.map(|c| -c));
    *dpdu = v(i.dpdu);
    *dpdv = v(i.dpdv);
    *dpdx = v(i.dpdx);
    *dpdy = v(i.dpdy);
    *uv = ffi::Vec2 { u: i.uv[0].into(), v: i.uv[1].into() };
    *time = i.time.into();
    *filterwidth = i.filterwidth.into();
    *random = random_value;
    *object_id = int(i.object_id);
    *instance_id = int(i.instance_id);
    *depth = int(i.depth);
    *pixel_x = int(i.pixel[0]);
    *pixel_y = int(i.pixel[1]);
    *pad = 0;
}

/// The shading point as `--debug-pixel` prints it.
fn describe(i: &ShadeInput) -> String {
    let v = |a: [f32; 3]| format!("({}, {}, {})", a[0], a[1], a[2]);
    format!(
        "{{ P = {}, Pw = {}, Pc = {}, N = {}, Ng = {}, I = {}, uv = ({}, {}), dPdu = {}, dPdv = {}, \
         dPdx = {}, dPdy = {}, filterwidth = {}, object_id = {}, instance_id = {}, depth = {}, time = {} }}",
        v(i.p),
        v(i.pw),
        v(i.pc),
        v(i.n),
        v(i.ng),
        v(i.i),
        i.uv[0],
        i.uv[1],
        v(i.dpdu),
        v(i.dpdv),
        v(i.dpdx),
        v(i.dpdy),
        i.filterwidth,
        i.object_id,
        i.instance_id,
        i.depth,
        i.time
    )
}

/// A repeatable number in [0, 1) per object (SplitMix64's finaliser): the
/// same on every thread and run, different between neighbouring ids.
pub(crate) fn object_random(id: u32) -> f64 {
    let mut z = u64::from(id).wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}
