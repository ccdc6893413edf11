//! Sandbox escape attempts: each must fail with a clear error, and none may
//! reach the real globals, the FFI or the prelude's locals.

use super::tests::{color_err, input, set_of};
use super::*;

/// Runs `expr` inside a color shader and returns the error it must raise.
fn escape(expr: &str) -> ShaderError {
    let e = color_err(&format!("function color(s)\n  {expr}\n  return 1, 1, 1\nend"));
    assert!(
        matches!(e.kind, ShaderErrorKind::Runtime | ShaderErrorKind::Syntax),
        "{expr}: unexpected kind: {e}"
    );
    assert!(e.message.contains("test.lua:"), "{expr}: no location: {e}");
    e
}

#[test]
fn dangerous_globals_are_absent() {
    for expr in [
        "os.execute('true')",
        "io.open('/etc/passwd')",
        "package.loaded.os.exit()",
        "debug.getinfo(1)",
        "ffi.C.abort()",
        "jit.off()",
        "getfenv(1)",
        "setfenv(1, {})",
        "loadstring('return 1')()",
        "load('return 1')()",
        "dofile('/etc/passwd')",
        "loadfile('/etc/passwd')",
        "newproxy(true)",
        "module('x')",
        "string.dump(color)",
        "math.random()",
    ] {
        let e = escape(expr);
        assert!(e.message.contains("was removed from shaders"), "{expr}: {e}");
    }
}

#[test]
fn string_metatable_is_hidden_and_cleaned() {
    let e = escape("local mt = getmetatable('') ; local dump = mt.__index.dump");
    assert!(e.message.contains("boolean value"), "{e}");
    let e = escape("local f = ('').dump ; f(color)");
    assert!(e.message.contains("a nil value"), "{e}");
    escape("setmetatable('', {})");
    // rep is capped on the real table too, which `("x"):rep` reaches.
    let e = escape("local s = ('x'):rep(1e12)");
    assert!(e.message.contains("limit"), "{e}");
}

#[test]
fn globals_tricks_do_not_reach_the_real_environment() {
    let set = set_of(
        "function color(s)
           local reach = 0
           if rawget(_G, 'os') ~= nil or rawget(_G, 'ffi') ~= nil then reach = reach + 1 end
           if rawget(_G, 'io') ~= nil or rawget(_G._G, 'debug') ~= nil then reach = reach + 1 end
           if pcall(function() return _G.io end) then reach = reach + 1 end
           for k, v in pairs(_G) do
             if k == 'ffi' or k == 'jit' or k == 'os' or k == 'io' or k == 'package' then reach = reach + 1 end
           end
           -- The globals' metatable (which explains removed names) is hidden.
           if getmetatable(_G) ~= false then reach = reach + 1 end
           if getmetatable(s) ~= 'ffi' then reach = reach + 1 end
           return reach, 0, 0
         end",
    )
    .unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [0.0, 0.0, 0.0]);
}

#[test]
fn the_tick_cannot_be_replaced_or_disabled() {
    for code in [
        "__luster_tick = function() end\nfunction color(s) while true do end end",
        "local __luster_tick\nfunction color(s) while true do end end",
        "function color(s) local t = _G['__luster' .. '_tick'] ; return t, 0, 0 end",
    ] {
        match set_of(code) {
            Err(e) => assert_eq!(e.kind, ShaderErrorKind::Syntax, "{code}: {e}"),
            Ok(set) => {
                let e = set.color(0, &input([0.0; 3])).unwrap_err();
                assert_eq!(e.kind, ShaderErrorKind::BadResult, "{code}: {e}");
            }
        }
    }
    // The chunk's `...` is the tick itself, which is harmless to hold.
    let set = set_of("local t = ...\nfunction color(s) t() return 1, 1, 1 end").unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [1.0, 1.0, 1.0]);
}

#[test]
fn cdata_gives_no_pointer_arithmetic_or_out_of_bounds_access() {
    for expr in [
        "local p = s + 1",
        "local x = s[1000]",
        "local q = s.P + 'x'",
        "local q = s.P * {}",
        "s.P = 'x'",
        "local v = s.nothing",
    ] {
        escape(expr);
    }
}

#[test]
fn builtins_do_not_leak_the_prelude() {
    // Functions hand out no environment or upvalues without the debug library;
    // the built-ins are plain Lua functions, not cdata function pointers.
    let set = set_of(
        "function color(s)
           local leaks = 0
           for _, f in ipairs({ perlin3, fbm, voronoi, vec3, ramp, brick }) do
             if type(f) ~= 'function' then leaks = leaks + 1 end
           end
           if rawget(_G, 'getfenv') ~= nil or rawget(_G, 'debug') ~= nil then leaks = leaks + 1 end
           return leaks, 0, 0
         end",
    )
    .unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [0.0, 0.0, 0.0]);
}

#[test]
fn collectgarbage_allows_only_count() {
    let set = set_of("function height(s) return collectgarbage('count') end").unwrap();
    assert!(set.height(0, &input([0.0; 3])).unwrap() > 0.0);
    let e = escape("collectgarbage('stop')");
    assert!(e.message.contains("count"), "{e}");
}
