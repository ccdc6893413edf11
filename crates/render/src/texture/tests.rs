//! Texture lookups, uv frames, normal and bump mapping on synthetic inputs.

use super::*;
use crate::accel::TriHit;
use crate::geometry::{Mesh, Sphere};
use luster_scene::description::NoiseConversion;

fn frame(n: Vec3, dpdu: Vec3, dpdv: Vec3, uv: Vec2) -> TexFrame {
    TexFrame {
        uv,
        p_object: Vec3::new(0.3, 0.2, 0.1),
        p_world: Vec3::new(0.3, 0.2, 0.1),
        time: 0.0,
        p_rest: Vec3::new(0.3, 0.2, 0.1),
        rest_in_object: false,
        dpdu,
        dpdv,
        n,
        to_world: None,
        footprint: 0.0,
        ctx: Default::default(),
    }
}

/// A 2×2 image: black, white / red, blue.
fn tiny() -> Image {
    Image::from_rgb8(2, 2, vec![[0, 0, 0], [255, 255, 255], [255, 0, 0], [0, 0, 255]]).unwrap()
}

#[test]
fn nearest_picks_the_texel_containing_the_point() {
    let img = tiny();
    assert_eq!(img.nearest(Vec2::new(0.1, 0.1)), Vec3::ZERO);
    assert_eq!(img.nearest(Vec2::new(0.9, 0.1)), Vec3::splat(255.0));
    assert_eq!(img.nearest(Vec2::new(0.1, 0.9)), Vec3::new(255.0, 0.0, 0.0));
    assert_eq!(img.nearest(Vec2::new(0.9, 0.9)), Vec3::new(0.0, 0.0, 255.0));
    // Repeats outside [0, 1].
    assert_eq!(img.nearest(Vec2::new(1.9, -0.1)), img.nearest(Vec2::new(0.9, 0.9)));
}

#[test]
fn bilinear_weights_texels_at_integer_coordinates_and_repeats_edges() {
    let img = tiny();
    // The course's convention: texel (i, j) has full weight at (i, j)·size.
    assert_eq!(img.bilinear(Vec2::new(0.0, 0.0)), Vec3::ZERO);
    let mid = img.bilinear(Vec2::new(0.25, 0.0));
    assert!((mid - Vec3::splat(127.5)).length() < 1e-3, "{mid}");
    let c = img.bilinear(Vec2::new(0.25, 0.25));
    assert!((c - Vec3::new(127.5, 63.75, 127.5)).length() < 1e-3, "{c}");
    // Beyond the last texel the edge repeats rather than wrapping around.
    assert_eq!(img.bilinear(Vec2::new(0.75, 0.0)), Vec3::splat(255.0));
    assert_eq!(img.bilinear(Vec2::new(0.75, 0.75)), Vec3::new(0.0, 0.0, 255.0));
}

#[test]
fn trilinear_blends_mip_levels() {
    let mut img = tiny();
    img.build_mipmaps();
    assert_eq!(img.level_count(), 2);
    let mean = Vec3::new(127.5, 63.75, 127.5);
    let top = img.trilinear(Vec2::new(0.0, 0.0), 0.0);
    assert_eq!(top, Vec3::ZERO);
    // Level 1 is the 1×1 average (rounded to 8 bits).
    let l1 = img.trilinear(Vec2::new(0.0, 0.0), 1.0);
    assert!((l1 - mean).abs().max_element() <= 0.5, "{l1}");
    let half = img.trilinear(Vec2::new(0.0, 0.0), 0.5);
    assert!((half - (top + l1) * 0.5).length() < 1e-3, "{half}");
    // Beyond the coarsest level, the coarsest level; below 0, level 0.
    assert_eq!(img.trilinear(Vec2::new(0.0, 0.0), 7.0), l1);
    assert_eq!(img.trilinear(Vec2::new(0.0, 0.0), -3.0), top);
    // A 5×3 image halves to 2×1 and then 1×1.
    let mut odd = Image::from_rgb8(5, 3, vec![[10, 20, 30]; 15]).unwrap();
    odd.build_mipmaps();
    assert_eq!(odd.level_count(), 3);
    assert_eq!(odd.trilinear(Vec2::new(0.5, 0.5), 2.0), Vec3::new(10.0, 20.0, 30.0));
}

