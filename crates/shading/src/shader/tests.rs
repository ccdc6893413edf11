//! Shader runtime tests: entry points, parameters, built-ins, errors,
//! timeouts and threads. Sandbox escapes are in `tests_sandbox.rs`.

use std::time::{Duration, Instant};

use super::*;
use crate::noise::{fractal, perlin, voronoi};

pub(super) fn set_of(code: &str) -> Result<ShaderSet, ShaderError> {
    ShaderSet::new(vec![ShaderSource::new("test", "test.lua", code)], DEFAULT_TIMEOUT)
}

pub(super) fn input(p: [f32; 3]) -> ShadeInput {
    ShadeInput {
        p,
        pw: [p[0] + 10.0, p[1], p[2]],
        n: [0.0, 0.0, 1.0],
        uv: [0.25, 0.75],
        time: 0.5,
        ..ShadeInput::default()
    }
}

pub(super) fn color_err(code: &str) -> ShaderError {
    match set_of(code) {
        Ok(set) => set.color(0, &input([0.0; 3])).expect_err("the call should fail"),
        Err(e) => e,
    }
}

#[test]
fn entry_points_return_their_values() {
    let set = set_of(
        "function color(s) return s.P.x, s.Pw.x, s.N.z end
         function height(s) return s.uv.u + s.uv.v + s.time end
         function reflect(s) return vec3(0.1, 0.2, 0.3) * 2 end",
    )
    .unwrap();
    assert!(set.has_color(0) && set.has_height(0) && set.has_reflect(0));
    let i = input([0.5, 2.0, 3.0]);
    assert_eq!(set.color(0, &i).unwrap(), [0.5, 10.5, 1.0]);
    assert_eq!(set.height(0, &i).unwrap(), 1.5);
    let r = set.reflect(0, &i).unwrap();
    assert!((r[0] - 0.2).abs() < 1e-6 && (r[1] - 0.4).abs() < 1e-6 && (r[2] - 0.6).abs() < 1e-6);
}

#[test]
fn only_defined_entry_points_are_reported_and_callable() {
    let set = set_of("function height(s) return 1 end").unwrap();
    assert!(!set.has_color(0) && set.has_height(0) && !set.has_reflect(0));
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap_err().kind, ShaderErrorKind::Usage);
    assert_eq!(set.height(7, &input([0.0; 3])).unwrap_err().kind, ShaderErrorKind::Usage);
    let e = set_of("x = 1").unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::NoEntryPoint);
    assert!(e.to_string().contains("test.lua"), "{e}");
}

#[test]
fn color_can_call_height() {
    let set = set_of(
        "function height(s) return s.P.x * 2 end
         function color(s) local h = height(s) return h, h + 1, 0 end",
    )
    .unwrap();
    assert_eq!(set.color(0, &input([0.25, 0.0, 0.0])).unwrap(), [0.5, 1.5, 0.0]);
}

#[test]
fn params_reach_the_script() {
    let src = ShaderSource::new(
        "p",
        "p.lua",
        "function color(s) return param.scale, param.tint.y, #param.label end",
    )
    .with_number("scale", 2.5)
    .with_param("tint", ParamValue::Vec3([1.0, 0.5, 0.25]))
    .with_param("label", ParamValue::Text("four".into()));
    let set = ShaderSet::new(vec![src], DEFAULT_TIMEOUT).unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [2.5, 0.5, 4.0]);
}

#[test]
fn shaders_have_separate_globals() {
    let a = ShaderSource::new("a", "a.lua", "k = 1 math.floor = nil function color(s) return k, 0, 0 end");
    let b = ShaderSource::new("b", "b.lua", "k = 2 function color(s) return k, math.floor(1.5), 0 end");
    let set = ShaderSet::new(vec![a, b], DEFAULT_TIMEOUT).unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [1.0, 0.0, 0.0]);
    assert_eq!(set.color(1, &input([0.0; 3])).unwrap(), [2.0, 1.0, 0.0]);
    assert_eq!(set.name(1), Some("b"));
}

