//! Closures from `material(s)`: the nodes each constructor and combinator
//! writes, their parameters' forms and checks, `openpbr{}`, and the cost of
//! a call.

use std::time::Instant;

use super::closure::{Closure, Node, NodeKind};
use super::tests::input;
use super::*;

fn set(code: &str) -> Result<ShaderSet, ShaderError> {
    ShaderSet::new(vec![ShaderSource::new("t", "t.lua", code)], DEFAULT_TIMEOUT)
}

/// The closure `material(s)` returns when its body is `body`.
fn closure_of(body: &str) -> Closure {
    let set = set(&format!("function material(s)\n{body}\nend")).unwrap();
    let m = set.material(0, &input([0.0; 3])).unwrap();
    m.closure.expect("material(s) gives a closure")
}

/// The error a call of `material(s)` gives (or building the set, if that fails).
fn err_of(code: &str) -> ShaderError {
    match set(code) {
        Ok(set) => set.material(0, &input([0.0; 3])).expect_err("the call should fail"),
        Err(e) => e,
    }
}

fn used(c: &Closure) -> &[Node] {
    &c.nodes[..usize::from(c.len)]
}

fn kinds(c: &Closure) -> Vec<NodeKind> {
    used(c).iter().map(|n| n.kind).collect()
}

fn grey(v: f32) -> [f32; 3] {
    [v; 3]
}

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6)
}

#[test]
fn each_constructor_writes_its_node_with_defaults() {
    let c = closure_of("return diffuse{}");
    assert_eq!((c.len, c.root), (1, 0));
    assert_eq!(
        c.nodes[0],
        Node { kind: NodeKind::Diffuse, c: [grey(0.8), [0.0; 3], [0.0; 3]], ..Node::default() }
    );

    let c = closure_of("return conductor{}");
    let n = c.nodes[0];
    assert_eq!((n.kind, n.c[0], n.c[1], n.x), (NodeKind::Conductor, grey(1.0), grey(1.0), [0.0; 3]));

    let c = closure_of("return dielectric{}");
    let n = c.nodes[0];
    assert_eq!(n.kind, NodeKind::Dielectric);
    assert_eq!((n.c[0], n.c[1], n.x, n.thin), (grey(1.0), grey(1.0), [1.5, 0.0, 0.0], false));

    let c = closure_of("return sheen{}");
    assert_eq!((c.nodes[0].kind, c.nodes[0].c[0], c.nodes[0].x[0]), (NodeKind::Sheen, grey(1.0), 0.3));
    let c = closure_of("return emission{}");
    assert_eq!((c.nodes[0].kind, c.nodes[0].c[0]), (NodeKind::Emission, grey(1.0)));
    let c = closure_of("return transparent{}");
    assert_eq!((c.nodes[0].kind, c.nodes[0].c[0]), (NodeKind::Transparent, grey(1.0)));
}

#[test]
fn each_constructor_takes_its_parameters() {
    let n = closure_of("return diffuse{albedo = vec3(0.25, 0.5, 0.75), roughness = 0.5}").nodes[0];
    assert_eq!((n.c[0], n.x[0]), ([0.25, 0.5, 0.75], 0.5));
    let n =
        closure_of("return conductor{f0 = 0.5, edge = {0.25, 0.5, 1}, roughness = 0.25, anisotropy = 0.75}")
            .nodes[0];
    assert_eq!((n.c[0], n.c[1], n.x), (grey(0.5), [0.25, 0.5, 1.0], [0.25, 0.75, 0.0]));
    let n = closure_of(
        "return dielectric{ior = 1.33, roughness = 0.125, anisotropy = 0.5, tint = rgb(0.5, 0.75, 1), \
         specular = 0.25, thin = true}",
    )
    .nodes[0];
    assert_eq!((n.c[0], n.c[1], n.thin), ([0.5, 0.75, 1.0], grey(0.25), true));
    assert!(close(n.x, [1.33, 0.125, 0.5]), "{:?}", n.x);
    let n = closure_of("return sheen{color = 0.5, roughness = 1}").nodes[0];
    assert_eq!((n.c[0], n.x[0]), (grey(0.5), 1.0));
    // Radiance has no upper bound.
    let n = closure_of("return emission{radiance = vec3(20, 10, 0)}").nodes[0];
    assert_eq!(n.c[0], [20.0, 10.0, 0.0]);
    let n = closure_of("return transparent{color = {r = 0.25, g = 0.5, b = 1}}").nodes[0];
    assert_eq!(n.c[0], [0.25, 0.5, 1.0]);
}

