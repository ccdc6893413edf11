//! The bounds on what one shader call can cost: native recursion through
//! library functions is a Lua error, library functions cannot outrun the
//! clock, the clock is kept from outside the Lua thread, and error messages
//! are escaped, capped and never quote a file that is not a script.

use std::time::{Duration, Instant};

use super::tests::{input, set_of};
use super::*;

fn set_with(code: &str, timeout: Duration) -> Result<ShaderSet, ShaderError> {
    ShaderSet::new(vec![ShaderSource::new("test", "test.lua", code)], timeout)
}

/// The error of loading `code` or, when it loads, of calling its `color`.
fn failure(code: &str, timeout: Duration) -> ShaderError {
    match set_with(code, timeout) {
        Ok(set) => set.color(0, &input([0.0; 3])).expect_err("the call should fail"),
        Err(e) => e,
    }
}

/// Runs `f` on a thread with a native stack of `bytes`: the recursion tests
/// run on a stack smaller than any thread luster starts, so that they show
/// the bound, not the size of a big stack.
fn on_stack<T: Send + 'static>(bytes: usize, f: impl FnOnce() -> T + Send + 'static) -> T {
    let worker = std::thread::Builder::new().stack_size(bytes).spawn(f).expect("a thread");
    worker.join().expect("the thread finishes")
}

include!("../../tests-data/recursions.rs");

/// An `xpcall` handler that calls `xpcall` with itself: LuaJIT runs one
/// handler at a time ("error in error handling" for an error inside it).
const HANDLER: &str = "local function h(e) return xpcall(error, h) end\n\
                       function color(s) local ok, e = xpcall(error, h) return ok and 1 or 0, 1, 1 end";

#[test]
fn native_recursion_through_library_functions_is_a_lua_error() {
    for &(name, code) in RECURSIONS {
        for (place, script) in [
            ("top level", format!("{code}\ngo()\nfunction color(s) return 1, 1, 1 end")),
            ("call", format!("{code}\nfunction color(s) go() return 1, 1, 1 end")),
            ("pcall", format!("{code}\nfunction color(s) local ok, e = pcall(go) error(e, 0) end")),
        ] {
            // 1 MiB: half of a Rust thread's default stack.
            let e = on_stack(1 << 20, move || failure(&script, Duration::from_secs(10)));
            assert!(
                matches!(e.kind, ShaderErrorKind::Runtime),
                "{name} ({place}): expected a runtime error, got {e}"
            );
            assert!(e.message.contains("test.lua:"), "{name} ({place}): no line: {e}");
            assert!(e.message.contains("too deep"), "{name} ({place}): {e}");
        }
    }
    let rgb = on_stack(1 << 20, || set_of(HANDLER).unwrap().color(0, &input([0.0; 3])).unwrap());
    assert_eq!(rgb, [0.0, 1.0, 1.0]);
}

/// The native stack used by `f` on a fresh thread: the stack below the
/// thread's first frame is painted with a pattern, and the deepest word
/// that no longer holds it after `f` is the high-water mark.
fn native_stack_of(f: impl FnOnce() + Send + 'static) -> usize {
    const STACK: usize = 40 << 20;
    const PAINTED: usize = 32 << 20;
    const PATTERN: u64 = 0xa5a5_5a5a_a5a5_5a5a;
    on_stack(STACK, move || {
        let top = std::hint::black_box(0u8);
        let top = std::ptr::addr_of!(top) as usize & !7;
        // Leave this frame and the painter's own alone.
        let (low, high) = (top - PAINTED, top - 4096);
        paint(low, high, PATTERN);
        f();
        let mut deepest = high;
        for a in (low..high).step_by(8) {
            // SAFETY: [low, high) lies inside this thread's stack (STACK
            // bytes below its first frame, PAINTED of them), mapped and
            // owned by this thread; nothing else reads or writes it now.
            if unsafe { std::ptr::read_volatile(a as *const u64) } != PATTERN {
                deepest = a;
                break;
            }
        }
        top - deepest
    })
}