#[test]
fn syntax_error_carries_file_and_line() {
    let e = set_of("function color(s)\n  return 1,\nend").unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Syntax);
    assert!(e.message.contains("test.lua:3:"), "{e}");
    let e = set_of("local __luster_tick = 1\nfunction color(s) return 1, 1, 1 end").unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Syntax);
    assert!(e.message.contains("test.lua:1:") && e.message.contains("reserved"), "{e}");
}

#[test]
fn runtime_error_names_shader_file_and_line() {
    let e = color_err("function color(s)\n  local t = nil\n  return t.x, 0, 0\nend");
    assert_eq!(e.kind, ShaderErrorKind::Runtime);
    let text = e.with_object("Sphere[id=2]").to_string();
    assert!(text.starts_with("shader 'test' (shading Sphere[id=2]): test.lua:3:"), "{text}");
    assert!(!text.contains("stack traceback"), "{text}");
    let e = color_err("function color(s) error('custom failure') end");
    assert!(e.message.contains("test.lua:1: custom failure"), "{e}");
    let e = set_of("error('at load')\nfunction color(s) return 1, 1, 1 end").unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Runtime);
    assert!(e.message.contains("test.lua:1: at load"), "{e}");
}

#[test]
fn bad_results_are_errors_naming_shader_and_entry() {
    for (code, what) in [
        ("function color(s) return 0/0, 0, 0 end", "NaN as its red value"),
        ("function color(s) return 1, nil, 0 end", "nothing (nil) as its green value"),
        ("function color(s) return 1, 1, 'x' end", "a string as its blue value"),
        ("function color(s) end", "nothing (nil) as its red value"),
        ("function color(s) return {} end", "a table as its red value"),
    ] {
        let e = color_err(code);
        assert_eq!(e.kind, ShaderErrorKind::BadResult, "{code}: {e}");
        assert!(e.to_string().contains("shader 'test'") && e.message.contains("color() returned"), "{e}");
        assert!(e.message.contains(what), "{code}: {e}");
    }
    let set = set_of("function height(s) return 'high' end").unwrap();
    let e = set.height(0, &input([0.0; 3])).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::BadResult);
    assert!(e.message.contains("height() returned a string"), "{e}");
    // The state stays usable after an error.
    let set = set_of("function color(s) if s.P.x > 0 then return 0/0, 0, 0 end return 1, 2, 3 end").unwrap();
    assert!(set.color(0, &input([1.0, 0.0, 0.0])).is_err());
    assert_eq!(set.color(0, &input([-1.0, 0.0, 0.0])).unwrap(), [1.0, 2.0, 3.0]);
}

/// CPU time consumed so far by the calling thread.
fn thread_cpu_time() -> Duration {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

fn assert_stops(code: &str) {
    let timeout = Duration::from_millis(300);
    let set = ShaderSet::new(vec![ShaderSource::new("spin", "spin.lua", code)], timeout).unwrap();
    let start = Instant::now();
    let cpu_start = thread_cpu_time();
    let e = set.color(0, &input([0.0; 3])).expect_err("an endless shader must be stopped");
    let took = start.elapsed();
    let cpu = thread_cpu_time().saturating_sub(cpu_start);
    assert_eq!(e.kind, ShaderErrorKind::Timeout, "{code}: {e}");
    assert!(e.message.contains("spin.lua:") && e.message.contains("time limit"), "{e}");
    assert!(took >= timeout, "{code}: stopped after {took:?}, before its limit");
    // How late the stop comes is judged in this thread's CPU time: on a
    // loaded machine the wall clock also counts time the thread spent
    // waiting for a core, which says nothing about how often the deadline
    // is checked. The wall bound only catches a hang.
    assert!(cpu < timeout + Duration::from_millis(700), "{code}: ran {cpu:?} of CPU time");
    assert!(took < timeout + Duration::from_secs(20), "{code}: took {took:?}");
    // The next call gets a fresh deadline.
    let e = set.color(0, &input([0.0; 3])).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Timeout);
}

