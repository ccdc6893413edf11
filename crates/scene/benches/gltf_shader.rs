//! What the built-in glTF material shader (`gltf_pbr.lua`) costs per
//! shading call: wall-clock nanoseconds of `ShaderSet::material` for an
//! untextured material, a textured one (base colour, metallic-roughness,
//! emissive, alpha blend) and one with clearcoat, sheen and transmission
//! too, beside a script returning a bare `openpbr{}` and an empty closure.
//! Texture lookups answer a constant, so the figures are the shader's own
//! cost (an image lookup adds what `texture()` costs anywhere).
//!
//! Run: `taskset -c 1 cargo bench -p luster-scene --bench gltf_shader`.

use base64::Engine;
use luster_scene::description::TextureSource;
use luster_scene::gltf::material::{read_materials, GltfMaterial};
use luster_shading::shader::{
    ImageSampler, SampleFilter, ShadeInput, ShaderImages, ShaderSet, ShaderSource, DEFAULT_TIMEOUT,
};
use serde_json::json;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

struct Constant;

impl ImageSampler for Constant {
    fn sample(&self, _: usize, _: f32, _: f32, _: SampleFilter) -> Option<[f32; 3]> {
        Some([0.5, 0.5, 0.5])
    }
}

fn material(m: serde_json::Value, textures: usize) -> GltfMaterial {
    let img = image::RgbaImage::from_pixel(4, 4, image::Rgba([200, 100, 50, 128]));
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png).expect("PNG");
    let uri = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png.into_inner())
    );
    let root = json!({"asset": {"version": "2.0"}, "materials": [m],
        "images": vec![json!({"uri": uri}); textures],
        "textures": (0..textures).map(|i| json!({"source": i})).collect::<Vec<_>>()});
    let doc = gltf::Gltf::from_slice(root.to_string().as_bytes()).expect("glTF").document;
    let mut w = Vec::new();
    read_materials(&doc, &[], Path::new("."), Path::new("b.gltf"), &[], &mut w).expect("materials").remove(0)
}

fn set_of(
    name: &str,
    code: &str,
    params: Vec<(String, luster_shading::shader::ParamValue)>,
    m: Option<&GltfMaterial>,
) -> ShaderSet {
    let mut src = ShaderSource::new(name, format!("{name}.lua"), code);
    src.params = params;
    let names =
        m.map(|m| m.images.iter().enumerate().map(|(i, d)| (d.id.clone(), i)).collect()).unwrap_or_default();
    let images = ShaderImages { names, sampler: Arc::new(Constant) };
    ShaderSet::with_images(vec![src], DEFAULT_TIMEOUT, Some(images)).expect("shader compiles")
}

fn gltf_set(m: &GltfMaterial) -> ShaderSet {
    let TextureSource::Shader { code, params, .. } = &m.maps.last().expect("a map").map.source else {
        panic!("no shader map")
    };
    set_of("gltf_pbr", code, params.clone(), Some(m))
}

/// Median over 7 rounds of the ns per call of `n` calls.
fn time(set: &ShaderSet, n: usize) -> f64 {
    let pts: Vec<ShadeInput> = (0..256)
        .map(|i| {
            let f = i as f32;
            ShadeInput { uv: [f * 0.013 % 1.0, f * 0.029 % 1.0], n: [0.0, 0.0, 1.0], ..ShadeInput::default() }
        })
        .collect();
    let mut rounds: Vec<f64> = (0..7)
        .map(|_| {
            let t = Instant::now();
            for k in 0..n {
                std::hint::black_box(set.material(0, &pts[k & 255]).expect("call"));
            }
            t.elapsed().as_nanos() as f64 / n as f64
        })
        .collect();
    rounds.sort_by(f64::total_cmp);
    rounds[3]
}

fn main() {
    let plain = material(json!({"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.5}}), 0);
    let textured = material(
        json!({"alphaMode": "BLEND", "emissiveFactor": [1.0, 1.0, 1.0],
               "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 1}},
               "emissiveTexture": {"index": 2}}),
        3,
    );
    let layered = material(
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 1},
                                        "metallicFactor": 0.0},
               "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.1},
                              "KHR_materials_sheen": {"sheenColorFactor": [0.5, 0.5, 0.5]},
                              "KHR_materials_transmission": {"transmissionFactor": 0.5}}}),
        2,
    );
    let n = 200_000;
    let cases = [
        (
            "material(s) returning diffuse{}",
            set_of("empty", "function material(s) return diffuse{} end", vec![], None),
        ),
        ("bare openpbr{}", set_of("openpbr", "function material(s) return openpbr{} end", vec![], None)),
        (
            "3 texture() calls and diffuse{}",
            set_of(
                "lookups",
                "function material(s)\n  local u, v = s.uv.u, s.uv.v\n  local a = texture(NAME, u, v)\n  \
                 local b = texture(NAME, u, v)\n  local c = texture(NAME, u, v)\n  return diffuse{albedo = a * b * c}\nend"
                    .replace("NAME", &format!("{:?}", textured.images[0].id))
                    .as_str(),
                vec![],
                Some(&textured),
            ),
        ),
        ("gltf_pbr, factors only", gltf_set(&plain)),
        ("gltf_pbr, 3 textures + alpha blend", gltf_set(&textured)),
        ("gltf_pbr, 2 textures + coat, sheen, transmission", gltf_set(&layered)),
    ];
    for (name, set) in &cases {
        time(set, n / 10);
        println!("{name:<52} {:>7.0} ns per call", time(set, n));
    }
}