#[test]
fn colour_parameters_take_every_form() {
    for (form, want) in [
        ("0.5", grey(0.5)),
        ("vec3(0.25, 0.5, 1)", [0.25, 0.5, 1.0]),
        ("rgb(0.25, 0.5, 1)", [0.25, 0.5, 1.0]),
        ("rgb(0.5)", grey(0.5)),
        ("{0.25, 0.5, 1}", [0.25, 0.5, 1.0]),
        ("{r = 0.25, g = 0.5, b = 1}", [0.25, 0.5, 1.0]),
    ] {
        let c = closure_of(&format!("return diffuse{{albedo = {form}}}"));
        assert_eq!(c.nodes[0].c[0], want, "{form}");
    }
}

#[test]
fn add_scale_and_layer_link_their_children() {
    let c = closure_of("local d = diffuse{}\nlocal s = sheen{}\nreturn d + s");
    assert_eq!(kinds(&c), [NodeKind::Diffuse, NodeKind::Sheen, NodeKind::Add]);
    assert_eq!((c.root, c.nodes[2].a, c.nodes[2].b), (2, 0, 1));

    for (expr, w) in [
        ("0.25 * d", grey(0.25)),
        ("d * 0.25", grey(0.25)),
        ("vec3(0.25, 0.5, 1) * d", [0.25, 0.5, 1.0]),
        ("d * vec3(0.25, 0.5, 1)", [0.25, 0.5, 1.0]),
        ("rgb(0.5) * d", grey(0.5)),
        ("{0.25, 0.5, 1} * d", [0.25, 0.5, 1.0]),
    ] {
        let c = closure_of(&format!("local d = diffuse{{}}\nreturn {expr}"));
        assert_eq!(kinds(&c), [NodeKind::Diffuse, NodeKind::Scale], "{expr}");
        assert_eq!((c.root, c.nodes[1].a, c.nodes[1].c[0]), (1, 0, w), "{expr}");
    }
    // A weight of exactly 1 adds no node.
    assert_eq!(kinds(&closure_of("return 1 * diffuse{}")), [NodeKind::Diffuse]);

    let c = closure_of("return layer{top = dielectric{}, base = diffuse{}}");
    assert_eq!(kinds(&c), [NodeKind::Dielectric, NodeKind::Diffuse, NodeKind::Layer]);
    assert_eq!((c.root, c.nodes[2].a, c.nodes[2].b), (2, 0, 1));
}

#[test]
fn mix_is_two_scales_and_an_add() {
    let c = closure_of("return mix(diffuse{}, conductor{}, 0.25)");
    assert_eq!(
        kinds(&c),
        [NodeKind::Diffuse, NodeKind::Conductor, NodeKind::Scale, NodeKind::Scale, NodeKind::Add]
    );
    let n = used(&c);
    assert_eq!((n[2].a, n[2].c[0]), (0, grey(0.75)));
    assert_eq!((n[3].a, n[3].c[0]), (1, grey(0.25)));
    assert_eq!((c.root, n[4].a, n[4].b), (4, 2, 3));
    // A colour t mixes per channel.
    let c = closure_of("return mix(diffuse{}, conductor{}, vec3(0, 0.5, 1))");
    assert_eq!((c.nodes[2].c[0], c.nodes[3].c[0]), ([1.0, 0.5, 0.0], [0.0, 0.5, 1.0]));
    // t of 0 or 1 is one side, with no node added.
    let c = closure_of("return mix(diffuse{}, conductor{}, 0)");
    assert_eq!((c.len, c.root), (2, 0));
    let c = closure_of("return mix(diffuse{}, conductor{}, 1)");
    assert_eq!((c.len, c.root), (2, 1));
    // mix of numbers and vec3s is what it was.
    let set =
        set("function color(s) return mix(0, 10, 0.25), mix(vec3(2), vec3(4), 0.5).x, lerp(1, 3, 0.5) end")
            .unwrap();
    assert_eq!(set.color(0, &input([0.0; 3])).unwrap(), [2.5, 3.0, 2.0]);
}

