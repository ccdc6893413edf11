//! The glTF material mapping, checked on small documents built here: the
//! parameters it makes, and the closure the built-in shader returns from
//! them (its texture lookups answered by a stand-in for the scene's images).

use super::*;
use crate::description::{ImageEncoding, TextureSource};
use base64::Engine;
use luster_shading::shader::closure::{Closure, Node, NodeKind};
use luster_shading::shader::{ImageSampler, SampleFilter, ShadeInput, ShaderImages, ShaderSet, ShaderSource};
use serde_json::{json, Value};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// A PNG of `w`×`h` texels, as bytes.
fn png(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbaImage::from_pixel(w, h, image::Rgba([188, 188, 188, 128]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A glTF document of these materials, textures, samplers and images.
fn doc_of(mut root: Value) -> gltf::Document {
    root["asset"] = json!({"version": "2.0"});
    gltf::Gltf::from_slice(root.to_string().as_bytes()).unwrap().document
}

fn read(doc: &gltf::Document, buffers: &[Vec<u8>]) -> (Result<Vec<GltfMaterial>, SceneError>, Vec<Warning>) {
    read_with(doc, buffers, Path::new("."), &[])
}

fn read_with(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    dir: &Path,
    overrides: &[MaterialOverride],
) -> (Result<Vec<GltfMaterial>, SceneError>, Vec<Warning>) {
    let mut w = Vec::new();
    let r = read_materials(doc, buffers, dir, Path::new("m.gltf"), overrides, &mut w);
    (r, w)
}

/// One material with an image (a data URI) behind every texture index.
fn one(material: Value, images: usize) -> gltf::Document {
    let uri = data_uri(&png(4, 2));
    doc_of(json!({
        "materials": [material],
        "images": vec![json!({"uri": uri}); images],
        "textures": (0..images).map(|i| json!({"source": i})).collect::<Vec<_>>(),
    }))
}

fn param<'a>(m: &'a GltfMaterial, name: &str) -> Option<&'a ParamValue> {
    let TextureSource::Shader { params, .. } = &m.maps.last().unwrap().map.source else {
        panic!("no shader map")
    };
    params.iter().find(|(n, _)| n == name).map(|(_, v)| v)
}

fn number(m: &GltfMaterial, name: &str) -> f64 {
    match param(m, name) {
        Some(ParamValue::Number(x)) => *x,
        other => panic!("{name}: {other:?}"),
    }
}

/// The stand-in for the scene's images: each answers its colour, and every
/// lookup is recorded.
struct Images {
    colours: Vec<[f32; 3]>,
    seen: Mutex<Vec<(usize, f32, f32, SampleFilter)>>,
}

impl ImageSampler for Images {
    fn sample(&self, index: usize, u: f32, v: f32, filter: SampleFilter) -> Option<[f32; 3]> {
        self.seen.lock().unwrap().push((index, u, v, filter));
        self.colours.get(index).copied()
    }
}

/// The closure material `m`'s shader returns at `uv`, where its image read
/// as an encoding has the colour `colour` gives; and the lookups it made.
fn shade(
    m: &GltfMaterial,
    colour: impl Fn(&ImageDesc) -> [f32; 3],
    uv: [f32; 2],
) -> (Closure, Vec<(usize, f32, f32, SampleFilter)>) {
    let TextureSource::Shader { path, code, params } = &m.maps.last().unwrap().map.source else { panic!() };
    let mut src = ShaderSource::new("gltf_pbr", path.clone(), code.clone());
    src.params = params.clone();
    let images =
        Arc::new(Images { colours: m.images.iter().map(&colour).collect(), seen: Mutex::new(Vec::new()) });
    let names = m.images.iter().enumerate().map(|(i, d)| (d.id.clone(), i)).collect();
    let set = ShaderSet::with_images(
        vec![src],
        Duration::from_secs(10),
        Some(ShaderImages { names, sampler: images.clone() }),
    )
    .unwrap();
    let input =
        ShadeInput { uv, n: [0.0, 0.0, 1.0], ng: [0.0, 0.0, 1.0], i: [0.0, 0.0, -1.0], ..Default::default() };
    let out = set.material(0, &input).unwrap();
    let seen = images.seen.lock().unwrap().clone();
    (out.closure.expect("a closure"), seen)
}

fn nodes(c: &Closure) -> &[Node] {
    &c.nodes[..usize::from(c.len)]
}

fn of_kind(c: &Closure, k: NodeKind) -> Vec<Node> {
    nodes(c).iter().copied().filter(|n| n.kind == k).collect()
}

fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5)
}

