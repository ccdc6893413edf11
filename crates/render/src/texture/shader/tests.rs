//! Tests of shader texture maps (`shader/mod.rs`): decal modes against entry
//! points, evaluation at surface points, and material outputs.

use super::*;
use crate::bsdf::lobe::{Conductor, Diffuse, Lobe};
use crate::texture::Texture;
use luster_scene::Loc;
use luster_shading::shader::ParamValue;

fn map(code: &str, decal: DecalMode, params: &[(&str, f64)]) -> TextureMapDesc {
    TextureMapDesc {
        id: "m".into(),
        source: TextureSource::Shader {
            path: "dir/s.lua".into(),
            code: code.into(),
            params: params.iter().map(|(k, v)| (k.to_string(), ParamValue::Number(*v))).collect(),
        },
        decal,
        bump_factor: 1.0,
        loc: Loc::default(),
    }
}

fn frame() -> TexFrame {
    TexFrame {
        uv: Vec2::new(0.25, 0.75),
        p_object: Vec3::new(0.5, 0.0, 0.0),
        p_world: Vec3::new(1.5, 0.0, 0.0),
        time: 0.5,
        p_rest: Vec3::new(1.5, 0.0, 0.0),
        rest_in_object: false,
        dpdu: Vec3::X,
        dpdv: Vec3::Y,
        n: Vec3::Z,
        to_world: None,
        footprint: 0.0,
        ctx: Default::default(),
    }
}

const GREY: &str = "local g = param.g\nassert(g < 1, 'g too big')\nfunction color(s) return g, g, g end";