#[test]
fn endless_loops_are_stopped_even_when_jit_compiled() {
    assert_stops("function color(s) while true do end end");
    assert_stops("function color(s) local x = 0 while true do x = x + 1 end end");
    assert_stops("function color(s) repeat until false end");
    assert_stops("function color(s) for i = 1, math.huge do end end");
    assert_stops("function color(s) ::top:: goto top end");
    assert_stops("function color(s) local i = 0 ::a:: i = i + 1 if i > 0 then goto a end end");
    assert_stops("local function f(n) return f(n + 1) end function color(s) return f(0) end");
    assert_stops("function color(s) while true do pcall(function() while true do end end) end end");
    assert_stops("function color(s) local t = {} for i = 1, 1e12 do t[i % 8 + 1] = i end end");
    assert_stops("function color(s) while true do local x = string.rep('ab', 5e5) end end");
    assert_stops("function color(s) while true do local a, b = voronoi(1, 2, 3) end end");
}

#[test]
fn goto_continue_idiom_still_compiles() {
    // The label ends its block after a local; a check inserted after the
    // label would make this "jumps into the scope of local 'x'".
    let set = set_of(
        "function height(s)
           local n = 0
           for i = 1, 4 do
             if i % 2 == 0 then goto continue end
             local x = i
             n = n + x
             ::continue::
           end
           return n
         end",
    )
    .unwrap();
    assert_eq!(set.height(0, &input([0.0; 3])).unwrap(), 4.0);
}

#[test]
fn deep_recursion_and_memory_bombs_fail_cleanly() {
    let e = color_err("local function f(n) return 1 + f(n + 1) end function color(s) return f(0), 0, 0 end");
    assert_eq!(e.kind, ShaderErrorKind::Runtime, "{e}");
    // With the line when LuaJIT knows it; inside compiled code it may not.
    assert!(e.message.starts_with("test.lua:") && e.message.contains(": recursion too deep"), "{e}");
    let e = color_err("function color(s) local x = string.rep('x', 1e10) return 1, 1, 1 end");
    assert!(e.message.contains("limit"), "{e}");
    let e = color_err("function color(s) local x = ('x'):rep(2^40) return 1, 1, 1 end");
    assert!(e.message.contains("limit"), "{e}");
    let e = color_err("function color(s) local s = 'x' for i = 1, 40 do s = s .. s end return 1, 1, 1 end");
    assert_eq!(e.kind, ShaderErrorKind::Memory, "{e}");
    let e = color_err("function color(s) local t = {} for i = 1, 1e9 do t[i] = i end return 1, 1, 1 end");
    assert_eq!(e.kind, ShaderErrorKind::Memory, "{e}");
}

#[test]
fn lua_fbm_and_turbulence_match_rust() {
    let set = set_of(
        "function color(s)
           local x, y, z = s.P.x, s.P.y, s.P.z
           local f, t, a, amp = 0, 0, 1, 1
           for i = 1, 5 do
             local n = perlin3(x * a, y * a, z * a)
             f = f + amp * n
             t = t + amp * math.abs(n)
             a, amp = a * 2, amp * 0.5
           end
           return f, t, fbm(x, y, z, 5, 2, 0.5) - turbulence(x, y, z, 5, 2, 0.5)
         end",
    )
    .unwrap();
    for p in [[0.1f32, 0.2, 0.3], [1.7, -2.3, 0.45], [10.5, 3.25, -7.125]] {
        let c = set.color(0, &input(p)).unwrap();
        let f = fractal::fbm3(p[0], p[1], p[2], 5, 2.0, 0.5);
        let t = fractal::turbulence3(p[0], p[1], p[2], 5, 2.0, 0.5);
        assert!((c[0] - f).abs() < 1e-5, "fbm at {p:?}: lua {} rust {f}", c[0]);
        assert!((c[1] - t).abs() < 1e-5, "turbulence at {p:?}: lua {} rust {t}", c[1]);
        assert!((c[2] - (f - t)).abs() < 1e-5, "built-ins at {p:?}");
    }
}