#[test]
fn factors_become_the_openpbr_closure() {
    let doc = one(
        json!({"name": "paint", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0],
               "metallicFactor": 0.3, "roughnessFactor": 0.6},
               "emissiveFactor": [1.0, 0.5, 0.0],
               "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}),
        0,
    );
    let (m, w) = read(&doc, &[]);
    let m = &m.unwrap()[0];
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(m.name, "paint");
    let (c, seen) = shade(m, |_| [0.0; 3], [0.5, 0.5]);
    assert!(seen.is_empty(), "no textures, no lookups");
    let d = of_kind(&c, NodeKind::Diffuse);
    assert!(close(d[0].c[0], [0.5, 0.25, 1.0]), "diffuse albedo is the base colour: {:?}", d[0].c[0]);
    let metal = of_kind(&c, NodeKind::Conductor);
    assert!(close(metal[0].c[0], [0.5, 0.25, 1.0]) && (metal[0].x[0] - 0.6).abs() < 1e-6);
    let gloss = of_kind(&c, NodeKind::Dielectric);
    assert_eq!(gloss.len(), 1);
    assert!(
        (gloss[0].x[0] - 1.5).abs() < 1e-6 && (gloss[0].x[1] - 0.6).abs() < 1e-6,
        "ior 1.5, roughness as given"
    );
    let weights: Vec<f32> = of_kind(&c, NodeKind::Scale).iter().map(|n| n.c[0][0]).collect();
    assert!(weights.iter().any(|w| (w - 0.3).abs() < 1e-6) && weights.iter().any(|w| (w - 0.7).abs() < 1e-6));
    let e = of_kind(&c, NodeKind::Emission);
    assert!(close(e[0].c[0], [1020.0, 510.0, 0.0]), "emission is 255 × strength × factor: {:?}", e[0].c[0]);
}

#[test]
fn textures_multiply_their_factors_channel_by_channel() {
    let doc = one(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1.0, 1.0, 1.0], "metallicFactor": 0.8,
               "roughnessFactor": 0.5, "baseColorTexture": {"index": 0},
               "metallicRoughnessTexture": {"index": 1}}}),
        2,
    );
    let (m, _) = read(&doc, &[]);
    let m = &m.unwrap()[0];
    assert_eq!(m.name, "materials[0]");
    let enc: Vec<ImageEncoding> = m.images.iter().map(|i| i.encoding).collect();
    assert_eq!(enc, [ImageEncoding::Srgb, ImageEncoding::Linear], "base colour sRGB, metal-roughness linear");
    assert_eq!(number(m, "metallic_tex"), number(m, "roughness_tex"), "one texture, sampled once");
    let colour =
        |d: &ImageDesc| if d.encoding == ImageEncoding::Srgb { [0.5, 0.25, 1.0] } else { [0.0, 0.5, 0.25] };
    let (c, seen) = shade(m, colour, [0.5, 0.5]);
    assert_eq!(seen.len(), 2);
    let d = of_kind(&c, NodeKind::Diffuse);
    assert!(close(d[0].c[0], [0.25, 0.25, 1.0]), "{:?}", d[0].c[0]);
    // Roughness from green (0.5 × 0.5), metalness from blue (0.8 × 0.25).
    assert!((of_kind(&c, NodeKind::Dielectric)[0].x[1] - 0.25).abs() < 1e-6);
    let weights: Vec<f32> = of_kind(&c, NodeKind::Scale).iter().map(|n| n.c[0][0]).collect();
    assert!(weights.iter().any(|w| (w - 0.2).abs() < 1e-6), "{weights:?}");
}