#[test]
fn one_script_serves_maps_with_different_parameters() {
    let descs =
        [map(GREY, DecalMode::ReplaceKd, &[("g", 0.2)]), map(GREY, DecalMode::ReplaceKd, &[("g", 0.6)])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let lists = [tex.maps[0], tex.maps[1]];
    let diffuse: Vec<Vec3> = lists
        .iter()
        .map(|m| {
            let Texture::Shader { id } = m.texture else { panic!("a shader map") };
            let mut mat = Material::default();
            let mut n = Vec3::Z;
            assert_eq!(
                tex.apply_shader(id, m, &frame(), &mut mat, &mut n, &mut Lobes::default()).unwrap(),
                None
            );
            mat.diffuse
        })
        .collect();
    assert_eq!(diffuse, [Vec3::splat(0.2), Vec3::splat(0.6)]);
}

#[test]
fn the_failing_map_is_found_even_when_its_script_is_shared() {
    let descs =
        [map(GREY, DecalMode::ReplaceKd, &[("g", 0.2)]), map(GREY, DecalMode::ReplaceKd, &[("g", 3.0)])];
    let e = compile(&descs, DEFAULT, None).unwrap_err();
    assert_eq!(e.map, 1);
    assert!(e.message.contains("s.lua:2") && e.message.contains("g too big"), "{}", e.message);
}

#[test]
fn decal_modes_need_their_entry_points() {
    let bg = [map(GREY, DecalMode::ReplaceBackground, &[("g", 0.1)])];
    assert!(compile(&bg, DEFAULT, None)
        .unwrap_err()
        .message
        .contains("cannot drive DecalMode replace_background"));
    let km = [map(GREY, DecalMode::ReplaceKm, &[("g", 0.1)])];
    assert!(compile(&km, DEFAULT, None).unwrap_err().message.contains("no reflect(s)"));
    assert!(compile(&[], DEFAULT, None).unwrap().is_none());
}

#[test]
fn the_script_sees_the_frame_and_reflect_makes_a_mirror() {
    let code = "function reflect(s) return s.P.x, s.Pw.x, s.uv.v + s.time end\n\
                function color(s) return s.N.x, s.N.y, s.N.z end";
    let descs = [map(code, DecalMode::ReplaceKm, &[]), map(code, DecalMode::ReplaceAll, &[])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let mut mat = Material::default();
    let mut n = Vec3::Y;
    assert_eq!(
        tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut n, &mut Lobes::default()).unwrap(),
        None
    );
    assert_eq!(mat.mirror, Vec3::new(0.5, 1.5, 1.25));
    assert_eq!(mat.kind, Specular::Mirror);
    assert_eq!(
        tex.apply_shader(1, &tex.maps[1], &frame(), &mut mat, &mut n, &mut Lobes::default()).unwrap(),
        Some(Vec3::Y)
    );
}

#[test]
fn a_height_shader_bumps_and_its_errors_come_back() {
    let code = "function height(s)\n  if s.P.y > 1 then error('bad') end\n  return 0.5 * s.P.x\nend";
    let descs = [map(code, DecalMode::BumpNormal, &[])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let mut mat = Material::default();
    let mut n = Vec3::Z;
    tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut n, &mut Lobes::default()).unwrap();
    // Slope 0.5 along x tilts the normal towards -x: n ∝ (-0.5, 0, 1).
    assert!((n - Vec3::new(-0.5, 0.0, 1.0).normalize()).length() < 1e-3, "{n}");
    let high = TexFrame { p_object: Vec3::new(0.0, 2.0, 0.0), ..frame() };
    let e = tex.apply_shader(0, &tex.maps[0], &high, &mut mat, &mut n, &mut Lobes::default()).unwrap_err();
    assert!(e.message.contains("s.lua:2: bad"), "{}", e.message);
}

#[test]
fn material_outputs_become_a_diffuse_and_conductor_closure() {
    let code = "function color(s) return 0.8, 0.4, 0.2 end\n\
                function specular(s) return 0.04, 0.04, 0.04 end\n\
                function roughness(s) return 0.5 end\n\
                function metalness(s) return 0.25 end\n\
                function emission(s) return 3, 2, 1 end";
    let descs = [map(code, DecalMode::Material, &[])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let mut mat = Material { phong: 30.0, ..Material::default() };
    let mut n = Vec3::Z;
    let mut lobes = Lobes::default();
    assert_eq!(tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut n, &mut lobes).unwrap(), None);
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
    assert!(close(mat.diffuse, Vec3::new(0.6, 0.3, 0.15)), "{}", mat.diffuse);
    assert!(close(mat.specular, Vec3::new(0.23, 0.13, 0.08)), "{}", mat.specular);
    assert_eq!(mat.emission, Vec3::new(3.0, 2.0, 1.0));
    assert!(mat.closure && mat.brdf.is_none() && mat.kind == Specular::None);
    // The diffuse part dimmed by the largest specular colour, then the metal.
    assert_eq!(lobes.len(), 2);
    let want = [
        Lobe::Diffuse(Diffuse::new(Vec3::new(0.6, 0.3, 0.15) * 0.77, 0.0)),
        Lobe::Conductor(Conductor::new(Vec3::new(0.23, 0.13, 0.08), Vec3::ONE, 0.5, 0.0)),
    ];
    for (k, w) in want.iter().enumerate() {
        let (l, weight) = lobes.lobe(k);
        assert_eq!(weight, Vec3::ONE);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let wi = Vec3::new(-0.3, 0.2, 0.9).normalize();
        let (a, b) = (l.eval(wo, wi), w.eval(wo, wi));
        assert!(close(a.0, b.0) && (a.1 - b.1).abs() < 1e-5, "lobe {k}");
    }
}

#[test]
fn material_mode_keeps_what_the_script_does_not_define() {
    // Only emission: the material's own model, colours and exponent stay.
    let descs = [map("function emission(s) return 0, 5, 0 end", DecalMode::Material, &[])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let before =
        Material { diffuse: Vec3::splat(0.5), specular: Vec3::ONE, phong: 40.0, ..Material::default() };
    let mut mat = before;
    let mut lobes = Lobes::default();
    tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone(), &mut lobes).unwrap();
    assert_eq!(
        (mat.diffuse, mat.specular, mat.phong, mat.brdf, mat.closure),
        (before.diffuse, before.specular, 40.0, None, false)
    );
    assert_eq!(mat.emission, Vec3::new(0.0, 5.0, 0.0));
    // Metalness without roughness keeps the exponent's highlight width:
    // α = sqrt(2 / (p + 2)), roughness √α.
    let descs = [map("function metalness(s) return 1 end", DecalMode::Material, &[])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let mut mat = before;
    tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone(), &mut lobes).unwrap();
    assert_eq!((mat.diffuse, mat.specular), (Vec3::ZERO, Vec3::splat(0.5)));
    let r = (2.0f32 / 42.0).sqrt().sqrt();
    let want = Lobe::Conductor(Conductor::new(Vec3::splat(0.5), Vec3::ONE, r, 0.0));
    assert!(mat.closure);
    // The diffuse lobe is black and left out.
    assert_eq!(lobes.len(), 1);
    let (wo, wi) = (Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.5, 0.1, 0.86).normalize());
    assert!((lobes.lobe(0).0.eval(wo, wi).0 - want.eval(wo, wi).0).abs().max_element() < 1e-5);
}