#[test]
fn sphere_uv_follows_the_course_mapping_and_derivatives_match_differences() {
    let s = Sphere { center: Vec3::new(1.0, 2.0, 3.0), radius: 2.0 };
    // The +y pole is v = 0, the equator v = 1/2; +x is u = 1/2, +z u = 1/4.
    let (uv, _, _) = s.uv_frame(s.center + Vec3::new(2.0, 0.0, 0.0));
    assert!((uv - Vec2::new(0.5, 0.5)).length() < 1e-6, "{uv}");
    let (uv, _, _) = s.uv_frame(s.center + Vec3::new(0.0, 0.0, 2.0));
    assert!((uv - Vec2::new(0.25, 0.5)).length() < 1e-6, "{uv}");
    let (uv, _, _) = s.uv_frame(s.center + Vec3::new(0.0, 2.0, 0.0) * 0.999_999);
    assert!(uv.y < 1e-3, "{uv}");
    // Derivatives against moving along the sphere by (du, dv).
    let point = |u: f32, v: f32| {
        let (phi, theta) = (std::f32::consts::PI - 2.0 * std::f32::consts::PI * u, std::f32::consts::PI * v);
        s.center + Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()) * s.radius
    };
    for &(u, v) in &[(0.1, 0.3), (0.6, 0.7), (0.85, 0.45)] {
        let p = point(u, v);
        let (uv, dpdu, dpdv) = s.uv_frame(p);
        assert!((uv - Vec2::new(u, v)).length() < 1e-4, "{uv} vs {u} {v}");
        let h = 1e-3;
        let fu = (point(u + h, v) - point(u - h, v)) / (2.0 * h);
        let fv = (point(u, v + h) - point(u, v - h)) / (2.0 * h);
        assert!((fu - dpdu).length() < 1e-2 * dpdu.length(), "{fu} vs {dpdu}");
        assert!((fv - dpdv).length() < 1e-2 * dpdv.length(), "{fv} vs {dpdv}");
    }
}

#[test]
fn triangle_uv_interpolates_and_its_frame_inverts_the_uv_map() {
    let positions = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 1.0)];
    let uvs = vec![Vec2::new(0.1, 0.2), Vec2::new(0.5, 0.2), Vec2::new(0.1, 0.8)];
    let mesh = Mesh::new(positions.clone(), vec![[0, 1, 2]], None).with_uvs(Some(uvs.clone()));
    let hit = TriHit { t: 1.0, prim: 0, u: 0.25, v: 0.5 };
    let f = mesh.uv_frame(&hit);
    let w = 1.0 - hit.u - hit.v;
    let expect_uv = uvs[0] * w + uvs[1] * hit.u + uvs[2] * hit.v;
    assert!((f.uv - expect_uv).length() < 1e-6);
    assert!((f.p - (positions[0] * w + positions[1] * hit.u + positions[2] * hit.v)).length() < 1e-6);
    // Moving by (du, dv) in texture space moves the point by dpdu du + dpdv dv:
    // check on the edges, where both are known exactly.
    let e1 = positions[1] - positions[0];
    let e2 = positions[2] - positions[0];
    let (d1, d2) = (uvs[1] - uvs[0], uvs[2] - uvs[0]);
    assert!((f.dpdu * d1.x + f.dpdv * d1.y - e1).length() < 1e-5);
    assert!((f.dpdu * d2.x + f.dpdv * d2.y - e2).length() < 1e-5);
}

#[test]
fn flat_normal_map_texel_leaves_the_normal_unchanged() {
    let n = Vec3::new(0.0, 0.0, 1.0);
    let f = frame(n, Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, -2.0, 0.0), Vec2::new(0.3, 0.3));
    // (0.5, 0.5, 1) in [0, 1], i.e. (0, 0, 1) in tangent space.
    let out = bump::normal_map(&f, Vec3::new(0.5, 0.5, 1.0) * 2.0 - Vec3::ONE);
    assert!((out - n).length() < 1e-6, "{out}");
    // Through the whole map pipeline too, with a uniform image of (128, 128, 255).
    let img = Image::from_rgb8(1, 1, vec![[128, 128, 255]]).unwrap();
    let mut tex = Textures::new(vec![img], &[], None, None);
    tex.maps.push(TextureMap {
        texture: Texture::Image { image: 0, interpolation: Interpolation::Bilinear, scale: 1.0 / 255.0 },
        decal: DecalMode::ReplaceNormal,
        bump_factor: 1.0,
    });
    let list = tex.add_list(&[0]);
    let mut m = crate::material::Material::default();
    let mut out = n;
    assert!(matches!(tex.apply(list, &f, &mut m, &mut out, &mut Lobes::default()), Ok(Applied::Lit)));
    assert!((out - n).length() < 0.01, "{out}");
}