#[test]
fn the_texture_transform_and_sampler_reach_the_lookup() {
    let (rot, s, o) = (0.3f32, [2.0f32, 0.5f32], [0.1f32, -0.2f32]);
    let doc = doc_of(json!({
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions":
            {"KHR_texture_transform": {"offset": o, "rotation": rot, "scale": s}}}}}],
        "images": [{"uri": data_uri(&png(4, 2))}],
        "samplers": [{"wrapS": 33071, "wrapT": 33648}],
        "textures": [{"source": 0, "sampler": 0}],
    }));
    let (m, _) = read(&doc, &[]);
    let m = &m.unwrap()[0];
    let (u, v) = (0.45f32, 0.7f32);
    let (_, seen) = shade(m, |_| [1.0; 3], [u, v]);
    // KHR_texture_transform's uv' = T R S uv.
    let x = rot.cos() * s[0] * u + rot.sin() * s[1] * v + o[0];
    let y = -rot.sin() * s[0] * u + rot.cos() * s[1] * v + o[1];
    // Clamp to the edge texels' centres across (4 texels), mirror down.
    let x = x.clamp(0.125, 0.875);
    let y = {
        let t = y.rem_euclid(2.0);
        if t > 1.0 {
            2.0 - t
        } else {
            t
        }
    };
    // texture() centres texel i at i / width: half a texel back.
    let (x, y) = (x - 0.125, y - 0.25);
    let (_, lu, lv, f) = seen[0];
    assert!((lu - x).abs() < 1e-5 && (lv - y).abs() < 1e-5, "looked up ({lu}, {lv}), expected ({x}, {y})");
    assert_eq!(f, SampleFilter::Bilinear);
}

#[test]
fn a_nearest_sampler_looks_up_unshifted() {
    let doc = doc_of(json!({
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "images": [{"uri": data_uri(&png(4, 2))}],
        "samplers": [{"magFilter": 9728}],
        "textures": [{"source": 0, "sampler": 0}],
    }));
    let (m, _) = read(&doc, &[]);
    let (_, seen) = shade(&m.unwrap()[0], |_| [1.0; 3], [0.3, 1.6]);
    let (_, u, v, f) = seen[0];
    assert_eq!(f, SampleFilter::Nearest);
    assert!((u - 0.3).abs() < 1e-6 && (v - 1.6).abs() < 1e-6, "repeat is texture()'s own: ({u}, {v})");
}