#[test]
fn a_closure_replaces_the_material() {
    let code = "function material(s) return 0.5 * diffuse{albedo = 0.6} + emission{radiance = 2} end";
    let descs = [map(code, DecalMode::Material, &[])];
    let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
    let mut mat =
        Material { diffuse: Vec3::ONE, kind: Specular::Mirror, mirror: Vec3::ONE, ..Material::default() };
    let mut lobes = Lobes::default();
    tex.apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone(), &mut lobes).unwrap();
    assert!(mat.closure && mat.kind == Specular::None && mat.diffuse == Vec3::ZERO);
    assert_eq!(mat.emission, Vec3::splat(2.0));
    assert_eq!(lobes.len(), 1);
    assert_eq!(lobes.lobe(0).1, Vec3::splat(0.5));
}

#[test]
fn out_of_range_material_outputs_are_one_sentence_errors() {
    for (code, what) in [
        ("function roughness(s) return 1.5 end", "roughness() returned 1.5 (expected a number from 0 to 1)"),
        ("function metalness(s) return -0.1 end", "metalness() returned -0.1"),
        ("function roughness(s) return 0/0 end", "roughness() returned NaN"),
        ("function color(s) return 1.2, 0, 0 end", "color() returned 1.2 as its red value (expected 0 to 1"),
        ("function specular(s) return 0, 0, -1 end", "specular() returned -1 as its blue value"),
        (
            "function emission(s) return 0, -2, 0 end",
            "emission() returned -2 as its green value (expected 0 or more",
        ),
        ("function emission(s) return 1/0, 0, 0 end", "emission() returned inf as its red value"),
        ("function reflect(s) return 0.5 end", "reflect() returned nothing (nil) as its green value"),
    ] {
        let descs = [map(code, DecalMode::Material, &[])];
        let tex = Textures::new(vec![], &descs, None, compile(&descs, DEFAULT, None).unwrap());
        let mut mat = Material::default();
        let e = tex
            .apply_shader(0, &tex.maps[0], &frame(), &mut mat, &mut Vec3::Z.clone(), &mut Lobes::default())
            .unwrap_err();
        assert_eq!(e.kind, luster_shading::shader::ShaderErrorKind::BadResult, "{code}: {e}");
        let text = e.to_string();
        assert!(text.contains(what) && !text.contains('\n'), "{code}: {text}");
    }
    // A script with no material output cannot drive the mode.
    let descs = [map("function height(s) return 0 end", DecalMode::Material, &[])];
    let e = compile(&descs, DEFAULT, None).unwrap_err();
    assert!(e.message.contains("defines none of material, color, specular, roughness"), "{}", e.message);
}

