//! glTF materials in whole renders (`docs/gltf-materials.md`): a material
//! read from a small glTF document is put on a sphere or a quad of a course
//! scene, and what it shows is checked against values known without a
//! reference image: unlit and emissive surfaces show their colour exactly,
//! a smooth sphere under a uniform sky shows its Fresnel reflectance at the
//! centre, a white metal passes the white furnace at any roughness.

use crate::common::{render_spp as render, two_seed_mean, white_sky};
use base64::Engine;
use luster::math::Vec3;
use luster::scene::description::TextureSource;
use luster::scene::gltf::material::{read_materials, GltfMaterial, MaterialOverride};
use luster::scene::Description;
use serde_json::{json, Value};
use std::path::Path;

/// `w`×`h` RGBA texels as a PNG file's bytes.
fn png(w: u32, h: u32, texels: &[[u8; 4]]) -> Vec<u8> {
    let raw: Vec<u8> = texels.iter().flatten().copied().collect();
    let img = image::RgbaImage::from_raw(w, h, raw).expect("texels fit");
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).expect("PNG written");
    out.into_inner()
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// The materials of a glTF document (`asset` added), its images relative to `dir`.
fn materials(
    dir: &Path,
    mut root: Value,
    buffers: &[Vec<u8>],
    overrides: &[MaterialOverride],
) -> Vec<GltfMaterial> {
    root["asset"] = json!({"version": "2.0"});
    let doc = gltf::Gltf::from_slice(root.to_string().as_bytes()).expect("valid glTF").document;
    let mut warnings = Vec::new();
    let m =
        read_materials(&doc, buffers, dir, &dir.join("m.gltf"), overrides, &mut warnings).expect("materials");
    assert!(warnings.is_empty(), "{warnings:?}");
    m
}

/// One material with these textures (data URIs), read from `dir`.
fn one(dir: &Path, material: Value, textures: &[(Vec<u8>, Value)]) -> GltfMaterial {
    let root = json!({
        "materials": [material],
        "images": textures.iter().map(|(png, _)| json!({"uri": data_uri(png)})).collect::<Vec<_>>(),
        "samplers": textures.iter().map(|(_, s)| s.clone()).collect::<Vec<_>>(),
        "textures": (0..textures.len()).map(|i| json!({"source": i, "sampler": i})).collect::<Vec<_>>(),
    });
    materials(dir, root, &[], &[]).remove(0)
}

/// Puts glTF material `m` on object 0 of `desc`, as the glTF loader adds a
/// material: its shader's images, its maps (an image map's image too).
fn attach(desc: &mut Description, m: &GltfMaterial) {
    m.add_images_to(&mut desc.images);
    let mut maps = Vec::new();
    for pm in &m.maps {
        let mut map = pm.map.clone();
        if let (TextureSource::Image { image, .. }, Some(img)) = (&mut map.source, &pm.image) {
            desc.images.push(img.clone());
            *image = desc.images.len() - 1;
        }
        desc.texture_maps.push(map);
        maps.push(desc.texture_maps.len() - 1);
    }
    desc.materials.push(m.material.clone());
    desc.objects[0].material = desc.materials.len() - 1;
    desc.objects[0].textures = maps;
}

const PT: &str = "<Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams>";

/// A unit sphere seen from +z filling most of a 24×24 image, with `lights`.
fn sphere(lights: &str, background: &str) -> String {
    format!(
        r#"<Scene><MaxRecursionDepth>32</MaxRecursionDepth><BackgroundColor>{background}</BackgroundColor>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>24 24</ImageResolution>
    <ImageName>a.exr</ImageName>{PT}</Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images></Textures>
  <Lights>{lights}</Lights>
  <Materials><Material id="1"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#
    )
}

const SKY: &str =
    r#"<SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight>"#;

/// A quad from (−1, −1) to (1, 1) at z = 0 filling a 24×24 image seen from
/// +z, with glTF's texture coordinates: u = (x + 1) / 2 along +x, v = (1 −
/// y) / 2 from the top.
fn quad(lights: &str, background: &str) -> String {
    format!(
        r#"<Scene><MaxRecursionDepth>8</MaxRecursionDepth><BackgroundColor>{background}</BackgroundColor>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>20</FovY><NearDistance>1</NearDistance><ImageResolution>24 24</ImageResolution>
    <ImageName>a.exr</ImageName>{PT}</Camera></Cameras>
  <Lights>{lights}</Lights>
  <Materials><Material id="1"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material></Materials>
  <VertexData>-1 -1 0  1 -1 0  1 1 0  -1 1 0</VertexData>
  <TexCoordData>0 1  1 1  1 0  0 0</TexCoordData>
  <Objects><Mesh id="1"><Material>1</Material><Faces>1 2 3 1 3 4</Faces></Mesh></Objects>
</Scene>"#
    )
}