#[test]
fn a_closure_script_has_a_closure_and_no_other_outputs() {
    let s = set("function material(s) return diffuse{} end").unwrap();
    assert!(s.has_closure(0) && s.has_material(0) && !s.has_color(0) && !s.has_emission(0));
    // Outputs beside material(s) are not called.
    let s = set("function material(s) return diffuse{} end\nfunction color(s) return 0/0, 0, 0 end").unwrap();
    let m = s.material(0, &input([0.0; 3])).unwrap();
    assert!(m.closure.is_some() && m.color.is_none() && m.roughness.is_none() && m.emission.is_none());
    // A script without material(s) has no closure, and the emission{}
    // constructor is no emission output.
    let s = set("function color(s) return 1, 0, 0 end").unwrap();
    assert!(!s.has_closure(0) && !s.has_emission(0) && s.has_material(0));
    let m = s.material(0, &input([0.0; 3])).unwrap();
    assert!(m.closure.is_none() && m.emission.is_none() && m.color == Some([1.0, 0.0, 0.0]));
    // The closure's entry is not callable alone.
    let s = set("function material(s) return diffuse{} end").unwrap();
    let mut rgb = [0.0; 3];
    let code = s.call_point(0, Entry::Material, &input([0.0; 3]), &mut rgb);
    let e = s.call_slow(0, Entry::Material, &input([0.0; 3]), code).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Usage, "{e}");
}

#[test]
fn closures_follow_the_point_from_call_to_call() {
    let s = set(
        "function material(s)\nif s.P.x > 0 then return conductor{} end\nreturn diffuse{} + sheen{}\nend",
    )
    .unwrap();
    for _ in 0..3 {
        let a = s.material(0, &input([1.0, 0.0, 0.0])).unwrap().closure.unwrap();
        assert_eq!(kinds(&a), [NodeKind::Conductor]);
        let b = s.material(0, &input([-1.0, 0.0, 0.0])).unwrap().closure.unwrap();
        assert_eq!(kinds(&b), [NodeKind::Diffuse, NodeKind::Sheen, NodeKind::Add]);
    }
}

#[test]
fn the_closure_prints_node_by_node() {
    let c = closure_of("return layer{top = 0.5 * sheen{}, base = diffuse{albedo = 0.25}}");
    let text = c.to_string();
    assert!(
        text.starts_with("#0 sheen{color=(1, 1, 1), roughness=0.3} #1 scale{(0.5, 0.5, 0.5) * #0}"),
        "{text}"
    );
    assert!(text.ends_with("#3 layer{top=#1, base=#2} root #3"), "{text}");
}

/// Checks that `code` fails at `t.lua:line` with a message containing every
/// one of `parts`.
#[track_caller]
fn fails_at(code: &str, line: u32, parts: &[&str]) {
    let e = err_of(code);
    assert_eq!(e.shader, "t", "{e}");
    assert!(e.message.starts_with(&format!("t.lua:{line}: ")), "{code}\n{e}");
    for p in parts {
        assert!(e.message.contains(p), "{code}\nwanted {p:?} in\n{e}");
    }
    assert!(!e.message.contains("luster value") && !e.message.contains("cdata"), "{e}");
}