#[test]
fn a_moved_point_is_the_point_input_builds_there() {
    let xf = luster_core::math::Transform::scaling(Vec3::new(2.0, 1.0, 0.5))
        .and_then(|s| luster_core::math::Transform::rotation(30.0, Vec3::Y).map(|r| s.then(&r)))
        .unwrap();
    let mut f = frame();
    f.to_world = Some(xf);
    f.ctx.view =
        crate::texture::View { eye: Vec3::new(0.0, 1.0, 5.0), right: Vec3::X, up: Vec3::Y, back: Vec3::Z };
    f.ctx.incident = Vec3::new(0.0, -0.6, -0.8);
    f.ctx.set_footprint(0.01);
    let n = Vec3::new(0.0, 0.6, 0.8);
    let base = input(&f, f.p_object, f.uv, n);
    for (p, uv) in [
        (f.p_object + Vec3::new(1e-3, 0.0, 0.0), f.uv + Vec2::new(1e-3, 0.0)),
        (f.p_object + Vec3::new(0.0, -2e-3, 5e-4), f.uv + Vec2::new(0.0, 2e-3)),
        (f.p_object, f.uv),
    ] {
        assert_eq!(moved(&f, &base, p, uv), input(&f, p, uv, n), "at {p}");
    }
}

#[test]
fn the_footprint_reaches_the_script_in_every_space() {
    let xf = luster_core::math::Transform::scaling(Vec3::new(2.0, 1.0, 0.5))
        .and_then(|s| luster_core::math::Transform::rotation(30.0, Vec3::Y).map(|r| s.then(&r)))
        .unwrap();
    let mut f = frame();
    // A sheared parameterization, so that du and dv mix.
    f.dpdu = Vec3::new(2.0, 0.0, 0.0);
    f.dpdv = Vec3::new(1.0, 3.0, 0.0);
    f.to_world = Some(xf);
    f.ctx.view = crate::texture::View {
        eye: Vec3::new(0.0, 1.0, 5.0),
        right: Vec3::new(0.6, 0.0, -0.8),
        up: Vec3::Y,
        back: Vec3::new(0.8, 0.0, 0.6),
    };
    f.ctx.ng = xf.normal_to_world(Vec3::Z).normalize();
    f.ctx.incident = Vec3::new(0.1, -0.6, -0.8).normalize();
    f.ctx.set_footprint(0.01);
    let i = input(&f, f.p_object, f.uv, Vec3::Z);
    let v = Vec3::from_array;
    assert_eq!((v(i.dpwdx), v(i.dpwdy)), (f.ctx.dpdx, f.ctx.dpdy));
    for (pc, pw) in [(i.dpcdx, i.dpwdx), (i.dpcdy, i.dpwdy)] {
        // A camera-space step is the difference of two camera-space points
        // (rounded to the points' own precision).
        let view = &f.ctx.view;
        let want = view.to_camera(f.p_world + v(pw)) - view.to_camera(f.p_world);
        let ulp = f32::EPSILON * (f.p_world - view.eye).length();
        assert!((v(pc) - want).length() <= 4.0 * ulp, "{pc:?} vs {want}");
    }
    for (duv, dp) in [(i.duvdx, i.dpdx), (i.duvdy, i.dpdy)] {
        // The footprint lies in the surface, so the uv step rebuilds it.
        let rebuilt = f.dpdu * duv[0] + f.dpdv * duv[1];
        assert!(v(dp).length() > 0.0);
        assert!((rebuilt - v(dp)).length() <= 1e-4 * v(dp).length(), "{rebuilt} vs {dp:?}");
    }
    // A degenerate parameterization gives no uv change.
    f.dpdv = f.dpdu * 2.0;
    let i = input(&f, f.p_object, f.uv, Vec3::Z);
    assert_eq!((i.duvdx, i.duvdy), ([0.0; 2], [0.0; 2]));
}

const DEFAULT: Duration = luster_shading::shader::DEFAULT_TIMEOUT;
