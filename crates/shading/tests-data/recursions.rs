// The recursions through library functions the shader sandbox must stop
// with a Lua error, shared by the shading crate's unit tests
// (`shader/tests_limits.rs`) and the hostile-input tests
// (`crates/luster/tests/it/hostile/shaders2.rs`), which `include!` it.

/// Every way a script can make C call back into Lua that calls the same C
/// function again, at the top level and in a call, bare and inside `pcall`.
const RECURSIONS: &[(&str, &str)] = &[
    ("gsub function", "local function f(m) return (string.gsub('a', 'a', f)) end\nlocal function go() f('a') end"),
    (
        "gsub table __index",
        "local t = setmetatable({}, {__index = function(t, k) return (string.gsub('a', 'a', t)) end})\n\
         local function go() string.gsub('a', 'a', t) end",
    ),
    (
        "format __tostring",
        "local t = setmetatable({}, {__tostring = function(x) return string.format('%s', x) end})\n\
         local function go() return tostring(t) end",
    ),
    (
        "format method __tostring",
        "local t = setmetatable({}, {__tostring = function(x) return ('<%s>'):format(x) end})\n\
         local function go() return ('%s'):format(t) end",
    ),
    (
        "sort comparator",
        "local function cmp(a, b) table.sort({3, 2, 1}, cmp) return a < b end\n\
         local function go() table.sort({3, 2, 1}, cmp) end",
    ),
    (
        "sort __lt",
        "local mt = {}\nmt.__lt = function(a, b) table.sort({setmetatable({}, mt), setmetatable({}, mt)}) return false end\n\
         local function go() table.sort({setmetatable({}, mt), setmetatable({}, mt)}) end",
    ),
    ("coroutine.wrap", "local function f() return coroutine.wrap(f)() end\nlocal function go() f() end"),
    (
        "coroutine.resume",
        "local function f() local ok, e = coroutine.resume(coroutine.create(f)) if not ok then error(e, 0) end end\n\
         local function go() f() end",
    ),
    (
        "coroutine and gsub",
        "local function f(m) return coroutine.wrap(function() return (string.gsub('a', 'a', f)) end)() end\n\
         local function go() f('a') end",
    ),
];
