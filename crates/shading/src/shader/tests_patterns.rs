//! The built-in `require "patterns"` (`lib/patterns.lua`): every pattern's
//! range and period, its filtered form against a supersampled box filter of
//! the pattern and at the two ends of the footprint's scale, the waves,
//! `color_map` and the warps, and how the built-in is found.

use super::*;
use crate::noise::perlin;
use std::path::Path;

/// Every pattern the module has, with the footprint width at which its
/// filtered form is compared with a box filter: about a third of its
/// finest feature.
const PATTERNS: &[(&str, f64)] = &[
    ("agate", 0.1),
    ("boxed", 0.3),
    ("bozo", 0.3),
    ("brick", 0.5),
    ("bumps", 0.3),
    ("cells", 0.3),
    ("checker", 0.3),
    ("crackle", 0.2),
    ("cylindrical", 0.3),
    ("dents", 0.3),
    ("gradient", 0.3),
    ("granite", 0.05),
    ("hexagon", 0.3),
    ("leopard", 1.0),
    ("marble", 0.2),
    ("onion", 0.3),
    ("planar", 0.3),
    ("radial", 0.3),
    ("ripples", 0.3),
    ("spherical", 0.3),
    ("spiral1", 0.2),
    ("spiral2", 0.2),
    ("spotted", 0.3),
    ("waves", 0.3),
    ("wood", 0.3),
    ("wrinkles", 0.1),
];

/// Patterns that are no function of a repeating or noisy field but a shape
/// of a unit's size round the origin: under a vast footprint they fade to
/// 0 (the shape is lost in it), not to a mean.
const SHAPES: &[&str] = &["boxed", "cylindrical", "planar", "spherical"];

/// Calls the pattern `param.name` in the way `param.mode` says; the points
/// for "range" and "period" are drawn here, those of "stats" and "limits"
/// come from Rust as `s.P`.
const HARNESS: &str = r#"
local P = require "patterns"
params { name = "bozo", mode = "stats", fw = 0.3, n = 6, extent = 20 }
local sqrt, abs, min, max, pi = math.sqrt, math.abs, math.min, math.max, math.pi
local TAU = 2 * pi
-- Options beyond the defaults for the statistical tests (false: none).
local OPTIONS = { marble = { turbulence = 0.8 }, wood = { turbulence = 0.05 }, spiral1 = { arms = 3 },
  spiral2 = { arms = 2, turbulence = 0.3 }, agate = { agate_turb = 0.5 }, radial = { frequency = 3 },
  crackle = { form = vec3(-1, 1, 0) } }
local f = P[param.name]
local opts = OPTIONS[param.name] or false
local function at(p, fw, o)
  if o == nil then o = opts end
  return (f(p, fw, o or nil))
end
-- The unfiltered pattern averaged over n³ jittered strata of the box of
-- width w round p.
local function box(p, w, n)
  local sum, k = 0, 0
  for i = 0, n - 1 do
    for j = 0, n - 1 do
      for l = 0, n - 1 do
        k = k + 1
        local jx, jy, jz = hash(k, p.x * 9973, 1), hash(k, p.y * 9973, 2), hash(k, p.z * 9973, 3)
        sum = sum + at(p + vec3((i + jx) / n - 0.5, (j + jy) / n - 0.5, (l + jz) / n - 0.5) * w)
      end
    end
  end
  return sum / (n * n * n)
end
local function point(i)
  local e = param.extent
  return vec3((hash(i, 1) * 2 - 1) * e, (hash(i, 2) * 2 - 1) * e, (hash(i, 3) * 2 - 1) * e)
end
local function shift(x, y, z) return function(p) return p + vec3(x, y, z) end end
local function rot_y(a) return function(p)
  return vec3(p.x * math.cos(a) + p.z * math.sin(a), p.y, -p.x * math.sin(a) + p.z * math.cos(a)) end end
local function rot_z(a) return function(p)
  return vec3(p.x * math.cos(a) - p.y * math.sin(a), p.x * math.sin(a) + p.y * math.cos(a), p.z) end end
-- A unit further from the origin (onion) or from the z axis (wood).
local function out3(p) local r = length(p) return p * ((r + 1) / r) end
local function out_xy(p)
  local r = sqrt(p.x * p.x + p.y * p.y)
  return vec3(p.x * (r + 1) / r, p.y * (r + 1) / r, p.z)