#[test]
fn zero_bump_factor_leaves_the_normal_unchanged() {
    let n = Vec3::new(0.0, 1.0, 0.0);
    let f = frame(n, Vec3::X, Vec3::Z, Vec2::new(0.4, 0.6));
    let img = Image::from_rgb8(2, 2, vec![[0, 0, 0], [255, 255, 255], [90, 10, 30], [7, 200, 100]]).unwrap();
    let tex = Textures::new(vec![img], &[], None, None);
    for (texture, k) in [
        (Texture::Image { image: 0, interpolation: Interpolation::Bilinear, scale: 1.0 / 255.0 }, 0.0),
        (Texture::Perlin(Perlin { scale: 3.0, conversion: NoiseConversion::AbsVal, octaves: 2 }), 0.0),
    ] {
        let map = TextureMap { texture, decal: DecalMode::BumpNormal, bump_factor: k };
        assert_eq!(bump::bump(&tex, &map, &f), n);
        // A non-zero factor does tilt it (the test can fail).
        let tilted = bump::bump(&tex, &TextureMap { bump_factor: 1.0, ..map }, &f);
        assert!((tilted - n).length() > 1e-4, "{tilted}");
        assert!((tilted.length() - 1.0).abs() < 1e-5);
    }
}

/// An image bump under a non-uniform, mirroring scale: spheres displace
/// their world-space surface, meshes their object-space one (as the course's
/// hw4 `bump_mapping_transformed` shows; see `bump/mod.rs`).
#[test]
fn image_bumps_displace_spheres_in_world_space_and_meshes_in_object_space() {
    let img = Image::from_rgb8(2, 2, vec![[0, 0, 0], [255, 255, 255], [90, 10, 30], [7, 200, 100]]).unwrap();
    let tex = Textures::new(vec![img], &[], None, None);
    let texture = Texture::Image { image: 0, interpolation: Interpolation::Nearest, scale: 1.0 / 255.0 };
    let map = TextureMap { texture, decal: DecalMode::BumpNormal, bump_factor: 0.2 };
    let s = Sphere { center: Vec3::ZERO, radius: 10.0 };
    let p = Vec3::new(6.0, 3.0, 7.0).normalize() * 10.0;
    let (_, dpdu, dpdv) = s.uv_frame(p);
    // The texel (0, 0), with a step up to the right and down.
    let uv = Vec2::new(0.1, 0.1);
    let xf = luster_core::math::Transform::scaling(Vec3::new(-2.0, 1.0, 1.0)).unwrap();
    let sphere = TexFrame { to_world: Some(xf), ..frame(s.normal(p), dpdu, dpdv, uv) };
    let n_world = xf.normal_to_world(s.normal(p)).normalize();
    let world = frame(n_world, xf.vector(dpdu), xf.vector(dpdv), uv);
    let got = bump::bump(&tex, &map, &sphere);
    let want = bump::bump(&tex, &map, &world);
    assert!((got - want).length() < 1e-5, "sphere: {got} vs world-space {want}");
    // The object-space answer is another one here (the test can fail).
    let object = xf.normal_to_world(bump::bump(&tex, &map, &frame(s.normal(p), dpdu, dpdv, uv))).normalize();
    assert!(got.dot(object) < 0.999, "{got} vs object-space {object}");

    // A mesh under a uniform scale keeps its object-space bump: the same
    // tilt as unscaled, where world-space tangents would strengthen it 20×.
    let small = luster_core::math::Transform::scaling(Vec3::splat(0.05)).unwrap();
    let n = dpdu.cross(dpdv).normalize();
    let mesh = TexFrame { rest_in_object: true, to_world: Some(small), ..frame(n, dpdu, dpdv, uv) };
    let unscaled = bump::bump(&tex, &map, &frame(n, dpdu, dpdv, uv));
    let got = bump::bump(&tex, &map, &mesh);
    assert!((got - unscaled).length() < 1e-5, "mesh: {got} vs {unscaled}");
    assert!(unscaled.dot(n) < 0.999, "the bump tilts the normal: {unscaled} vs {n}");
}

