//! Compiling one shader script into a [`ThreadState`]: instrumenting it
//! for the time limit, running its top level in its sandbox, and keeping
//! the entry wrappers the prelude makes for it on the state's call thread.

use mlua::{Function, Table, Value};

use super::call::Slot;
use super::declared::{self, DeclaredParam};
use super::error::{ShaderError, ShaderErrorKind};
use super::ffi::Shade;
use super::instrument::{instrument, ScanError};
use super::params;
use super::state::ThreadState;
use super::{Entry, ParamValue, ShaderSource, ENTRIES};

/// The entry wrappers of one compiled shader, as kept by the state's
/// [`Caller`](super::call::Caller).
pub(super) struct Compiled {
    pub(super) name: String,
    /// The script's file, for errors LuaJIT raises without a location.
    pub(super) file: String,
    pub(super) entries: [Option<Slot>; ENTRIES],
    /// `height` at three points in one call, for bump mapping.
    pub(super) height3: Option<Slot>,
    /// Every material output in one call (`DecalMode material`).
    pub(super) material: Option<Slot>,
    /// Whether the script defines `material(s)`: then `material` calls it
    /// alone.
    pub(super) closure: bool,
    /// What its `params{...}` declares (empty without one).
    pub(super) declared: Vec<DeclaredParam>,
}

/// Wrappers kept per shader: one per entry point, `height3` and `material`.
pub(super) const WRAPPERS: usize = ENTRIES + 2;

/// The entry wrappers of one shader as the prelude made them.
struct Wrappers {
    name: String,
    file: String,
    entries: [Option<Function>; ENTRIES],
    height3: Option<Function>,
    material: Option<Function>,
    closure: bool,
    declared: Vec<DeclaredParam>,
}

/// The prelude's functions that build a script's sandbox and its wrappers.
pub(super) struct Makers {
    pub(super) env: Function,
    pub(super) entry: Function,
    pub(super) height3: Function,
    pub(super) material: Function,
}

impl ThreadState {
    /// Compiles `src` and keeps its wrappers: the next shader id.
    pub(super) fn add(
        &mut self,
        src: &ShaderSource,
        makers: &Makers,
        tick: &Function,
    ) -> Result<(), ShaderError> {
        let wrappers = self.compile(src, makers, tick)?;
        let compiled = self.keep(wrappers)?;
        self.shaders.push(compiled);
        Ok(())
    }

    fn compile(&self, src: &ShaderSource, makers: &Makers, tick: &Function) -> Result<Wrappers, ShaderError> {
        let Makers { env: make_env, entry: make_entry, height3: make_height3, material: make_material } =
            makers;
        let name = src.name.as_str();
        let file = src.path.display().to_string();
        let lua_err = |e: mlua::Error| self.error(name, &file, &e);
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
        let (has_params, declaration): (bool, Table) = declared.call(()).map_err(lua_err)?;
        if !has_params {
            params::check_undeclared(src)
                .map_err(|m| ShaderError::new(ShaderErrorKind::Parameter, name, format!("{file}: {m}")))?;
        }
        let declared = declared::from_lua(&declaration).unwrap_or_default();

        let mut entries: [Option<Function>; ENTRIES] = Default::default();
        for entry in Entry::ALL {
            // material(s) has no wrapper of its own: `make_material` calls it.
            if entry != Entry::Material {
                entries[entry as usize] =
                    make_entry.call((env.clone(), entry.name(), name)).map_err(lua_err)?;
            }
        }
        let closure = matches!(env.raw_get::<Value>(Entry::Material.name()), Ok(Value::Function(_)));
        if entries.iter().all(Option::is_none) && !closure {
            return Err(ShaderError::new(
                ShaderErrorKind::NoEntryPoint,
                name,
                format!(
                    "{file}: defines none of the functions color, height, reflect, specular, roughness, \
                     metalness, emission, material or density"
                ),
            ));
        }
        let height3 = make_height3.call((env.clone(), name)).map_err(lua_err)?;
        let material = make_material.call((env, name)).map_err(lua_err)?;
        Ok(Wrappers { name: name.to_string(), file, entries, height3, material, closure, declared })
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
        Ok(Compiled {
            name: w.name,
            file: w.file,
            entries,
            height3,
            material,
            closure: w.closure,
            declared: w.declared,
        })
    }
}