#[test]
fn parameter_errors_name_the_line_and_the_parameter() {
    let f = |body: &str| format!("function material(s)\n  local c = {body}\n  return c\nend");
    let e = err_of(&f("diffuse{albdo = 0.5}"));
    assert_eq!(e.kind, ShaderErrorKind::Runtime);
    assert_eq!(e.message, "t.lua:2: diffuse{}: unknown parameter 'albdo' (diffuse takes albedo, roughness)");
    assert_eq!(
        e.to_string(),
        "shader 't': t.lua:2: diffuse{}: unknown parameter 'albdo' (diffuse takes albedo, roughness)"
    );
    fails_at(
        &f("diffuse{albedo = 'red'}"),
        2,
        &["diffuse{}: albedo is a string (expected a number from 0 to 1"],
    );
    fails_at(&f("diffuse{albedo = 1.5}"), 2, &["diffuse{}: albedo is 1.5 (expected a number from 0 to 1"]);
    fails_at(
        &f("diffuse{albedo = vec3(0.5, 1.5, 0)}"),
        2,
        &["albedo's green value is 1.5 (expected 0 to 1)"],
    );
    fails_at(&f("diffuse{albedo = {0.5, 0/0, 0}}"), 2, &["albedo's green value is NaN (expected 0 to 1)"]);
    fails_at(&f("diffuse{albedo = {0.5}}"), 2, &["albedo is a table without three numbers"]);
    fails_at(
        &f("diffuse{roughness = 0/0}"),
        2,
        &["diffuse{}: roughness is NaN (expected a number from 0 to 1)"],
    );
    fails_at(&f("conductor{anisotropy = -0.5}"), 2, &["conductor{}: anisotropy is -0.5"]);
    fails_at(&f("conductor{f0 = '1'}"), 2, &["conductor{}: f0 is a string"]);
    fails_at(&f("dielectric{ior = 0.5}"), 2, &["dielectric{}: ior is 0.5 (expected a number from 1 to 5)"]);
    fails_at(&f("dielectric{ior = 1/0}"), 2, &["dielectric{}: ior is inf"]);
    fails_at(&f("dielectric{thin = 1}"), 2, &["dielectric{}: thin is a number (expected true or false)"]);
    fails_at(&f("sheen{roughness = '0.3'}"), 2, &["sheen{}: roughness is a string (expected a number"]);
    fails_at(
        &f("emission{radiance = -1}"),
        2,
        &["emission{}: radiance is -1 (expected a finite number, 0 or more"],
    );
    fails_at(&f("emission{radiance = vec3(1, 1/0, 1)}"), 2, &["radiance's green value is inf"]);
    fails_at(
        &f("transparent{colour = 1}"),
        2,
        &["transparent{}: unknown parameter 'colour' (transparent takes color)"],
    );
    fails_at(
        &f("diffuse(0.5)"),
        2,
        &["diffuse{} takes one table of named parameters (albedo, roughness), got a number"],
    );
}

#[test]
fn combinator_errors_name_the_line() {
    let f = |body: &str| {
        format!("function material(s)\n  local d = diffuse{{}}\n  local c = {body}\n  return c\nend")
    };
    fails_at(
        &f("d + 1"),
        3,
        &["closure +: the right operand is a number (expected a closure such as diffuse{...})"],
    );
    fails_at(&f("vec3(1) + d"), 3, &["vec3 +: expected a vec3 or a number, got a closure"]);
    fails_at(&f("d * d"), 3, &["closure *: both operands are closures"]);
    fails_at(&f("1.5 * d"), 3, &["closure *: the weight is 1.5"]);
    fails_at(&f("vec3(0.5, 2, 0) * d"), 3, &["closure *: the weight's green value is 2"]);
    fails_at(&f("d * (0/0)"), 3, &["closure *: the weight is NaN"]);
    fails_at(&f("mix(d, 1, 0.5)"), 3, &["mix(): the second closure is a number"]);
    fails_at(&f("mix(d, d, 2)"), 3, &["mix(): t is 2"]);
    fails_at(&f("mix(d, d)"), 3, &["mix(): t is missing"]);
    fails_at(
        &f("layer{top = d}"),
        3,
        &["layer{}: base is missing (expected a closure such as diffuse{...})"],
    );
    fails_at(&f("layer{base = d}"), 3, &["layer{}: top is missing"]);
    fails_at(&f("layer{top = d, base = 0.5}"), 3, &["layer{}: base is a number"]);
    fails_at(&f("d - d"), 3, &["closure -: not defined"]);
    fails_at(&f("d.albedo"), 3, &["a closure has no field 'albedo'"]);
}