fn scene(dir: &Path, text: &str, m: &GltfMaterial) -> Description {
    white_sky(dir);
    let mut desc = crate::common::load_with(dir, text, &[]);
    attach(&mut desc, m);
    desc
}

/// The sRGB decoding curve (IEC 61966-2-1) of an 8-bit value.
fn srgb(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn near(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

/// An unlit surface shows its base colour × 255: a 50% grey texel (188,
/// sRGB-encoded) gives what a factor of 0.5 gives, not 188/255.
#[test]
fn an_srgb_texel_of_188_is_the_albedo_of_a_factor_of_a_half() {
    let dir = tempfile::tempdir().expect("temp dir");
    let unlit = json!({"KHR_materials_unlit": {}});
    let grey = png(1, 1, &[[188, 188, 188, 255]]);
    let textured = one(
        dir.path(),
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, "extensions": unlit}),
        &[(grey, json!({}))],
    );
    let factor = one(
        dir.path(),
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0]}, "extensions": unlit}),
        &[],
    );
    let a = render(&scene(dir.path(), &quad("", "0 0 0"), &textured), 1, 1);
    let b = render(&scene(dir.path(), &quad("", "0 0 0"), &factor), 1, 1);
    let want = 255.0 * srgb(188);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        assert!(near(*p, Vec3::splat(want), 1e-3 * want), "texel 188 shows {p}, expected {want}");
        assert!(near(*q, Vec3::splat(127.5), 1e-3), "factor 0.5 shows {q}");
        assert!((p.x / q.x - 1.0).abs() < 0.01, "the same albedo within 1%: {p} vs {q}");
    }
}

/// The same image as a data URI, a `.glb` buffer view and a file gives the
/// same pixels, byte for byte.
#[test]
fn embedded_and_file_images_render_the_same() {
    let dir = tempfile::tempdir().expect("temp dir");
    let texels: Vec<[u8; 4]> = (0..16u8).map(|i| [i * 16, 255 - i * 9, (i * 37) % 251, 255]).collect();
    let bytes = png(4, 4, &texels);
    std::fs::write(dir.path().join("tex 1.png"), &bytes).expect("image written");
    let mut buffer = vec![7u8; 12];
    buffer.extend_from_slice(&bytes);
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
                          "extensions": {"KHR_materials_unlit": {}}});
    let with_image = |image: Value| {
        let root = json!({
            "materials": [material],
            "buffers": [{"byteLength": buffer.len()}],
            "bufferViews": [{"buffer": 0, "byteOffset": 12, "byteLength": bytes.len()}],
            "images": [image], "textures": [{"source": 0}],
        });
        let m = materials(dir.path(), root, &[buffer.clone()], &[]).remove(0);
        render(&scene(dir.path(), &quad("", "0 0 0"), &m), 2, 1).pixels.clone()
    };
    let file = with_image(json!({"uri": "tex%201.png"}));
    let data = with_image(json!({"uri": data_uri(&bytes)}));
    let view = with_image(json!({"bufferView": 0, "mimeType": "image/png"}));
    assert!(file.iter().any(|p| p.distance(file[0]) > 10.0), "the texture shows");
    assert_eq!(file, data, "a data URI renders as the file");
    assert_eq!(file, view, "a buffer view renders as the file");
}