#[test]
fn noise_builtins_reach_rust() {
    let set = set_of(
        "function color(s)
           local f1, f2, id, px, py, pz = voronoi(s.P.x, s.P.y, s.P.z, 'manhattan', 0.8)
           local v, gx = perlin3_grad(s.P.x, s.P.y, s.P.z)
           return f1 + id * 0 + px * 0, v, gx
         end
         function height(s) local f = voronoi(1, 2, 3, 'taxicab') return f end",
    )
    .unwrap();
    let p = [0.3f32, 1.6, -2.2];
    let c = set.color(0, &input(p)).unwrap();
    let cell = voronoi::voronoi3(p[0], p[1], p[2], voronoi::Metric::Manhattan, 0.8);
    let (v, g) = perlin::noise3_grad(p[0], p[1], p[2]);
    assert_eq!(c, [cell.f1, v, g[0]]);
    let e = set.height(0, &input(p)).unwrap_err();
    assert!(e.message.contains("test.lua:6:") && e.message.contains("taxicab"), "{e}");
}

#[test]
fn pattern_helpers() {
    let set = set_of(
        "local r = ramp({0, 0.5, 1}, {{0, 0, 0}, vec3(1, 0.5, 0), {1, 1, 1}})
         function color(s)
           local m, id, bu, bv = brick(0.5, 0.25, 1, 0.5, 0.1)
           local m2 = brick(0.01, 0.25, 1, 0.5, 0.1)
           local a, b, c = r(0.25)
           return m * 10 + m2, smoothstep(0, 1, 0.5) + checker(0.5, 1.5, 0), a + b + c + clamp(5, 0, 1)
         end
         function height(s)
           local a = vec3(1, 0, 0)
           local b = vec3(0, 1, 0)
           return a:cross(b).z + dot(a, b) + normalize(vec3(3, 0, 4)).z + length(vec3(2)) ^ 2 + mix(2, 4, 0.25)
         end",
    )
    .unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [1.0, 1.5, 0.75 + 1.0]);
    assert!((set.height(0, &input([0.0; 3])).unwrap() - (1.0 + 0.0 + 0.8 + 12.0 + 2.5)).abs() < 1e-5);
}

#[test]
fn hash_is_repeatable_and_spread() {
    let set = set_of(
        "function color(s)
           local seen, lo, hi, n = {}, 1, 0, 0
           for i = -50, 49 do
             for j = 0, 9 do
               local h = hash(i, j, 7)
               if not seen[h] then seen[h] = true n = n + 1 end
               lo, hi = math.min(lo, h), math.max(hi, h)
             end
           end
           return n, lo, hi
         end
         function height(s) return hash(s.P.x, s.P.y, s.P.z) end",
    )
    .unwrap();
    let [distinct, lo, hi] = set.color(0, &input([0.0; 3])).unwrap();
    assert_eq!(distinct, 1000.0);
    assert!((0.0..0.01).contains(&lo) && (0.99..1.0).contains(&hi), "{lo} {hi}");
    let a = set.height(0, &input([3.5, -2.0, 9.0])).unwrap();
    assert_eq!(a, set.height(0, &input([3.9, -1.5, 9.2])).unwrap());
    assert_ne!(a, set.height(0, &input([4.0, -2.0, 9.0])).unwrap());
}

#[test]
fn threads_give_identical_results() {
    let set = set_of(
        "function color(s)
           local t = turbulence(s.P.x * 4, s.P.y * 4, s.P.z * 4, 4)
           local v = 0.5 + 0.5 * math.sin(s.P.x * 6 + 5 * t)
           return v, v * v, simplex3(s.P.x, s.P.y, s.P.z)
         end",
    )
    .unwrap();
    let points: Vec<ShadeInput> =
        (0..500).map(|i| input([i as f32 * 0.013, (i % 17) as f32 * 0.1, -(i as f32) * 0.007])).collect();
    let expected: Vec<[f32; 3]> = points.iter().map(|p| set.color(0, p).unwrap()).collect();
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..4)
            .map(|_| scope.spawn(|| points.iter().map(|p| set.color(0, p).unwrap()).collect::<Vec<_>>()))
            .collect();
        for h in handles {
            assert_eq!(h.join().unwrap(), expected);
        }
    });
}