#[inline(never)]
fn paint(low: usize, high: usize, pattern: u64) {
    for a in (low..high).step_by(8) {
        // SAFETY: see native_stack_of: unused stack of this thread, below
        // every live frame.
        unsafe { std::ptr::write_volatile(a as *mut u64, pattern) };
    }
}

/// The native stack a thread needs for the deepest thing a script can do:
/// each recursion above up to its Lua error, LuaJIT's parser at its nesting
/// limit, and the coroutine nesting limit. [`STACK_SIZE`] must hold the
/// worst of them with a wide margin (8 times) for the renderer's own frames.
#[test]
fn the_native_stack_a_script_can_use_is_far_below_the_stack_size() {
    let nested_functions = format!(
        "{}{}\nfunction color(s) return 1, 1, 1 end",
        "local x = function() ".repeat(98),
        " end".repeat(98)
    );
    let nested_parens =
        format!("local x = {}1{}\nfunction color(s) return 1, 1, 1 end", "(".repeat(190), ")".repeat(190));
    let coroutines = "local function f(n) if n > 0 then coroutine.wrap(f)(n - 1) end end\n\
                      function color(s) f(199) return 1, 1, 1 end"
        .to_string();
    let mut cases: Vec<(String, String)> = RECURSIONS
        .iter()
        .map(|&(name, code)| {
            (name.to_string(), format!("{code}\nfunction color(s) pcall(go) return 1, 1, 1 end"))
        })
        .collect();
    cases.push(("parser: 98 nested functions".into(), nested_functions));
    cases.push(("parser: 190 nested parentheses".into(), nested_parens));
    cases.push(("199 nested coroutines".into(), coroutines));
    cases.push(("xpcall handler calling xpcall".into(), HANDLER.to_string()));
    let baseline = native_stack_of(|| {
        let set = set_of("function color(s) return 1, 1, 1 end").unwrap();
        set.color(0, &input([0.0; 3])).unwrap();
    });
    let mut worst = 0;
    for (name, code) in cases {
        let used = native_stack_of(move || {
            let set = set_of(&code).unwrap();
            set.color(0, &input([0.0; 3])).unwrap();
        });
        eprintln!("native stack of {name}: {} KiB (an empty shader: {} KiB)", used / 1024, baseline / 1024);
        worst = worst.max(used);
    }
    assert!(worst > baseline, "the measurement sees nothing");
    assert!(worst * 8 < STACK_SIZE, "{worst} bytes of native stack leave too little margin in {STACK_SIZE}");
}

#[test]
fn coroutines_nest_up_to_the_limit_and_no_deeper() {
    let ok = "local function f(n) if n > 0 then return coroutine.wrap(f)(n - 1) end return 7 end\n\
              function color(s) return f(199), 0, 0 end";
    assert_eq!(set_of(ok).unwrap().color(0, &input([0.0; 3])).unwrap(), [7.0, 0.0, 0.0]);
    // The count starts again with every call, and a caught error does not leak it.
    let set = set_of(
        "local function f(n) if n > 0 then return coroutine.wrap(f)(n - 1) end return 7 end\n\
         local function deep() local co = coroutine.wrap(function() error('x') end) co() end\n\
         function color(s) for i = 1, 300 do pcall(deep) end return f(150), 0, 0 end",
    )
    .unwrap();
    for _ in 0..3 {
        assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [7.0, 0.0, 0.0]);
    }
    let e = failure(ok.replace("199", "250").as_str(), Duration::from_secs(10));
    assert!(e.message.contains("coroutines nested too deep") && e.message.contains("test.lua:"), "{e}");
}