end
-- Transforms that leave each periodic pattern (with PERIOD_OPTIONS) as it is.
local PERIODS = {
  gradient = { shift(1, 0, 0), shift(-3, 0, 0), shift(0, 2.5, 0), shift(0, 0, -7) },
  marble = { shift(1, 0, 0), shift(-2, 0, 0), shift(0, 1.7, 0), shift(0, 0, 4) },
  wood = { out_xy, shift(0, 0, 3) },
  onion = { out3 },
  radial = { rot_y(TAU / 4), rot_y(-TAU / 2), shift(0, 5, 0), function(p) return vec3(2 * p.x, p.y, 2 * p.z) end },
  spiral1 = { shift(0, 0, 1), shift(0, 0, -2), rot_z(TAU / 3) },
  spiral2 = { shift(0, 0, 1), shift(0, 0, -3) },
  leopard = { shift(TAU, 0, 0), shift(0, TAU, 0), shift(0, 0, -TAU) },
  checker = { shift(2, 0, 0), shift(0, 2, 0), shift(0, 0, 2), shift(1, 1, 0) },
  brick = { shift(8, 0, 0), shift(0, 6, 0), shift(0, 0, 4.5), shift(-16, 12, 9) },
  hexagon = { shift(3, 0, 0), shift(0, 0, 3 * sqrt(3)), shift(0, 5, 0), shift(1.5, 0, 1.5 * sqrt(3)) },
}
local PERIOD_OPTIONS = { radial = { frequency = 4 }, spiral1 = { arms = 3 } }
function color(s)
  local mode = param.mode
  if mode == "stats" then
    return at(s.P), at(s.P, param.fw), box(s.P, param.fw, param.n)
  elseif mode == "limits" then
    return at(s.P, 1e-7), at(s.P, 1e4), at(s.P)
  elseif mode == "range" then
    local lo, hi, ulo, uhi = math.huge, -math.huge, math.huge, -math.huge
    for i = 1, 2000 do
      local p = point(i)
      local v = at(p)
      if v ~= v then return -1, -1, -1 end
      ulo, uhi = min(ulo, v), max(uhi, v)
      for _, w in ipairs({ 0.01, 0.1, 1, 10, vec3(0.2, 0.05, 0), vec3(0, 0, 3) }) do
        v = at(p, w)
        if v ~= v then return -1, -1, -1 end
        lo, hi = min(lo, v), max(hi, v)
      end
    end
    return min(lo, ulo), max(hi, uhi), uhi - ulo
  elseif mode == "period" then
    local o = PERIOD_OPTIONS[param.name] or false
    local bad, n = 0, 0
    for i = 1, 500 do
      local p = point(i)
      local v = at(p, nil, o)
      for _, t in ipairs(PERIODS[param.name]) do
        n = n + 1
        if abs(at(t(p), nil, o) - v) > 1e-6 then bad = bad + 1 end
      end
    end
    return bad, n, 0
  end
  error("unknown mode")
end
"#;

fn harness(name: &str, mode: &str, fw: f64) -> ShaderSet {
    let source = ShaderSource::new("harness", "harness.lua", HARNESS)
        .with_param("name", ParamValue::Text(name.into()))
        .with_param("mode", ParamValue::Text(mode.into()))
        .with_number("fw", fw)
        .with_number("extent", if SHAPES.contains(&name) { 1.5 } else { 20.0 });
    ShaderSet::with_modules(vec![source], Duration::from_secs(60), None, vec![]).expect("the harness loads")
}

fn at(set: &ShaderSet, p: [f32; 3]) -> [f64; 3] {
    let input = ShadeInput { p, ..ShadeInput::default() };
    set.color(0, &input).expect("the call succeeds").map(f64::from)
}

/// Repeatable points in [-10, 10)³, or round the origin for the shapes.
fn points(name: &str, n: usize, seed: u64) -> Vec<[f32; 3]> {
    let extent = if SHAPES.contains(&name) { 1.5 } else { 10.0 };
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * extent
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, var.sqrt())
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0.0);
    for x in v {
        s += x * x;
        n += 1.0;
    }
    (s / n).sqrt()
}