#[test]
fn states_of_dropped_sets_are_freed() {
    let before = threads::count();
    let sets: Vec<ShaderSet> = (0..3).map(|_| set_of("function height(s) return 1 end").unwrap()).collect();
    assert_eq!(threads::count(), before + 3);
    drop(sets);
    assert_eq!(threads::count(), before);
    let many: Vec<ShaderSet> = (0..threads::MAX_SETS_PER_THREAD + 3)
        .map(|_| set_of("function height(s) return 2 end").unwrap())
        .collect();
    assert!(threads::count() <= threads::MAX_SETS_PER_THREAD);
    // An evicted state is rebuilt on demand.
    assert_eq!(many[0].height(0, &input([0.0; 3])).unwrap(), 2.0);
}

#[test]
fn shader_set_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<ShaderSet>();
}

#[test]
fn heights3_matches_three_height_calls_and_isolates_them() {
    // The script scribbles on s; the next point must not see it.
    let set =
        set_of("function height(s) local h = s.P.x + 2 * s.uv.u; s.P = vec3(9, 9, 9); return h end").unwrap();
    let pts = [input([0.1, 0.0, 0.0]), input([0.2, 0.0, 0.0]), input([0.3, 0.0, 0.0])];
    let one = pts.map(|p| set.height(0, &p).unwrap());
    assert_eq!(set.heights3(0, &pts).unwrap(), one);
    let bad = set_of("function height(s) if s.P.x > 0.25 then return 'x' end return 1 end").unwrap();
    let e = bad.heights3(0, &pts).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::BadResult, "{e}");
    assert!(e.message.contains("height"), "{e}");
    let none = set_of("function color(s) return 1, 1, 1 end").unwrap();
    assert_eq!(none.heights3(0, &pts).unwrap_err().kind, ShaderErrorKind::Usage);
}

/// A sampler whose colour is the coordinates it was asked for, so the test
/// sees what reached Rust.
struct EchoSampler;

impl ImageSampler for EchoSampler {
    fn sample(&self, index: usize, u: f32, v: f32, filter: SampleFilter) -> Option<[f32; 3]> {
        (index < 2)
            .then(|| [u + index as f32 * 10.0, v, if filter == SampleFilter::Nearest { 0.0 } else { 1.0 }])
    }
}

#[test]
fn texture_reaches_the_sampler_by_name_and_filter() {
    let images = ShaderImages {
        names: vec![("1".into(), 0), ("bricks".into(), 1), ("bricks.png".into(), 1)],
        sampler: Arc::new(EchoSampler),
    };
    let src = ShaderSource::new(
        "t",
        "t.lua",
        "function color(s)
           local a = texture(1, s.uv.u, s.uv.v)
           local b, v = texture('bricks', 0.5, 0.125)
           local _, _, f = texture('bricks.png', 0, 0, 'nearest')
           return a, b + v, f
         end",
    );
    let set = ShaderSet::with_images(vec![src], DEFAULT_TIMEOUT, Some(images)).unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [0.25, 10.625, 0.0]);
}

#[test]
fn texture_without_images_is_an_error_naming_none() {
    let e = color_err("function color(s)\n  local r = texture('x', 0, 0)\n  return r, r, r\nend");
    assert_eq!(e.kind, ShaderErrorKind::Runtime);
    assert!(e.message.contains("test.lua:2") && e.message.contains("(its images: none)"), "{e}");
}

#[test]
fn a_caught_timeout_still_fails_the_call_and_costs_the_limit_only_once_per_call() {
    let timeout = Duration::from_millis(200);
    let code = "function color(s) pcall(function() while true do end end) return 1, 1, 1 end";
    let set = ShaderSet::new(vec![ShaderSource::new("spin", "spin.lua", code)], timeout).unwrap();
    for _ in 0..2 {
        let start = Instant::now();
        let e = set.color(0, &input([0.0; 3])).expect_err("a caught timeout must still fail");
        assert_eq!(e.kind, ShaderErrorKind::Timeout, "{e}");
        assert!(e.message.contains("caught the error"), "{e}");
        assert!(start.elapsed() < timeout + Duration::from_millis(700), "took {:?}", start.elapsed());
    }
    // Catching it inside the loop does not help either: every later tick raises again.
    assert_stops(
        "function color(s) while true do pcall(error, 'x') pcall(function() while true do end end) end end",
    );
}