#[test]
fn alpha_mask_cuts_out_and_blend_mixes() {
    let with = |mode: &str, alpha: f32| {
        let doc = one(
            json!({"alphaMode": mode, "alphaCutoff": 0.5,
                   "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, alpha], "baseColorTexture": {"index": 0}}}),
            1,
        );
        let (m, _) = read(&doc, &[]);
        let m = m.unwrap().remove(0);
        // The texture's alpha channel is read as its own image.
        let colour = |d: &ImageDesc| if d.encoding == ImageEncoding::Alpha { [0.5; 3] } else { [1.0; 3] };
        shade(&m, colour, [0.5, 0.5]).0
    };
    // MASK: alpha 0.9 × 0.5 is under the cutoff: fully transparent.
    let c = with("MASK", 0.9);
    assert_eq!(nodes(&c)[usize::from(c.root)].kind, NodeKind::Transparent);
    let c = with("MASK", 1.0);
    assert!(of_kind(&c, NodeKind::Transparent).is_empty(), "0.5 reaches the cutoff: opaque");
    // BLEND: opacity 0.6 × 0.5.
    let c = with("BLEND", 0.6);
    assert_eq!(of_kind(&c, NodeKind::Transparent).len(), 1);
    let weights: Vec<f32> = of_kind(&c, NodeKind::Scale).iter().map(|n| n.c[0][0]).collect();
    assert!(weights.iter().any(|w| (w - 0.3).abs() < 1e-6) && weights.iter().any(|w| (w - 0.7).abs() < 1e-6));
    // OPAQUE ignores alpha and reads no alpha image.
    let c = with("OPAQUE", 0.1);
    assert!(of_kind(&c, NodeKind::Transparent).is_empty());
}

#[test]
fn material_extensions_map_onto_openpbr() {
    let doc = one(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0},
               "extensions": {
                 "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.2},
                 "KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.4, 0.3], "sheenRoughnessFactor": 0.7},
                 "KHR_materials_transmission": {"transmissionFactor": 0.8},
                 "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationColor": [0.25, 1.0, 1.0],
                                          "attenuationDistance": 0.5},
                 "KHR_materials_ior": {"ior": 1.4}}}),
        0,
    );
    let (m, w) = read(&doc, &[]);
    assert!(w.is_empty(), "{w:?}");
    let (c, _) = shade(&m.unwrap()[0], |_| [1.0; 3], [0.0, 0.0]);
    let d = of_kind(&c, NodeKind::Dielectric);
    // The base's gloss, its transmission (tinted by the base colour and
    // Beer's law: 0.25^(1 / (2 × 0.5)) in red) and the coat.
    assert_eq!(d.len(), 3, "{d:?}");
    let coat = d.iter().find(|n| (n.x[0] - 1.5).abs() < 1e-6).expect("a coat of ior 1.5");
    assert!((coat.x[1] - 0.2).abs() < 1e-6);
    let clear = d.iter().find(|n| n.c[0] != [1.0; 3]).expect("a tinted transmission");
    assert!(
        close(clear.c[0], [0.125, 0.5, 0.5]) && (clear.x[0] - 1.4).abs() < 1e-5 && !clear.thin,
        "{clear:?}"
    );
    let sheen = of_kind(&c, NodeKind::Sheen);
    assert!(close(sheen[0].c[0], [0.5, 0.4, 0.3]) && (sheen[0].x[0] - 0.7).abs() < 1e-6);
    let weights: Vec<f32> = of_kind(&c, NodeKind::Scale).iter().map(|n| n.c[0][0]).collect();
    assert!(weights.iter().any(|w| (w - 0.8).abs() < 1e-6) && weights.iter().any(|w| (w - 0.5).abs() < 1e-6));
}

#[test]
fn transmission_without_volume_is_thin_walled() {
    let doc = one(json!({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}), 0);
    let (m, _) = read(&doc, &[]);
    let (c, _) = shade(&m.unwrap()[0], |_| [1.0; 3], [0.0, 0.0]);
    assert!(of_kind(&c, NodeKind::Dielectric).iter().all(|n| n.thin));
}

#[test]
fn a_specular_colour_over_one_raises_the_ior() {
    let doc = one(
        json!({"extensions": {"KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [2.0, 1.0, 0.5]}}}),
        0,
    );
    let (m, _) = read(&doc, &[]);
    let m = &m.unwrap()[0];
    assert_eq!(number(m, "specular"), 0.5);
    assert_eq!(param(m, "specular_color"), Some(&ParamValue::Vec3([1.0, 0.5, 0.25])));
    // F0 0.04 × 2 = 0.08: ior (1 + √0.08) / (1 − √0.08).
    let want = (1.0 + 0.08f64.sqrt()) / (1.0 - 0.08f64.sqrt());
    assert!((number(m, "ior") - want).abs() < 1e-4, "{}", number(m, "ior"));
}

#[test]
fn unlit_is_the_base_colour_emitted() {
    let doc = one(
        json!({"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1.0]},
               "extensions": {"KHR_materials_unlit": {}}}),
        0,
    );
    let (m, _) = read(&doc, &[]);
    let (c, _) = shade(&m.unwrap()[0], |_| [1.0; 3], [0.0, 0.0]);
    let e = of_kind(&c, NodeKind::Emission);
    assert!(close(e[0].c[0], [51.0, 102.0, 153.0]), "{:?}", e[0].c[0]);
    // Nothing reflects: the diffuse is black and the gloss has no F0.
    assert!(of_kind(&c, NodeKind::Diffuse).iter().all(|n| n.c[0] == [0.0; 3]));
}

#[test]
fn the_default_material_is_blenders_grey() {
    let m = default_material(Path::new("m.gltf"));
    let (c, _) = shade(&m, |_| [1.0; 3], [0.0, 0.0]);
    assert!(close(of_kind(&c, NodeKind::Diffuse)[0].c[0], [0.8; 3]));
    assert!(of_kind(&c, NodeKind::Conductor).is_empty());
    assert!((of_kind(&c, NodeKind::Dielectric)[0].x[1] - 0.5).abs() < 1e-6);
}

#[test]
fn the_normal_texture_is_a_replace_normal_map_first() {
    let doc = one(json!({"normalTexture": {"index": 0, "scale": 0.5}}), 1);
    let (m, _) = read(&doc, &[]);
    let m = &m.unwrap()[0];
    assert_eq!(m.maps.len(), 2);
    assert_eq!(m.maps[0].map.decal, DecalMode::ReplaceNormal);
    let img = m.maps[0].image.as_ref().unwrap();
    assert_eq!(img.encoding, ImageEncoding::GlNormal { scale: 0.5 });
    assert!(img.bytes.is_some(), "a data URI's image is held in memory");
    assert_eq!(m.maps[1].map.decal, DecalMode::Material);
}

#[test]
fn a_second_uv_set_is_a_warning() {
    let doc = one(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}}}), 1);
    let (m, w) = read(&doc, &[]);
    assert!(m.is_ok());
    assert_eq!(w.len(), 1);
    assert!(w[0].loc.path.contains("materials[0].pbrMetallicRoughness.baseColorTexture"), "{}", w[0]);
    assert!(w[0].message.contains("texCoord 1"), "{}", w[0]);
}

