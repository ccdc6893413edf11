//! The shader author's side: declared parameters, the shading context,
//! vec3 arguments, antialiased patterns, and errors in luster's own terms.

use super::tests::{color_err, input};
use super::*;
use crate::noise::perlin;

fn set_with(code: &str, params: &[(&str, ParamValue)]) -> Result<ShaderSet, ShaderError> {
    let mut src = ShaderSource::new("t", "t.lua", code);
    for (k, v) in params {
        src = src.with_param(*k, v.clone());
    }
    ShaderSet::new(vec![src], DEFAULT_TIMEOUT)
}

fn rgb_of(code: &str, params: &[(&str, ParamValue)], s: &ShadeInput) -> [f32; 3] {
    set_with(code, params).unwrap().color(0, s).unwrap()
}

const DECLARED: &str = "params { freq = 4, tint = rgb(0.5, 0.25, 1), label = 'x' }\n\
                        function color(s) return param.freq, param.tint.y, #param.label end";

#[test]
fn declared_parameters_take_defaults_and_scene_values() {
    assert_eq!(rgb_of(DECLARED, &[], &input([0.0; 3])), [4.0, 0.25, 1.0]);
    let given = [
        ("freq", ParamValue::Number(2.0)),
        ("tint", ParamValue::Number(0.75)),
        ("label", ParamValue::Text("abc".into())),
    ];
    assert_eq!(rgb_of(DECLARED, &given, &input([0.0; 3])), [2.0, 0.75, 3.0]);
}

#[test]
fn a_misspelt_or_mistyped_parameter_names_the_declared_ones() {
    let e = set_with(DECLARED, &[("frequncy", ParamValue::Number(2.0))]).unwrap_err();
    assert!(e.message.contains("t.lua:1:") && e.message.contains("'frequncy'"), "{e}");
    assert!(e.message.contains("freq (number, default 4)") && e.message.contains("tint (rgb"), "{e}");
    let e = set_with(DECLARED, &[("freq", ParamValue::Vec3([1.0, 2.0, 3.0]))]).unwrap_err();
    assert!(e.message.contains("'freq' is three numbers, but the script declares one number"), "{e}");
    // Reading an undeclared name is an error too, once the script declares.
    let e = set_with("params { a = 1 }\nlocal b = param.b\nfunction color(s) return 0, 0, 0 end", &[])
        .unwrap_err();
    assert!(e.message.contains("t.lua:2: param.b is not declared"), "{e}");
    // A script that declares nothing is checked against what it reads.
    let undeclared = "local f = param.frequency or 1\nfunction color(s) return f, f, f end";
    let e = set_with(undeclared, &[("frequncy", ParamValue::Number(2.0))]).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Parameter);
    assert!(e.message.contains("'frequncy'") && e.message.contains("param.frequency"), "{e}");
    assert!(set_with(undeclared, &[("frequency", ParamValue::Number(2.0))]).is_ok());
}

#[test]
fn the_context_reaches_the_script() {
    let s = ShadeInput {
        pc: [1.0, 2.0, -3.0],
        ng: [0.0, 1.0, 0.0],
        i: [0.0, 0.0, -1.0],
        dpdx: [0.01, 0.0, 0.0],
        filterwidth: 0.02,
        object_id: 3,
        instance_id: 5,
        depth: 2,
        pixel: [7, 9],
        ..input([0.0; 3])
    };
    let get = |expr: &str| rgb_of(&format!("function color(s) return {expr} end"), &[], &s);
    assert_eq!(get("s.Pc.x, s.Pc.z, s.Ng.y"), [1.0, -3.0, 1.0]);
    assert_eq!(get("s.I.z, s.V.z, s.dPdx.x * 100"), [-1.0, 1.0, 1.0]);
    assert_eq!(get("s.object_id, s.instance_id, s.depth"), [3.0, 5.0, 2.0]);
    assert_eq!(get("s.pixel_x, s.pixel_y, filterwidth(s, 50)"), [7.0, 9.0, 1.0]);
    let r = get("s.random, s.random, 0")[0];
    assert!((0.0..1.0).contains(&r));
    let other =
        rgb_of("function color(s) return s.random, 0, 0 end", &[], &ShadeInput { instance_id: 6, ..s });
    assert_ne!(other[0], r, "neighbouring objects get different random numbers");
}