/// A 2×1 texture, red | green, nearest: KHR_texture_transform's offset
/// moves it by half, its rotation of 90° turns u into v.
#[test]
fn the_texture_transform_puts_texels_where_it_says() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rg = png(2, 1, &[[255, 0, 0, 255], [0, 255, 0, 255]]);
    let render_with = |transform: Value| {
        let m = one(
            dir.path(),
            json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                     "extensions": {"KHR_texture_transform": transform}}},
                   "extensions": {"KHR_materials_unlit": {}}}),
            &[(rg.clone(), json!({"magFilter": 9728}))],
        );
        render(&scene(dir.path(), &quad("", "0 0 0"), &m), 1, 1)
    };
    let red = Vec3::new(255.0, 0.0, 0.0);
    let green = Vec3::new(0.0, 255.0, 0.0);
    let at = |img: &luster::render::RenderedImage, x: usize, y: usize| img.pixels[y * 24 + x];
    let plain = render_with(json!({}));
    assert!(near(at(&plain, 3, 12), red, 1e-3) && near(at(&plain, 20, 12), green, 1e-3));
    // u' = u + 0.5: the left half reads the right texel, the right half wraps.
    let moved = render_with(json!({"offset": [0.5, 0.0]}));
    assert!(near(at(&moved, 3, 12), green, 1e-3) && near(at(&moved, 20, 12), red, 1e-3));
    // Rotation by 90°: u' = v, so the top (v < 0.5) is red, the bottom green.
    let turned = render_with(json!({"rotation": std::f32::consts::FRAC_PI_2}));
    assert!(near(at(&turned, 12, 3), red, 1e-3) && near(at(&turned, 12, 20), green, 1e-3));
}

/// Emission: glTF's emissive 1 is display white (the film's 255), times
/// KHR_materials_emissive_strength.
#[test]
fn emission_is_factor_times_strength_in_display_white() {
    let dir = tempfile::tempdir().expect("temp dir");
    let m = one(
        dir.path(),
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
               "emissiveFactor": [1.0, 0.5, 0.25],
               "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}}),
        &[],
    );
    let img = render(&scene(dir.path(), &sphere("", "0 0 0"), &m), 4, 1);
    let centre = img.pixels[12 * 24 + 12];
    assert!(near(centre, Vec3::new(510.0, 255.0, 127.5), 0.01), "{centre}");
}

/// Under a uniform white sky a smooth sphere's centre shows F0: a metal's
/// base colour (a coloured reflection), a dielectric's 0.04 (white),
/// whatever its base colour under it (black here).
#[test]
fn metals_reflect_their_colour_and_dielectrics_white() {
    let dir = tempfile::tempdir().expect("temp dir");
    let smooth = |base: [f32; 3], metal: f32| {
        let m = one(
            dir.path(),
            json!({"pbrMetallicRoughness": {"baseColorFactor": [base[0], base[1], base[2], 1.0],
                   "metallicFactor": metal, "roughnessFactor": 0.0}}),
            &[],
        );
        let img = render(&scene(dir.path(), &sphere(SKY, "0 0 0"), &m), 4, 1);
        img.pixels[12 * 24 + 12]
    };
    let metal = smooth([1.0, 0.2, 0.2], 1.0);
    assert!(near(metal, Vec3::new(1.0, 0.2, 0.2), 0.01), "metal: {metal}");
    let dielectric = smooth([0.0, 0.0, 0.0], 0.0);
    assert!(near(dielectric, Vec3::splat(0.04), 0.002), "dielectric: {dielectric}");
}

/// The white furnace: a white metal keeps all the light at any roughness.
#[test]
fn a_white_metal_passes_the_furnace_at_any_roughness() {
    let dir = tempfile::tempdir().expect("temp dir");
    for roughness in [0.2, 0.6, 1.0] {
        let m = one(dir.path(), json!({"pbrMetallicRoughness": {"roughnessFactor": roughness}}), &[]);
        let desc = scene(dir.path(), &sphere(SKY, "0 0 0"), &m);
        let (a, b) = (render(&desc, 64, 1), render(&desc, 64, 2));
        // Pixels well inside the sphere (0.8 of its radius).
        let half = 15f32.to_radians().tan() * 5.0;
        let inner: Vec<usize> = (0..a.pixels.len())
            .filter(|&i| {
                let x = ((i % 24) as f32 + 0.5) / 12.0 - 1.0;
                let y = ((i / 24) as f32 + 0.5) / 12.0 - 1.0;
                (x * x + y * y).sqrt() * half < 0.8
            })
            .collect();
        let lum = |p: Vec3| f64::from(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z);
        let (la, lb): (Vec<f64>, Vec<f64>) =
            inner.iter().map(|&i| (lum(a.pixels[i]), lum(b.pixels[i]))).unzip();
        let (mean, se) = two_seed_mean(&la, &lb);
        assert!(
            mean > 0.99 - 4.0 * se && mean < 1.01 + 4.0 * se,
            "roughness {roughness}: {mean:.4} ± {se:.4}"
        );
    }
}