#[test]
fn decal_modes_change_the_right_component() {
    let img = Image::from_rgb8(1, 1, vec![[51, 102, 255]]).unwrap();
    let mut tex = Textures::new(vec![img], &[], None, None);
    let c = Vec3::new(0.2, 0.4, 1.0);
    for decal in [DecalMode::ReplaceKd, DecalMode::BlendKd, DecalMode::ReplaceKs, DecalMode::ReplaceAll] {
        tex.maps.push(TextureMap {
            texture: Texture::Image { image: 0, interpolation: Interpolation::Nearest, scale: 1.0 / 255.0 },
            decal,
            bump_factor: 1.0,
        });
    }
    let f = frame(Vec3::Z, Vec3::X, Vec3::Y, Vec2::new(0.5, 0.5));
    let base = crate::material::Material {
        diffuse: Vec3::splat(0.6),
        specular: Vec3::splat(0.1),
        ..Default::default()
    };
    tex.lists = vec![0, 1, 2, 3];
    let apply = |i: u32| {
        let mut m = base;
        let mut n = Vec3::Z;
        let r = tex.apply(TexList { start: i, len: 1 }, &f, &mut m, &mut n, &mut Lobes::default()).unwrap();
        (r, m)
    };
    let (_, m) = apply(0);
    assert!((m.diffuse - c).length() < 1e-6 && m.specular == base.specular);
    let (_, m) = apply(1);
    assert!((m.diffuse - (c + base.diffuse) * 0.5).length() < 1e-6);
    let (_, m) = apply(2);
    assert!((m.specular - c).length() < 1e-6 && m.diffuse == base.diffuse);
    let (r, _) = apply(3);
    assert!(matches!(r, Applied::Unlit(v) if (v - c).length() < 1e-6));
}

#[test]
fn a_bilinear_background_of_the_output_size_shows_texel_for_texel() {
    // A 4×1 image: every sample position inside pixel x must give texel x
    // exactly, wherever the sample is jittered within the pixel (hw4
    // galactica_dynamic's star field equals its texture pixel for pixel).
    let texels = vec![[0, 0, 0], [255, 255, 255], [0, 0, 0], [255, 0, 0]];
    let img = Image::from_rgb8(4, 1, texels.clone()).unwrap();
    let mut tex = Textures::new(vec![img], &[], Some(0), None);
    tex.maps.push(TextureMap {
        texture: Texture::Image { image: 0, interpolation: Interpolation::Bilinear, scale: 1.0 / 255.0 },
        decal: DecalMode::ReplaceBackground,
        bump_factor: 1.0,
    });
    for (x, t) in texels.iter().enumerate() {
        let want = Vec3::new(f32::from(t[0]), f32::from(t[1]), f32::from(t[2]));
        for jitter in [0.0, 0.3, 0.5, 0.99] {
            let uv = Vec2::new((x as f32 + jitter) / 4.0, 0.5);
            let got = tex.background(uv).unwrap();
            assert!((got - want).length() < 1e-3, "pixel {x} at jitter {jitter}: {got} instead of {want}");
        }
    }
}

/// The course's `PerlinTexture` through the texture map is the shading
/// language's `course.texture_value` bit for bit, so a shader can reproduce a
/// course texture exactly.
#[test]
fn perlin_map_is_the_noise_modules_texture_value_bit_for_bit() {
    use luster_shading::noise::course::texture_value;
    // Knuth's MMIX LCG: enough to scatter test points.
    let mut state = 0x5eedu64.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32 * 8.0 - 4.0
    };
    for (conversion, absval) in [(NoiseConversion::AbsVal, true), (NoiseConversion::Linear, false)] {
        for octaves in [0, 1, 4, 7] {
            let map = Perlin { scale: 3.0, conversion, octaves };
            for _ in 0..500 {
                let p = [next(), next(), next()];
                let want = map.value(Vec3::from_array(p));
                let got = texture_value(p, 3.0, octaves, absval);
                assert_eq!(got.to_bits(), want.to_bits(), "{p:?} {octaves} {absval}");
            }
        }
    }
}
