//! Calling the entry wrappers through Lua's C API, not `Function::call`.
//!
//! A wrapper takes no arguments and returns nothing: the shading point and
//! the result travel in the FFI records (`ffi.rs`). mlua's general call
//! still pushes its traceback handler, fetches the function from its
//! reference thread (`lua_xmove`), checks the stack and counts results; with
//! the lock and the stack guard, that outweighs an empty shader's own work. So
//! each state keeps its wrappers on the stack of a Lua thread of its own,
//! and a call is one `lua_pushvalue` and one `lua_pcall` there.
//!
//! A call's message handler (kept in slot 1) appends the stack traceback to
//! a string error, as mlua's calls do: when the error was raised inside the
//! runtime's own Lua (a library function that recursed too deeply), the
//! traceback holds the script line that called it (`error.rs`).
//!
//! Errors keep their meaning: a string error (what `error` in a script, the
//! timeout and the result checks raise) becomes `RuntimeError` or, when the
//! allocator failed, `MemoryError`; any other error value (a Rust callback's
//! wrapped error, a table) is handed to mlua to convert as it would have.
//! Without mlua's handler the message has no traceback appended, which the
//! shader errors cut off anyway (`error.rs`).
//!
//! # Safety
//!
//! `l` is the state of a Lua thread that `_thread` references, so it lives
//! as long as the [`Caller`], which its `ThreadState` drops before the `Lua`
//! (field order). Only this module touches that thread's stack: slot 1
//! holds the message handler and slots `2..=base` the kept functions, and every call leaves the top at
//! `base` again. A state and its caller are used by one OS thread only
//! (`threads.rs`), and never re-entrantly: no built-in calls back into Rust
//! shading.

use std::os::raw::c_int;

use mlua::ffi as lua;
use mlua::{Function, Lua, Thread, Value};

/// Free stack slots kept above the functions: a call needs one.
const HEADROOM: c_int = 8;

/// The message handler of every call (see the module doc).
unsafe extern "C-unwind" fn traceback(l: *mut lua::lua_State) -> c_int {
    if lua::lua_type(l, 1) == lua::LUA_TSTRING && lua::lua_checkstack(l, lua::LUA_TRACEBACK_STACK) != 0 {
        let msg = lua::lua_tostring(l, 1);
        lua::luaL_traceback(l, l, msg, 1);
    }
    1
}

/// Where a function kept by a [`Caller`] sits on its stack.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slot(c_int);

/// A Lua thread whose stack holds the functions to call.
pub(crate) struct Caller {
    l: *mut lua::lua_State,
    base: c_int,
    /// Slots the stack was grown to hold.
    room: c_int,
    _thread: Thread,
}

impl Caller {
    /// A caller on a new thread of `lua`, with room for `capacity` functions.
    pub(crate) fn new(lua: &Lua, capacity: usize) -> mlua::Result<Caller> {
        let mut l: *mut lua::lua_State = std::ptr::null_mut();
        let room = c_int::try_from(capacity).unwrap_or(c_int::MAX).saturating_add(HEADROOM + 1);
        let mut grown = false;
        // SAFETY: the closure runs protected on `lua`'s own state with room
        // for one value (exec_raw checks it); the new thread is left there
        // as exec_raw's result, which anchors it.
        let thread: Thread = unsafe {
            lua.exec_raw((), |s| {
                l = lua::lua_newthread(s);
                // A fresh thread's stack is small; grow it once, here, where
                // an allocation failure cannot unwind through a call.
                grown = lua::lua_checkstack(l, room) != 0;
                if grown {
                    lua::lua_pushcfunction(l, traceback);
                }
            })?
        };
        if l.is_null() || !grown {
            return Err(mlua::Error::MemoryError("no stack for the shader call thread".into()));
        }
        Ok(Caller { l, base: 1, room, _thread: thread })
    }

    /// Keeps `f` on the stack for [`Caller::call`].
    pub(crate) fn keep(&mut self, lua: &Lua, f: &Function) -> mlua::Result<Slot> {
        let l = self.l;
        if self.base + 1 + HEADROOM > self.room {
            return Err(mlua::Error::RuntimeError("shader call thread is full".into()));
        }
        // SAFETY: exec_raw pushed `f` onto its protected state; it moves to
        // our thread, whose stack `new` grew for it (checked just above).
        unsafe {
            lua.exec_raw::<()>(f.clone(), |s| lua::lua_xmove(s, l, 1))?;
            self.base = lua::lua_gettop(l);
        }
        Ok(Slot(self.base))
    }

    /// Calls the function at `slot` with no arguments, discarding results:
    /// `LUA_OK`, or the status of a failed call, whose error
    /// [`Caller::pop_error`] then takes. A bare status, not an
    /// `mlua::Result`, so the hot path moves no error-sized value around.
    #[inline(always)]
    pub(crate) fn call(&self, slot: Slot) -> c_int {
        // SAFETY: see the module doc; `slot` came from `keep` on this caller,
        // and the headroom leaves space for the pushed copy.
        unsafe {
            lua::lua_pushvalue(self.l, slot.0);
            lua::lua_pcall(self.l, 0, 0, 1)
        }
    }

    /// Drops the error a failed call left on the stack (a call that runs
    /// again: `invoke.rs`).
    pub(crate) fn drop_error(&self) {
        // SAFETY: a failed call left its error value on top of the stack
        // (module doc); this restores the top to `base`.
        unsafe { lua::lua_settop(self.l, self.base) }
    }

    /// The error a failed call left on the stack, which it pops.
    #[cold]
    pub(crate) fn pop_error(&self, lua: &Lua, status: c_int) -> mlua::Error {
        // SAFETY: a failed call left its error value on top of the stack
        // (module doc); this pops it and restores the top to `base`.
        unsafe { self.pop_error_raw(lua, status) }
    }

    unsafe fn pop_error_raw(&self, lua: &Lua, status: c_int) -> mlua::Error {
        let l = self.l;
        let err = if lua::lua_type(l, -1) == lua::LUA_TSTRING {
            let mut len = 0usize;
            let p = lua::lua_tolstring(l, -1, &mut len);
            let text = if p.is_null() {
                String::new()
            } else {
                String::from_utf8_lossy(std::slice::from_raw_parts(p.cast::<u8>(), len)).into_owned()
            };
            if status == lua::LUA_ERRMEM {
                mlua::Error::MemoryError(text)
            } else {
                mlua::Error::RuntimeError(text)
            }
        } else {
            match lua.exec_raw::<Value>((), |s| lua::lua_xmove(l, s, 1)) {
                Ok(Value::Error(e)) => *e,
                Ok(v) => mlua::Error::RuntimeError(
                    v.to_string().unwrap_or_else(|_| format!("<{}>", v.type_name())),
                ),
                Err(e) => e,
            }
        };
        lua::lua_settop(l, self.base);
        err
    }
}