/// Literal searches of a megabyte string for a near miss: quadratic in
/// LuaJIT's own search (minutes), linear here.
#[test]
fn literal_searches_are_linear() {
    let code = "local a = string.rep('a', 4e6)\n\
                local p = string.rep('a', 2e6) .. 'b'\n\
                function color(s)\n\
                  local n = 0\n\
                  if a:find(p, 1, true) == nil then n = n + 1 end\n\
                  if string.find(a, p) == nil then n = n + 1 end\n\
                  if a:match(p) == nil then n = n + 1 end\n\
                  for _ in a:gmatch(p) do n = n - 10 end\n\
                  local r, k = a:gsub(p, 'x')\n\
                  if k == 0 and #r == #a then n = n + 1 end\n\
                  return n, 0, 0\n\
                end";
    let set = set_with(code, Duration::from_secs(1)).unwrap();
    let start = Instant::now();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [4.0, 0.0, 0.0]);
    assert!(start.elapsed() < Duration::from_millis(500), "took {:?}", start.elapsed());
}

/// The literal pattern functions give what LuaJIT's give, edge cases
/// included (positions out of range, empty patterns, counts, `%` escapes,
/// table and function replacements), on inputs where LuaJIT's own are fast.
#[test]
fn literal_pattern_functions_agree_with_luajit() {
    let probes = [
        "('hello world'):find('o')",
        "('hello world'):find('o', 6)",
        "('hello world'):find('o', -3)",
        "('hello world'):find('o', -100)",
        "('hello world'):find('o', 100)",
        "('hello'):find('', 100)",
        "('hello'):find('', 3.7)",
        "('hello'):find('', -2.5)",
        "('hello'):find('', 0/0)",
        "('hello'):find('', 1e12)",
        "('hello'):find('l', '2')",
        "('a.b'):find('.', 1, true)",
        "string.find(12345, 34)",
        "('hello'):find('xyz')",
        "('hello'):find('')",
        "('hello'):match('ll')",
        "('hello'):match('ll', 4)",
        "('hello'):match('', 10)",
        "('hello'):match('z')",
        "('abab'):gsub('ab', 'x')",
        "('abab'):gsub('ab', 'x', 1)",
        "('abab'):gsub('ab', 'x', 0)",
        "('abab'):gsub('ab', 'x', -1)",
        "('abab'):gsub('ab', 'x', 1e10)",
        "('abc'):gsub('', '-')",
        "('abc'):gsub('', '-', 2)",
        "(''):gsub('', '-')",
        "('abab'):gsub('b', '<%0%1%%%x>')",
        "('abab'):gsub('b', '%')",
        "('abab'):gsub('b', 7)",
        "('abab'):gsub('b', {b = 'B'})",
        "('abab'):gsub('b', {b = false})",
        "('abab'):gsub('b', {b = 3})",
        "('abab'):gsub('b', function(m) return m .. m end)",
        "('abab'):gsub('b', function(m) return nil end)",
        "('aaa'):gsub('aa', 'x')",
        "string.gsub(1234, 2, 'x')",
        "('abab'):gsub('ab', 'x', '1')",
        "('a\\0b\\0'):gsub('\\0', 'x')",
        "('a\\0b'):gsub('b\\0c', 'x')",
        "('a\\0b'):match('\\0b')",
        "('a\\0b'):find('\\0b')",
    ];
    let iterate = ["('abab'):gmatch('ab')", "('abc'):gmatch('')", "('aaaa'):gmatch('aa')", "(''):gmatch('')"];
    // (A zero byte would end the message early: it is shown as <NUL>.)
    let show = "local function esc(s) local o = {} for i = 1, #s do local b = s:byte(i) \
                o[i] = b == 0 and '<NUL>' or s:sub(i, i) end return table.concat(o) end\n\
                local function show(...) local t = {} for i = 1, select('#', ...) do \
                t[#t + 1] = esc(tostring((select(i, ...)))) end return table.concat(t, ',') end\n";
    let mut exprs: Vec<String> = probes.iter().map(|p| format!("show({p})")).collect();
    exprs.extend(iterate.iter().map(|g| {
        format!("(function() local t = {{}} for m in {g} do t[#t + 1] = m if #t > 10 then break end end return #t .. ':' .. table.concat(t, ',') end)()")
    }));
    let list = exprs.join(",\n");
    let reference = mlua::Lua::new();
    let expected: Vec<String> = reference.load(format!("{show}return {{ {list} }}")).eval().unwrap();
    // The sandbox's answers come back as the message of an error the
    // script raises at its top level (one line each, escaped as every
    // message is).
    let probe = format!("{show}local results = {{ {list} }}\nerror(table.concat(results, '\\n'), 0)");
    let e = set_of(&probe).unwrap_err();
    let got: Vec<&str> = e.message.split("\\n").collect();
    assert_eq!(got.len(), expected.len(), "{}", e.message);
    for ((g, x), p) in got.iter().zip(&expected).zip(probes.iter().chain(iterate.iter())) {
        assert_eq!(*g, luster_core::text::printable(x, false), "{p}");
    }
    let e =
        failure("function color(s) local r = ('ab'):gsub('b', '%2') return r end", Duration::from_secs(1));
    assert!(e.message.contains("test.lua:1: invalid capture index"), "{e}");
    let e = failure(
        "function color(s) local r = ('ab'):gsub('b', {b = {}}) return r end",
        Duration::from_secs(1),
    );
    assert!(e.message.contains("test.lua:1: invalid replacement value (a table)"), "{e}");
}