/// MASK: a texture whose left texel has alpha 0 shows the background there
/// and the surface on the right. BLEND: alpha 0.25 lets 75% through.
#[test]
fn alpha_mask_cuts_out_and_blend_lets_light_through() {
    let dir = tempfile::tempdir().expect("temp dir");
    let halves = png(2, 1, &[[255, 255, 255, 0], [255, 255, 255, 255]]);
    let m = one(
        dir.path(),
        json!({"alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
               "extensions": {"KHR_materials_unlit": {}}}),
        &[(halves, json!({"magFilter": 9728}))],
    );
    let bg = Vec3::new(0.0, 0.0, 200.0);
    let img = render(&scene(dir.path(), &quad("", "0 0 200"), &m), 1, 1);
    assert!(near(img.pixels[12 * 24 + 3], bg, 1e-3), "cut out: {}", img.pixels[12 * 24 + 3]);
    assert!(near(img.pixels[12 * 24 + 20], Vec3::splat(255.0), 1e-3), "kept: {}", img.pixels[12 * 24 + 20]);

    let m = one(
        dir.path(),
        json!({"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.25]},
               "extensions": {"KHR_materials_unlit": {}}}),
        &[],
    );
    let desc = scene(dir.path(), &quad("", "0 0 200"), &m);
    let (a, b) = (render(&desc, 16, 1), render(&desc, 16, 2));
    let want = Vec3::splat(255.0) * 0.25 + bg * 0.75;
    for c in 0..3 {
        let (xa, xb): (Vec<f64>, Vec<f64>) =
            a.pixels.iter().zip(&b.pixels).map(|(p, q)| (f64::from(p[c]), f64::from(q[c]))).unzip();
        let (mean, se) = two_seed_mean(&xa, &xb);
        let w = f64::from(want[c]);
        assert!((mean - w).abs() < 4.0 * se + 1e-3 * w, "channel {c}: {mean:.3} ± {se:.3}, expected {w}");
    }
}

/// The normal texture follows glTF's convention (+Y up in the image): a
/// normal tilted up, t = (0, 0.6, 0.8), faces a light from above
/// (n·l = 0.99) and turns from one below (n·l = 0.14); a flat one sees both
/// alike.
#[test]
fn the_normal_texture_tilts_towards_image_up() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lit = |texel: [u8; 4], from_above: bool| {
        let m = one(
            dir.path(),
            json!({"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0},
                   "normalTexture": {"index": 0}}),
            &[(png(1, 1, &[texel]), json!({}))],
        );
        let y = if from_above { -1 } else { 1 };
        let light = format!(
            r#"<DirectionalLight id="1"><Direction>0 {y} -1</Direction><Radiance>100 100 100</Radiance></DirectionalLight>"#
        );
        let img = render(&scene(dir.path(), &quad(&light, "0 0 0"), &m), 4, 1);
        img.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / img.pixels.len() as f64
    };
    let up = [128, 204, 230, 255];
    let (above, below) = (lit(up, true), lit(up, false));
    assert!(above > 4.0 * below, "tilted up: lit from above {above:.3}, from below {below:.3}");
    let flat = [128, 128, 255, 255];
    let (above, below) = (lit(flat, true), lit(flat, false));
    assert!((above / below - 1.0).abs() < 0.05, "flat: {above:.3} vs {below:.3}");
}

/// `--material NAME=FILE.lua`: the named material renders as the script says.
#[test]
fn an_override_replaces_the_material_by_name() {
    let dir = tempfile::tempdir().expect("temp dir");
    let script = dir.path().join("glow.lua");
    std::fs::write(
        &script,
        "function material(s)\n  local c = emission{radiance = vec3(100, 50, 25)}\n  return c\nend\n",
    )
    .expect("script written");
    let over = MaterialOverride { name: "Body".into(), script };
    let m = materials(dir.path(), json!({"materials": [{"name": "Body"}]}), &[], &[over]).remove(0);
    let img = render(&scene(dir.path(), &sphere("", "0 0 0"), &m), 1, 1);
    assert!(
        near(img.pixels[12 * 24 + 12], Vec3::new(100.0, 50.0, 25.0), 1e-3),
        "{}",
        img.pixels[12 * 24 + 12]
    );
}