#[test]
fn built_ins_take_a_vec3_where_a_point_is_meant() {
    let p = input([0.3, 1.7, -2.2]);
    for (vec, scalars) in [
        ("perlin3(s.P)", "perlin3(s.P.x, s.P.y, s.P.z)"),
        ("fbm(s.P, 5, 2, 0.5)", "fbm(s.P.x, s.P.y, s.P.z, 5, 2, 0.5)"),
        ("turbulence(s.P, 3)", "turbulence(s.P.x, s.P.y, s.P.z, 3)"),
        ("ridged(s.P, 3, 2.5)", "ridged(s.P.x, s.P.y, s.P.z, 3, 2.5)"),
        ("(voronoi(s.P, 'manhattan'))", "(voronoi(s.P.x, s.P.y, s.P.z, 'manhattan'))"),
        ("checker(s.P)", "checker(s.P.x, s.P.y, s.P.z)"),
        ("hash(s.P)", "hash(s.P.x, s.P.y, s.P.z)"),
        ("simplex3(s.P)", "simplex3(s.P.x, s.P.y, s.P.z)"),
    ] {
        let code = format!("function color(s) return {vec}, {scalars}, 0 end");
        let [a, b, _] = rgb_of(&code, &[], &p);
        assert_eq!(a, b, "{vec} vs {scalars}");
    }
    let v = rgb_of("function color(s) return vperlin(s.P):unpack() end", &[], &p);
    assert!(v[0] != v[1] && v[1] != v[2], "{v:?}");
    assert_eq!(v[0], perlin::noise3(0.3, 1.7, -2.2));
}

/// Filtering: a zero width changes nothing; a width past the Nyquist limit
/// leaves only the mean (0 for fBm, the mean of |noise| for turbulence, ½
/// for the checker); aastep is a linear ramp of the width's length.
#[test]
fn filtered_patterns_fade_what_the_footprint_cannot_resolve() {
    let p = input([0.3, 1.7, -2.2]);
    let get = |expr: &str| rgb_of(&format!("function color(s) return {expr} end"), &[], &p);
    let [a, b, c] = get("fbm(s.P, 6, 2, 0.5, 0), fbm(s.P, 6), fbm(s.P, 6, 2, 0.5, 100)");
    assert_eq!(a, b);
    assert_eq!(c, 0.0);
    let [a, b, _] = get("turbulence(s.P, 6, 2, 0.5, 1e-9), turbulence(s.P, 6), 0");
    assert!((a - b).abs() < 1e-5, "{a} {b}");
    let [t, _, _] = get("turbulence(s.P, 2, 2, 0.5, 100), 0, 0");
    assert!((t - 0.2209 * 1.5).abs() < 1e-6, "{t}");
    let [sharp, blurred, _] = get("checker(s.P, 0), checker(s.P, 50), 0");
    assert!(sharp == 0.0 || sharp == 1.0);
    assert!((blurred - 0.5).abs() < 0.02, "{blurred}");
    assert_eq!(get("aastep(0.5, 0.5, 0.2), aastep(0.5, 0.45, 0.2), aastep(0.5, 0.2, 0.2)"), [0.5, 0.25, 0.0]);
}

/// The prelude's MEAN_ABS_PERLIN: the mean of |perlin3| over space.
#[test]
fn the_mean_of_absolute_noise_is_what_turbulence_assumes() {
    let mut seed = 1u64;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 40) as f32 / (1u64 << 24) as f32 * 100.0
    };
    let n = 200_000;
    let mean =
        (0..n).map(|_| f64::from(perlin::noise3(next(), next(), next()).abs())).sum::<f64>() / n as f64;
    eprintln!("mean |perlin3| = {mean:.4}");
    assert!((mean - 0.2209).abs() < 0.003, "{mean}");
}

#[test]
fn errors_speak_of_luster_types_not_luajit_internals() {
    for (code, want) in [
        ("return s.p.x, 0, 0", "the shading point s has no field 'p' (its fields: P, Pw"),
        ("return s.P.w, 0, 0", "a vec3 has no field 'w' (it has x, y, z"),
        ("return s.uv.x, 0, 0", "s.uv has no field 'x' (its fields: u, v)"),
        ("return math.sin(s.P), 0, 0", "got luster value (vec3, s or s.uv)"),
        ("return s.P + {}, 0, 0", "got a table"),
        ("return s + 1, 0, 0", "arithmetic on 'shading point' and 'number'"),
        ("return math.random(), 0, 0", "math.random was removed from shaders: images must not depend"),
        ("return os.time(), 0, 0", "os was removed from shaders"),
        ("local f = io.open('x')", "io was removed from shaders: shaders cannot read or write files"),
        ("return string.dump(color)", "string.dump was removed from shaders"),
    ] {
        let e = color_err(&format!("function color(s)\n  {code}\nend"));
        assert!(e.message.contains(want), "{code}: {e}");
        assert!(!e.message.contains("struct ") && !e.message.contains("cdata"), "{code}: {e}");
    }
}