#[test]
fn material_must_return_a_closure_of_its_own_call() {
    for (body, what) in [
        ("return 1", "material() returned a number (expected a closure such as diffuse{...})"),
        ("return nil", "material() returned nothing (nil) (expected a closure such as diffuse{...})"),
        ("return vec3(1)", "material() returned a vec3 (expected a closure such as diffuse{...})"),
    ] {
        let e = err_of(&format!("function material(s) {body} end"));
        assert_eq!(e.kind, ShaderErrorKind::BadResult, "{e}");
        assert_eq!(e.message, what);
        assert!(e.to_string().starts_with("shader 't': material() returned"), "{e}");
    }
    // A closure kept from an earlier call is refused, returned or combined.
    let kept =
        "local kept\nfunction material(s)\n  if kept == nil then kept = diffuse{} end\n  return kept\nend";
    let s = set(kept).unwrap();
    assert!(s.material(0, &input([0.0; 3])).is_ok());
    let e = s.material(0, &input([0.0; 3])).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::BadResult, "{e}");
    assert!(e.message.contains("material() returned a closure from an earlier call of material(s)"), "{e}");
    let kept = "local kept\nfunction material(s)\n  if kept == nil then kept = diffuse{} return kept end\n  \
                return kept + sheen{}\nend";
    let s = set(kept).unwrap();
    assert!(s.material(0, &input([0.0; 3])).is_ok());
    let e = s.material(0, &input([0.0; 3])).unwrap_err();
    assert!(
        e.message.starts_with("t.lua:4: closure +: the left operand is a closure from an earlier call"),
        "{e}"
    );
    // Nor can one be built outside a call of material(s).
    let e = err_of("local d = diffuse{}\nfunction material(s) return d end");
    assert!(
        e.message.starts_with("t.lua:1: diffuse{}: closures can be built only while material(s) runs"),
        "{e}"
    );
}

#[test]
fn more_than_32_nodes_is_an_error() {
    let code =
        "function material(s)\n  local c = diffuse{}\n  for i = 1, 20 do\n    c = c + sheen{}\n  end\n  \
                return c\nend";
    fails_at(code, 4, &["the closure would have more than 32 nodes"]);
    // Exactly 32 is fine.
    let c = closure_of("local c = diffuse{}\nfor i = 1, 31 do c = 0.5 * c end\nreturn c");
    assert_eq!((c.len, c.root), (32, 31));
    assert!(used(&c)
        .iter()
        .skip(1)
        .enumerate()
        .all(|(i, n)| n.kind == NodeKind::Scale && usize::from(n.a) == i));
}

#[test]
fn openpbr_defaults_are_a_glossy_diffuse() {
    let c = closure_of("return openpbr{}");
    assert_eq!(kinds(&c), [NodeKind::Diffuse, NodeKind::Dielectric, NodeKind::Layer]);
    let n = used(&c);
    assert_eq!((n[0].c[0], n[0].x[0]), (grey(0.8), 0.0));
    assert_eq!((n[1].c[0], n[1].c[1], n[1].thin), (grey(1.0), grey(1.0), false));
    assert!(close(n[1].x, [1.5, 0.3, 0.0]), "{:?}", n[1].x);
    assert_eq!((c.root, n[2].a, n[2].b), (2, 1, 0));
}