#[test]
fn images_come_from_buffer_views_and_files() {
    let bytes = png(3, 5);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("my tex.png"), &bytes).unwrap();
    let mut root = json!({
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                        "metallicRoughnessTexture": {"index": 1}}}],
        "buffers": [{"byteLength": bytes.len() + 4}],
        "bufferViews": [{"buffer": 0, "byteOffset": 4, "byteLength": bytes.len()}],
        "images": [{"bufferView": 0, "mimeType": "image/png"}, {"uri": "my%20tex.png"}],
        "textures": [{"source": 0}, {"source": 1}],
    });
    root["asset"] = json!({"version": "2.0"});
    let doc = gltf::Gltf::from_slice(root.to_string().as_bytes()).unwrap().document;
    let mut buffer = vec![0u8; 4];
    buffer.extend_from_slice(&bytes);
    let (m, _) = read_with(&doc, &[buffer], dir.path(), &[]);
    let m = &m.unwrap()[0];
    assert_eq!(m.images[0].bytes.as_deref(), Some(&bytes[..]), "the buffer view's bytes");
    assert_eq!(m.images[1].path, dir.path().join("my tex.png"), "percent-decoded, against the glTF's folder");
    assert!(m.images[1].bytes.is_none());
    // Half a texel of each image, from its header.
    assert_eq!(param(m, "texel1"), Some(&ParamValue::Vec3([0.5 / 3.0, 0.1, 0.0])));
}

#[test]
fn bad_images_name_their_json_path() {
    let err = |image: Value, buffers: &[Vec<u8>]| {
        let mut root = json!({
            "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
            "buffers": [{"byteLength": 64}],
            "bufferViews": [{"buffer": 0, "byteLength": 64}],
            "images": [image],
            "textures": [{"source": 0}],
        });
        root["asset"] = json!({"version": "2.0"});
        let doc = gltf::Gltf::from_slice(root.to_string().as_bytes()).unwrap().document;
        let dir = tempfile::tempdir().unwrap();
        read_with(&doc, buffers, dir.path(), &[]).0.unwrap_err().to_string()
    };
    let e = err(json!({"uri": "missing.png"}), &[]);
    assert!(e.starts_with("m.gltf: images[0].uri: cannot read image missing.png"), "{e}");
    let e = err(json!({"uri": "data:image/png,abc"}), &[]);
    assert!(e.starts_with("m.gltf: images[0].uri: ") && e.contains("not base64"), "{e}");
    let e = err(json!({"uri": data_uri(b"secret text, not an image")}), &[]);
    assert!(e.starts_with("m.gltf: images[0]: ") && e.contains("not a PNG or JPEG"), "{e}");
    assert!(!e.contains("secret"), "{e}");
    let e = err(json!({"uri": "https://example.com/a.png"}), &[]);
    assert!(e.starts_with("m.gltf: images[0].uri: ") && e.contains("not a relative file name"), "{e}");
    let e = err(json!({"bufferView": 0, "mimeType": "image/png"}), &[vec![0; 10]]);
    assert!(e.starts_with("m.gltf: images[0].bufferView: ") && e.contains("past the end"), "{e}");
    let mut broken = png(2, 2);
    broken.truncate(20);
    let e = err(json!({"uri": data_uri(&broken)}), &[]);
    assert!(e.starts_with("m.gltf: images[0]: ") && e.contains("does not decode"), "{e}");
}