#[test]
fn the_list_covers_every_pattern_of_the_module() {
    let code = format!(
        "local P = require 'patterns'\nlocal want = {{ {} }}\n\
         function color(s)\n  local missing = 0\n  for _, n in ipairs(want) do if type(P[n]) ~= 'function' then missing = missing + 1 end end\n\
         return #P.names, #want, missing\nend",
        PATTERNS.iter().map(|(n, _)| format!("{n:?}")).collect::<Vec<_>>().join(", ")
    );
    let set =
        ShaderSet::with_modules(vec![ShaderSource::new("t", "t.lua", code)], DEFAULT_TIMEOUT, None, vec![])
            .expect("loads");
    let [names, listed, missing] = at(&set, [0.0; 3]);
    assert_eq!((names, listed, missing), (PATTERNS.len() as f64, PATTERNS.len() as f64, 0.0));
}

#[test]
fn every_pattern_stays_in_its_range_and_is_not_constant() {
    for (name, _) in PATTERNS {
        let [lo, hi, spread] = at(&harness(name, "range", 0.0), [0.0; 3]);
        let top = if *name == "hexagon" { 2.0 } else { 1.0 };
        assert!(lo >= 0.0 && hi <= top, "{name}: values from {lo} to {hi}");
        assert!(spread > 0.2 * top, "{name}: unfiltered values span only {spread}");
    }
}

#[test]
fn periodic_patterns_repeat_with_their_period() {
    for name in [
        "gradient", "marble", "wood", "onion", "radial", "spiral1", "spiral2", "leopard", "checker", "brick",
        "hexagon",
    ] {
        let [bad, n, _] = at(&harness(name, "period", 0.0), [0.0; 3]);
        // Points on an edge may round to either side of it.
        assert!(n >= 500.0 && bad <= n * 0.005, "{name}: {bad} of {n} shifted points differ");
    }
}

/// The filtered form against the pattern's average over the box,
/// supersampled (216 jittered strata) at many points: no bias beyond the
/// difference's own noise, and nearer the box average than the unfiltered
/// pattern is.
#[test]
fn filtered_forms_match_a_supersampled_box_filter() {
    for (name, fw) in PATTERNS {
        let pts = points(name, 150, 7);
        let set = harness(name, "stats", *fw);
        let rows: Vec<[f64; 3]> = pts.iter().map(|p| at(&set, *p)).collect();
        let diff: Vec<f64> = rows.iter().map(|[_, f, r]| f - r).collect();
        let (bias, sd) = mean_sd(&diff);
        let se = sd / (diff.len() as f64).sqrt();
        let filtered = rms(diff.iter().copied());
        let unfiltered = rms(rows.iter().map(|[u, _, r]| u - r));
        eprintln!("{name:12} fw {fw:<5} bias {bias:+.4} (se {se:.4})  rms filtered {filtered:.4} unfiltered {unfiltered:.4}");
        assert!(bias.abs() <= 3.0 * se + 0.01, "{name}: biased by {bias} (standard error {se})");
        assert!(
            filtered < unfiltered,
            "{name}: filtered rms {filtered} is no better than unfiltered {unfiltered}"
        );
    }
}

/// A vanishing footprint gives the pattern itself; a vast one gives the
/// pattern's mean over space (measured here from the unfiltered values)
/// everywhere.
#[test]
fn filtered_forms_tend_to_the_pattern_and_to_its_mean() {
    for (name, _) in PATTERNS {
        let pts = points(name, 400, 11);
        let set = harness(name, "limits", 0.0);
        let rows: Vec<[f64; 3]> = pts.iter().map(|p| at(&set, *p)).collect();
        let off = rows.iter().filter(|[tiny, _, plain]| (tiny - plain).abs() > 1e-3).count();
        assert!(off <= pts.len() / 50, "{name}: {off} points differ under a vanishing footprint");
        let (vast, vast_sd) = mean_sd(&rows.iter().map(|r| r[1]).collect::<Vec<_>>());
        let (plain, plain_sd) = mean_sd(&rows.iter().map(|r| r[2]).collect::<Vec<_>>());
        let se = plain_sd / (pts.len() as f64).sqrt();
        eprintln!("{name:12} vast {vast:.4} (sd {vast_sd:.4})  mean of the pattern {plain:.4} (se {se:.4})");
        assert!(vast_sd < 0.01, "{name}: under a vast footprint values still vary (sd {vast_sd})");
        if SHAPES.contains(name) {
            assert!(vast.abs() < 0.01, "{name}: {vast}");
        } else {
            assert!((vast - plain).abs() <= 4.0 * se + 0.01, "{name}: tends to {vast}, its mean is {plain}");
        }
    }
}