#[test]
fn openpbr_builds_only_the_branches_with_weight() {
    let k = |args: &str| kinds(&closure_of(&format!("return openpbr{{{args}}}")));
    use NodeKind::*;
    assert_eq!(k("base_metalness = 1"), [Conductor]);
    assert_eq!(k("transmission_weight = 1"), [Dielectric]);
    assert_eq!(k("base_metalness = 0.5"), [Diffuse, Dielectric, Layer, Conductor, Scale, Scale, Add]);
    assert_eq!(k("coat_weight = 1"), [Diffuse, Dielectric, Layer, Dielectric, Layer]);
    assert_eq!(k("coat_weight = 0.5"), [Diffuse, Dielectric, Layer, Dielectric, Scale, Layer]);
    assert_eq!(k("fuzz_weight = 1, base_metalness = 1"), [Conductor, Sheen, Layer]);
    assert_eq!(k("emission_luminance = 5, base_metalness = 1"), [Conductor, Emission, Add]);
    assert_eq!(k("geometry_opacity = 0.5, base_metalness = 1"), [Conductor, Transparent, Scale, Scale, Add]);
    assert_eq!(k("geometry_opacity = 0, base_metalness = 1"), [Conductor, Transparent]);

    // The values each branch maps to.
    let c = closure_of(
        "return openpbr{base_metalness = 1, base_weight = 0.5, base_color = vec3(1, 0.5, 0.25), \
         specular_weight = 0.5, specular_color = 0.5, specular_roughness = 0.25, specular_anisotropy = 0.5, \
         coat_weight = 0.5, coat_color = 0.75, coat_roughness = 0.125, coat_ior = 1.25, \
         fuzz_weight = 1, fuzz_color = 0.5, fuzz_roughness = 0.75, emission_luminance = 4, \
         emission_color = vec3(1, 0.5, 0)}",
    );
    let n = used(&c);
    assert_eq!(kinds(&c), [Conductor, Dielectric, Scale, Layer, Sheen, Layer, Emission, Add]);
    assert_eq!((n[0].c[0], n[0].c[1], n[0].x), ([0.5, 0.25, 0.125], grey(0.25), [0.25, 0.5, 0.0]));
    assert_eq!((n[1].c[0], n[1].x), (grey(0.75), [1.25, 0.125, 0.0]));
    assert_eq!((n[2].a, n[2].c[0], n[3].a, n[3].b), (1, grey(0.5), 2, 0));
    assert_eq!((n[4].c[0], n[4].x[0], n[5].a, n[5].b), (grey(0.5), 0.75, 4, 3));
    assert_eq!((n[6].c[0], n[7].a, n[7].b, c.root), ([4.0, 2.0, 0.0], 5, 6, 7));

    // Transmission, thin walls, subsurface and the specular weight.
    let c = closure_of(
        "return openpbr{transmission_weight = 0.25, transmission_color = 0.5, thin_walled = true, \
         base_weight = 0.5, subsurface_weight = 0.5, subsurface_color = 0.4, base_color = 0.8, \
         specular_weight = 0}",
    );
    let n = used(&c);
    assert_eq!(kinds(&c), [Diffuse, Dielectric, Layer, Dielectric, Scale, Scale, Add]);
    assert!(close(n[0].c[0], grey(0.3)), "{:?}", n[0].c[0]);
    assert!(n[1].thin && n[3].thin && n[1].x[0] == 1.0, "specular_weight 0 leaves no interface");
    assert_eq!((n[1].c[0], n[3].c[0]), (grey(1.0), grey(0.5)));
    assert_eq!((n[4].c[0], n[5].c[0]), (grey(0.75), grey(0.25)));
    // specular_weight scales F0: half of 1.5's 0.04 is an ior of about 1.33.
    let n = closure_of("return openpbr{specular_weight = 0.5}").nodes[1];
    let f0 = ((n.x[0] - 1.0) / (n.x[0] + 1.0)).powi(2);
    assert!((f0 - 0.02).abs() < 1e-6, "{f0}");
}