#[test]
fn overrides_replace_materials_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("paint.lua");
    std::fs::write(&script, "function material(s) return diffuse{} end").unwrap();
    let doc = doc_of(json!({"materials": [{"name": "Body"}, {"name": "Glass"}]}));
    let body = MaterialOverride { name: "Body".into(), script: script.clone() };
    let stray = MaterialOverride { name: "Bdoy\u{1b}[31m".into(), script: script.clone() };
    let (m, w) = read_with(&doc, &[], dir.path(), &[body, stray]);
    let m = m.unwrap();
    let TextureSource::Shader { path, code, params } = &m[0].maps[0].map.source else { panic!() };
    assert_eq!(
        (path, code.as_str(), params.len()),
        (&script, "function material(s) return diffuse{} end", 0)
    );
    assert_eq!(m[0].maps.len(), 1);
    assert_eq!(m[0].maps[0].map.decal, DecalMode::Material);
    let TextureSource::Shader { path, .. } = &m[1].maps[0].map.source else { panic!() };
    assert_eq!(path, Path::new(PBR_SHADER), "Glass keeps the glTF mapping");
    assert_eq!(w.len(), 1);
    assert!(w[0].message.contains("matches none of the file's 2 materials ('Body', 'Glass')"), "{}", w[0]);
    assert!(!w[0].message.contains('\u{1b}'), "names are sanitized: {}", w[0]);
    let missing = MaterialOverride { name: "Glass".into(), script: dir.path().join("nope.lua") };
    let e = read_with(&doc, &[], dir.path(), &[missing]).0.unwrap_err().to_string();
    assert!(
        e.starts_with("m.gltf: materials[1]: the override of material 'Glass': cannot read shader script"),
        "{e}"
    );
}

#[test]
fn unsupported_extensions_warn_and_required_ones_fail() {
    let doc =
        doc_of(json!({"extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_anisotropy", "EXT_foo"]}));
    let (_, w) = read(&doc, &[]);
    let said: Vec<String> = w.iter().map(ToString::to_string).collect();
    assert_eq!(
        said,
        [
            "extensionsUsed[1]: extension KHR_materials_anisotropy is not supported; what it adds is ignored",
            "extensionsUsed[2]: extension EXT_foo is not supported; what it adds is ignored"
        ]
    );
    // The gltf crate refuses most required extensions itself; unvalidated,
    // the check here still does.
    let root = json!({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_draco_mesh_compression"],
                      "extensionsRequired": ["KHR_draco_mesh_compression"]});
    let doc = gltf::Gltf::from_slice_without_validation(root.to_string().as_bytes()).unwrap().document;
    let e = read(&doc, &[]).0.unwrap_err().to_string();
    assert_eq!(
        e,
        "m.gltf: extensionsRequired[0]: the file requires extension KHR_draco_mesh_compression, which luster does not support"
    );
}

#[test]
fn out_of_range_factors_are_clamped_with_a_warning() {
    let doc = one(json!({"pbrMetallicRoughness": {"metallicFactor": 1.5, "roughnessFactor": -1.0}}), 0);
    let (m, w) = read(&doc, &[]);
    let m = &m.unwrap()[0];
    assert_eq!((number(m, "metallic"), number(m, "roughness")), (1.0, 0.0));
    assert_eq!(w.len(), 2);
    assert!(
        w[0].to_string().starts_with("materials[0].pbrMetallicRoughness.metallicFactor: 1.5 is outside"),
        "{}",
        w[0]
    );
}