/// dents' filtered form needs the variance of perlin3 (PERLIN_VARIANCE in
/// patterns.lua), as turbulence needs the mean of its absolute value.
#[test]
fn the_variance_of_noise_is_what_dents_assumes() {
    let pts = points("noise", 200_000, 3);
    let var = pts
        .iter()
        .map(|p| f64::from(perlin::noise3(p[0] * 10.0, p[1] * 10.0, p[2] * 10.0)).powi(2))
        .sum::<f64>()
        / pts.len() as f64;
    eprintln!("E[perlin3²] = {var:.4}");
    assert!((var - 0.0736).abs() < 0.002, "{var}");
}

fn run(code: &str) -> Result<[f64; 3], ShaderError> {
    let set = ShaderSet::with_modules(
        vec![ShaderSource::new("s0", "s0.lua", format!("local P = require 'patterns'\n{code}"))],
        Duration::from_secs(60),
        None,
        vec![],
    )?;
    set.color(0, &ShadeInput::default()).map(|c| c.map(f64::from))
}

#[test]
fn waves_shape_and_average_as_defined() {
    let pi = std::f64::consts::PI;
    // Values from the definitions: triangle peaks mid-period, sine at a
    // quarter, scallop (|sin πs|) at a half, cubic is symmetric, poly is s^e.
    let v = run("function color(s) return P.triangle_wave(0.25), P.sine_wave(0.25), P.scallop_wave(0.5) end")
        .unwrap();
    assert!((v[0] - 0.5).abs() < 1e-6 && (v[1] - 1.0).abs() < 1e-6 && (v[2] - 1.0).abs() < 1e-6, "{v:?}");
    let v = run("function color(s) return P.cubic_wave(0.5), P.poly_wave(0.5, 2), P.ramp_wave(1.25) end")
        .unwrap();
    assert!((v[0] - 0.5).abs() < 1e-6 && (v[1] - 0.25).abs() < 1e-6 && (v[2] - 0.25).abs() < 1e-6, "{v:?}");
    let v = run("function color(s) return P.wave(0.1, 0, {frequency = 2, phase = 0.3}), \
                 P.wave(0.1, 0, {wave = 'triangle', frequency = 2, phase = 0.3}), P.wave(-0.25) end")
    .unwrap();
    assert!((v[0] - 0.5).abs() < 1e-6 && (v[1] - 1.0).abs() < 1e-6 && (v[2] - 0.75).abs() < 1e-6, "{v:?}");
    // The box average in closed form against the midpoint rule, and the
    // mean under a vast width.
    let check = r#"
      local worst, means = 0, {}
      for _, w in ipairs({ "ramp", "triangle", "sine", "scallop", "cubic", "poly" }) do
        for _, v in ipairs({ -1.37, 0.05, 0.5, 2.9 }) do
          for _, vw in ipairs({ 0.01, 0.3, 1, 2.6 }) do
            local o = { wave = w, exponent = 2.5, frequency = 1.5, phase = 0.2 }
            local n, sum = 5000, 0
            for i = 1, n do sum = sum + P.wave(v - vw / 2 + (i - 0.5) / n * vw, 0, o) end
            worst = math.max(worst, math.abs(P.wave(v, vw, o) - sum / n))
          end
        end
        means[#means + 1] = P.wave(0.3, 1e7, { wave = w, exponent = 2 })
      end
      function color(s) return worst, means[4], means[6] + means[1] + means[2] + means[3] + means[5] end
    "#;
    let [worst, scallop, rest] = run(check).unwrap();
    assert!(worst < 1e-3, "closed-form box averages are off by up to {worst}");
    assert!((scallop - 2.0 / pi).abs() < 1e-5, "{scallop}");
    assert!((rest - (1.0 / 3.0 + 2.0)).abs() < 1e-5, "{rest}");
}

#[test]
fn color_maps_interpolate_and_hold_their_ends() {
    let code = "local m = P.color_map{ {0.2, 0}, {0.6, vec3(1, 0.5, 0)}, {0.6, {0, 0, 1}}, {1, 1} }\n\
                function color(s)\n\
                  local a, b, c, d, e = m(0.4), m(0.0), m(0.7), m(1.5), m(0.6)\n\
                  return a.x + 10 * a.y, b.x + c.x, d.y + 10 * e.z end";
    let [a, bc, de] = run(code).unwrap();
    assert!((a - (0.5 + 10.0 * 0.25)).abs() < 1e-6, "{a}");
    assert!((bc - 0.25).abs() < 1e-6, "{bc}");
    assert!((de - 11.0).abs() < 1e-6, "{de}");
    for (code, want) in [
        ("local m = P.color_map{ {0.5, 1}, {0.2, 0} }", "entry 2's value 0.2 is below the entry before it"),
        ("local m = P.color_map{ {0.5, 'red'} }", "entry 1 has no colour second"),
        ("local m = P.color_map{}", "expected (a list of {value, colour} entries"),
    ] {
        let e = run(code).unwrap_err();
        assert!(e.message.contains("s0.lua:2:") && e.message.contains(want), "{e}");
    }
}

#[test]
fn bad_arguments_are_errors_at_the_callers_line() {
    for (code, want) in [
        (
            "function color(s) return P.bozo(1, 2, 3), 0, 0 end",
            "patterns.bozo(p, [fw], [options]): p must be a vec3",
        ),
        ("function color(s) return P.marble(s.P, 0, {turbulance = 1}), 0, 0 end", "no option 'turbulance'"),
        (
            "function color(s) return P.marble(s.P, 0, {octaves = 40}), 0, 0 end",
            "option octaves must be a whole number",
        ),
        ("function color(s) return P.wood(s.P, 'wide'), 0, 0 end", "fw must be a number or a vec3"),
        (
            "function color(s) return P.gradient(s.P, 0, {wave = 'saw'}), 0, 0 end",
            "option wave must be one of",
        ),
        (
            "function color(s) return P.warp.repeat_(s.P, nil, {direction = vec3(1, 1, 0)}).x, 0, 0 end",
            "exactly one non-zero component",
        ),
    ] {
        let e = run(code).unwrap_err();
        assert!(e.message.contains("s0.lua:2:") && e.message.contains(want), "{code}: {e}");
        assert!(!e.message.contains('\n'), "{e}");
    }
}

#[test]
fn hexagon_weights_are_a_partition_and_tell_its_value() {
    let code = "function color(s)\n\
                  local worst, mismatch = 0, 0\n\
                  for i = 1, 300 do\n\
                    local p = vec3(hash(i, 1) * 20, 0, hash(i, 2) * 20)\n\
                    for _, w in ipairs({ 0, 0.2, 0.7, 5 }) do\n\
                      local v, a, b, c = P.hexagon(p, w)\n\
                      worst = math.max(worst, math.abs(a + b + c - 1), math.abs(b + 2 * c - v))\n\
                    end\n\
                    local v, a, b, c = P.hexagon(p)\n\
                    if ({ a, b, c })[v + 1] ~= 1 then mismatch = mismatch + 1 end\n\
                  end\n\
                  return worst, mismatch, P.hexagon(vec3(0.1, 3, -0.2))\n\
                end";
    assert_eq!(run(code).unwrap(), [0.0, 0.0, 0.0]);
}

#[test]
fn warps_move_points_as_pov_ray_does() {
    // repeat: each slab is the first moved by the offset; flip mirrors odd slabs.
    let code = "function color(s)\n\
      local a = P.warp.repeat_(vec3(4.5, 1, 2), nil, {direction = vec3(2, 0, 0), offset = vec3(0, 10, 0)})\n\
      local b = P.warp['repeat'](vec3(2.5, 1, 2), nil, {direction = vec3(2, 0, 0), flip = vec3(1, 0, 0)})\n\
      return a.x + 100 * (a.y - 21), b.x, a.z + b.z end";
    let [a, b, z] = run(code).unwrap();
    assert!((a - 0.5).abs() < 1e-9 && (b - 1.5).abs() < 1e-9 && (z - 4.0).abs() < 1e-9, "{a} {b} {z}");
    // black_hole: outside untouched; inside, pushed out by S = ((R - d)/R)^falloff · strength.
    let code = "function color(s)\n\
      local o = {center = vec3(1, 0, 0), radius = 2, strength = 0.8, falloff = 2}\n\
      local out = P.warp.black_hole(vec3(4, 0, 0), nil, o)\n\
      local q = P.warp.black_hole(vec3(2, 0, 0), nil, o)\n\
      o.inverse = true\n\
      local r = P.warp.black_hole(vec3(2, 0, 0), nil, o)\n\
      return out.x, q.x, r.x end";
    // d = 1: S = 0.5² · 0.8 = 0.2.
    let [out, q, r] = run(code).unwrap();
    assert!((out - 4.0).abs() < 1e-6 && (q - 2.2).abs() < 1e-6 && (r - 1.8).abs() < 1e-6, "{out} {q} {r}");
    // Mappings: cylindrical (angle / 2π, y, radius), spherical (angle / 2π,
    // latitude 0 to 1, distance), toroidal (angle / 2π, tube angle / 2π,
    // distance from the tube's centre).
    let code = "function color(s)\n\
      local a = math.pi / 3\n\
      local c = P.warp.cylindrical(vec3(2 * math.cos(a), 0.7, 2 * math.sin(a)))\n\
      local e = P.warp.spherical(vec3(0, 3, 0))\n\
      local t = P.warp.toroidal(vec3(0, -0.5, 3), nil, {major_radius = 3})\n\
      return math.abs(c.x - 1 / 6) + math.abs(c.y - 0.7) + math.abs(c.z - 2),\n\
        math.abs(e.y - 1) + math.abs(e.z - 3), math.abs(t.x - 0.25) + math.abs(t.y - 0.25) + math.abs(t.z - 0.5) end";
    for d in run(code).unwrap() {
        assert!(d < 1e-6, "{d}");
    }
    // Footprints follow the mapping: a width along the circle of radius 2
    // spans width / (2π · 2) of the angle; the turbulence warp of amount 0
    // moves nothing and passes widths through.
    let code = "function color(s)\n\
      local _, w = P.warp.cylindrical(vec3(2, 0, 0), vec3(0, 0, 0.01))\n\
      local q, tw = P.warp.turbulence(vec3(1.3, 2.1, 0.4), 0.2, {amount = 0})\n\
      return w.x * 4 * math.pi / 0.01, w.z, length(q - vec3(1.3, 2.1, 0.4)) + length(tw - vec3(0.2)) end";
    let [wx, wz, still] = run(code).unwrap();
    assert!((wx - 1.0).abs() < 1e-3 && wz.abs() < 1e-6 && still < 1e-6, "{wx} {wz} {still}");
}

/// A folder holding `files` (path relative to it, text).
fn tree(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("a file");
    }
    dir
}