#[test]
fn openpbr_is_a_closure_like_the_others() {
    let c = closure_of("return layer{top = 0.5 * sheen{}, base = openpbr{base_metalness = 1}}");
    assert_eq!(kinds(&c), [NodeKind::Sheen, NodeKind::Scale, NodeKind::Conductor, NodeKind::Layer]);
    let f = |body: &str| format!("function material(s)\n  local c = {body}\n  return c\nend");
    fails_at(
        &f("openpbr{base_colour = 0.5}"),
        2,
        &["openpbr{}: unknown parameter 'base_colour' (openpbr takes base_weight, base_color,"],
    );
    fails_at(
        &f("openpbr{coat_ior = 0.5}"),
        2,
        &["openpbr{}: coat_ior is 0.5 (expected a number from 1 to 5)"],
    );
    fails_at(&f("openpbr{base_color = vec3(0, 0/0, 0)}"), 2, &["openpbr{}: base_color's green value is NaN"]);
    fails_at(
        &f("openpbr{geometry_thin_walled = 'yes'}"),
        2,
        &["openpbr{}: geometry_thin_walled is a string"],
    );
    let over = "function material(s)\n  local c = openpbr{coat_weight = 0.5, fuzz_weight = 0.5}\n  \
                for i = 1, 12 do\n    c = mix(c, diffuse{}, 0.5)\n  end\n  return c\nend";
    fails_at(over, 4, &["mix(): the closure would have more than 32 nodes"]);
    let full = "function material(s)\n  local c = diffuse{}\n  for i = 1, 20 do c = 0.5 * c end\n  \
                return openpbr{coat_weight = 0.5, fuzz_weight = 0.5, base_metalness = 0.5, \
                transmission_weight = 0.5}\nend";
    let e = err_of(full);
    assert!(e.message.contains("openpbr{}: the closure would have more than 32 nodes"), "{e}");
}

#[test]
fn an_error_in_a_returned_constructor_still_names_the_parameter() {
    // `return diffuse{...}` is a tail call: Lua keeps no line for it.
    let e = err_of("function material(s)\n  return diffuse{albdo = 1}\nend");
    assert!(e.message.contains("diffuse{}: unknown parameter 'albdo'"), "{e}");
    assert!(!e.message.contains("prelude"), "{e}");
}

/// Prints what one `material(s)` call costs, the best of five rounds
/// (release mode: `cargo test --release -p luster-shading closure_call_cost
/// -- --nocapture`). A script with `color(s)` alone is the baseline: the
/// cost of the call itself.
#[test]
fn closure_call_cost() {
    let calls = if cfg!(debug_assertions) { 1_000 } else { 100_000 };
    let cases = [
        ("color(s) alone (the baseline)", "function color(s) return 0.5, 0.5, 0.5 end"),
        ("diffuse{}", "function material(s) return diffuse{} end"),
        (
            "diffuse{albedo = vec3(...), roughness}",
            "function material(s) return diffuse{albedo = vec3(s.P.x, 0.5, 0.5), roughness = 0.5} end",
        ),
        ("openpbr{}", "function material(s) return openpbr{} end"),
        (
            "openpbr with coat",
            "function material(s) return openpbr{base_color = vec3(0.8, 0.2, 0.1), specular_roughness = 0.2, \
             coat_weight = 1, coat_roughness = 0.05} end",
        ),
    ];
    let sets: Vec<ShaderSet> = cases.iter().map(|(_, code)| set(code).unwrap()).collect();
    let i = input([0.25, 0.5, 0.75]);
    let mut best = vec![f64::MAX; cases.len()];
    for _ in 0..5 {
        for (s, best) in sets.iter().zip(&mut best) {
            for _ in 0..1000 {
                s.material(0, &i).unwrap();
            }
            let t = Instant::now();
            for _ in 0..calls {
                std::hint::black_box(s.material(0, &i).unwrap());
            }
            *best = best.min(t.elapsed().as_nanos() as f64 / f64::from(calls));
        }
    }
    for ((what, _), ns) in cases.iter().zip(best) {
        println!("material(s) with {what}: {ns:.0} ns per call");
    }
}