#[test]
fn sort_is_n_log_n_and_sorts() {
    let code = "local t = {}\n\
                for i = 1, 1000000 do t[i] = (i * 7919) % 1000003 end\n\
                local w = {}\n\
                for i = 1, 20000 do w[i] = tostring((i * 31) % 20011) end\n\
                function color(s)\n\
                  table.sort(t)\n\
                  for i = 2, #t do if t[i - 1] > t[i] then return 1, 0, 0 end end\n\
                  table.sort(t, function(a, b) return a > b end)\n\
                  for i = 2, #t do if t[i - 1] < t[i] then return 2, 0, 0 end end\n\
                  table.sort(w)\n\
                  for i = 2, #w do if w[i - 1] > w[i] then return 3, 0, 0 end end\n\
                  local same = {} for i = 1, 100000 do same[i] = 5 end\n\
                  table.sort(same)\n\
                  return #t, #w, 0\n\
                end";
    let set = set_with(code, Duration::from_secs(10)).unwrap();
    let start = Instant::now();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [1e6, 20000.0, 0.0]);
    assert!(start.elapsed() < Duration::from_secs(5), "took {:?}", start.elapsed());
    let e = failure("function color(s) table.sort({1, 'x'}) end", Duration::from_secs(1));
    assert!(e.message.contains("test.lua:1: attempt to compare"), "{e}");
}

/// A loop whose every iteration makes a slow library call is stopped as
/// promptly as an empty one: the clock is read at every tick.
#[test]
fn slow_library_calls_in_a_loop_stop_at_the_limit() {
    let timeout = Duration::from_millis(300);
    for code in [
        "local x = string.rep('x', 8e6)\nfunction color(s) while true do local y = x .. x end end",
        "function color(s) while true do local t = string.rep('ab', 4e6):upper() end end",
        "function color(s) while true do end end",
        "while true do end\nfunction color(s) return 1, 1, 1 end",
    ] {
        let start = Instant::now();
        let e = failure(code, timeout);
        let took = start.elapsed();
        assert_eq!(e.kind, ShaderErrorKind::Timeout, "{code}: {e}");
        assert!(e.message.contains("test.lua:"), "{code}: {e}");
        assert!(took < timeout * 2, "{code}: stopped after {took:?}");
        assert!(took >= timeout, "{code}: stopped early, after {took:?}");
    }
}

/// A call that returns after its limit, because one library call took the
/// time between two checks, is a timeout, not a result.
#[test]
fn a_call_that_overran_in_one_library_call_is_a_timeout() {
    let code = "function color(s)\n\
                  local x = string.rep('ab', 8e6)\n\
                  local y = x:upper():lower():reverse():upper():lower():reverse()\n\
                  local z = y .. y .. y .. y\n\
                  return 1, 1, #z\n\
                end";
    let set = set_with(code, Duration::from_millis(1)).unwrap();
    let e = set.color(0, &input([0.0; 3])).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Timeout, "{e}");
    assert!(set_with(code, Duration::from_secs(10)).unwrap().color(0, &input([0.0; 3])).is_ok());
}