#[test]
fn string_and_comment_tricks_do_not_hide_loops_from_the_time_checks() {
    for prefix in [
        "local a = 'x\\z\n   '\n",
        "local a = 'x\\z\r\n   '\r\n",
        "local a = 'x\\\r\ny'\r\n",
        "local a = 'x\\\n\ry'\n",
        "local a = \"x\\z\n\n\"\n",
        "-- comment\rlocal b = 1\r",
        "local a = [==[ ]] ]=] ]==]\n",
        "--[=[ ]] ]=]\n",
    ] {
        assert_stops(&format!("{prefix}function color(s) while true do end end"));
    }
}

#[test]
fn pattern_functions_take_only_literal_patterns() {
    let ok = set_of(
        "function color(s)
           local a = string.find('a.b', '.', 1, true)
           local b = ('abcabc'):find('ca')
           local c = select(2, string.gsub('a-b-c', 'b', 'x'))
           local n = 0
           for w in string.gmatch('xyxyx', 'xy') do n = n + 1 end
           return a, b + (string.match('hello', 'll') == 'll' and 10 or 0), c + n
         end",
    )
    .unwrap();
    assert_eq!(ok.color(0, &input([0.0; 3])).unwrap(), [2.0, 13.0, 3.0]);
    for call in [
        "string.find(string.rep('a', 1e5), '.-.-.-.-b')",
        "('aaaa'):match('(a*)*b')",
        "string.gsub('abc', '%a', 'x')",
        "string.gmatch('abc', '[a-c]')",
    ] {
        let e = color_err(&format!("function color(s) local r = {call} return 0, 0, 0 end"));
        assert_eq!(e.kind, ShaderErrorKind::Runtime, "{call}: {e}");
        assert!(e.message.contains("test.lua:1") && e.message.contains("magic characters"), "{call}: {e}");
    }
}

#[test]
fn infinite_results_are_refused() {
    for (code, what) in [
        ("function color(s) return 1/0, 0, 0 end", "inf as its red value"),
        ("function color(s) return vec3(0, -1/0, 0) end", "-inf as its green value"),
    ] {
        let e = color_err(code);
        assert_eq!(e.kind, ShaderErrorKind::BadResult, "{code}: {e}");
        assert!(e.message.contains(what), "{code}: {e}");
    }
    let set = set_of("function height(s) return -1/0 end").unwrap();
    let e = set.height(0, &input([0.0; 3])).unwrap_err();
    assert!(e.message.contains("height() returned -inf (expected a finite number)"), "{e}");
}

#[test]
fn course_perlin_is_the_perlin_maps_value() {
    use crate::noise::course;
    let set = set_of(
        "function color(s)
           return course_perlin(s.P.x, s.P.y, s.P.z, 3, 4, 'absval'), course_perlin(s.P, 2, 3),
             course_perlin(s.P)
         end",
    )
    .unwrap();
    for k in 0..200 {
        let f = k as f32;
        let p = [f * 0.173 % 5.0 - 2.5, f * 0.291 % 3.0 - 1.5, f * 0.0731 % 2.0];
        let c = set.color(0, &input(p)).unwrap();
        assert_eq!(c[0].to_bits(), course::texture_value(p, 3.0, 4, true).to_bits());
        assert_eq!(c[1].to_bits(), course::texture_value(p, 2.0, 3, false).to_bits());
        assert_eq!(c[2].to_bits(), course::texture_value(p, 1.0, 1, false).to_bits());
    }
    let e = color_err("function color(s) local v = course_perlin(s.P, 1, 4, 'abs') return v, v, v end");
    assert!(e.message.contains("test.lua:1") && e.message.contains("unknown conversion"), "{}", e.message);
}