fn scene_set(dir: &Path, code: &str) -> Result<ShaderSet, ShaderError> {
    ShaderSet::with_modules(
        vec![ShaderSource::new("s0", "s0.lua", code)],
        DEFAULT_TIMEOUT,
        None,
        vec![dir.to_path_buf()],
    )
}

#[test]
fn the_built_in_is_found_when_no_folder_has_one_and_is_not_watched() {
    let scene = tree(&[("other.lua", "return 1")]);
    let set = scene_set(
        scene.path(),
        "local P = require 'patterns'\nfunction color(s) return P.checker(vec3(0.5, 1.5, 0.5)), 0, 0 end",
    )
    .expect("loads");
    assert_eq!(set.color(0, &ShadeInput::default()).unwrap(), [1.0, 0.0, 0.0]);
    assert!(set.required_files().is_empty(), "{:?}", set.required_files());
}

#[test]
fn a_scenes_own_patterns_module_wins() {
    let scene = tree(&[("patterns.lua", "return { mine = 0.25 }")]);
    let set = scene_set(
        scene.path(),
        "local P = require 'patterns'\nfunction color(s) return P.mine, P.bozo and 1 or 0, 0 end",
    )
    .expect("loads");
    assert_eq!(set.color(0, &ShadeInput::default()).unwrap(), [0.25, 0.0, 0.0]);
    let mine = scene.path().join("patterns.lua").canonicalize().unwrap();
    assert_eq!(set.required_files(), [mine]);
}