#[test]
fn table_move_and_concat_are_bounded() {
    let e = failure("function color(s) table.move({}, 1, 2^31 - 2, 1) end", Duration::from_millis(200));
    assert_eq!(e.kind, ShaderErrorKind::Timeout, "{e}");
    assert!(e.message.contains("test.lua:1"), "{e}");
    let e = failure("function color(s) return #table.concat({}, '', 1, 2^30) end", Duration::from_secs(1));
    assert!(e.message.contains("table.concat") && e.message.contains("test.lua:1"), "{e}");
    let ok = "function color(s) local t = table.move({1, 2, 3}, 1, 3, 2) return t[1], t[2], t[4] end";
    assert_eq!(set_of(ok).unwrap().color(0, &input([0.0; 3])).unwrap(), [1.0, 1.0, 3.0]);
}

#[test]
fn error_messages_are_escaped_and_capped() {
    let e = failure("error('\\27]0;pwned\\7 and\\rCR')", Duration::from_secs(1));
    assert!(!e.message.chars().any(|c| c.is_control()), "{:?}", e.message);
    assert!(e.message.contains("\\e]0;pwned\\u{7} and\\rCR"), "{:?}", e.message);
    let e = failure("error(string.rep('x', 16e6))", Duration::from_secs(5));
    assert!(e.message.len() < 3000, "a message of {} bytes", e.message.len());
    assert!(e.message.contains("more characters"), "{}", &e.message[..100]);
}

#[test]
fn syntax_errors_never_quote_a_file_that_is_not_a_script() {
    let key = "-----BEGIN OPENSSH PRIVATE KEY-----\n\
               b3BlbnNzaC1rZXktdjEAAAAABG5vbmUAAAAEbm9uZQAAAAAAAAABAAAAMwAAAAtzc2gtZW\n\
               QyNTUxOQAAACDtMZsGcm4NNZNdg6jkcwZ1mk6ArTTCQb7Sxhj7eSDeZBAAAAJgAAAAAAA\n\
               -----END OPENSSH PRIVATE KEY-----\n";
    let e = set_of(key).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Syntax, "{e}");
    assert!(e.message.contains("test.lua:3"), "{e}");
    for line in key.lines().skip(1).take(2) {
        assert!(!e.message.contains(&line[..12]), "{e}");
    }
    // An unfinished string would carry the rest of its line.
    let e = set_of("x = 'secret: hunter2 and more\ny = 1").unwrap_err();
    assert!(!e.message.contains("hunter2") && e.message.contains("a token of"), "{e}");
    // Words, numbers and punctuation are what a script's own mistakes show.
    assert!(set_of("x = = 1").unwrap_err().message.ends_with("near '='"));
    assert!(set_of("local 5").unwrap_err().message.ends_with("near '5'"));
    assert!(set_of("x = 1\nfoo bar").unwrap_err().message.contains("near 'bar'"));
    assert!(set_of("function f(").unwrap_err().message.ends_with("near '<eof>'"));
}

#[test]
fn near_token_keeps_only_safe_tokens() {
    use super::error::near_token;
    assert_eq!(near_token("x.lua:1: unexpected symbol near '='"), "x.lua:1: unexpected symbol near '='");
    assert_eq!(near_token("x.lua:1: '=' expected near 'end'"), "x.lua:1: '=' expected near 'end'");
    assert_eq!(
        near_token("x.lua:1: unexpected symbol near '<\\27>'"),
        "x.lua:1: unexpected symbol near '<\\27>'"
    );
    assert_eq!(
        near_token("x.lua:1: unfinished string near ''root:x:0:0'"),
        "x.lua:1: unfinished string near a token of 11 characters"
    );
    assert_eq!(near_token("x.lua:1: no token here"), "x.lua:1: no token here");
}
