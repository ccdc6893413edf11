//! glTF scenes (`luster render scene.gltf`, docs/gltf.md): node transforms
//! put triangles where the composed matrices say, a mesh drawn by two
//! nodes is one geometry, a camera sees a known point at a known pixel,
//! `KHR_lights_punctual` lights give the analytic irradiance on a diffuse
//! plane, GLB and glTF + .bin load alike, and a file without a camera is
//! framed. The files are written by [`Gltf`] from the tests themselves.

use crate::common::{render_spp, two_seed_mean};
use base64::Engine;
use luster::math::{Vec2, Vec3};
use luster::scene::description::{DecalMode, MeshSource, Shape, TextureMapDesc, TextureSource};
use luster::scene::obj::ModelView;
use luster::scene::Description;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A glTF document under construction: its buffer's bytes, buffer views
/// and accessors, and the rest of the JSON.
#[derive(Default)]
pub struct Gltf {
    /// The buffer.
    pub bin: Vec<u8>,
    /// `bufferViews`.
    pub views: Vec<Value>,
    /// `accessors`.
    pub accessors: Vec<Value>,
}

impl Gltf {
    /// Adds a float accessor of `ty` (`VEC3`, `VEC2`) over `data`; its index.
    pub fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let n = if ty == "VEC3" { 3 } else { 2 };
        let offset = self.bin.len();
        self.bin.extend(data.iter().flat_map(|f| f.to_le_bytes()));
        self.views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len() * 4}));
        let (mut lo, mut hi) = (vec![f32::INFINITY; n], vec![f32::NEG_INFINITY; n]);
        for c in data.chunks(n) {
            for k in 0..n {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        self.accessors.push(json!({"bufferView": self.views.len() - 1, "componentType": 5126,
            "count": data.len() / n, "type": ty, "min": lo, "max": hi}));
        self.accessors.len() - 1
    }

    /// Adds an unsigned-short index accessor; its index.
    pub fn indices(&mut self, ix: &[u16]) -> usize {
        let offset = self.bin.len();
        self.bin.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": ix.len() * 2}));
        self.accessors.push(json!({"bufferView": self.views.len() - 1, "componentType": 5123,
            "count": ix.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    /// A mesh of one indexed triangle primitive over `positions` (x y z ...).
    pub fn mesh(&mut self, positions: &[f32], ix: &[u16]) -> Value {
        let p = self.floats(positions, "VEC3");
        let i = self.indices(ix);
        json!({"primitives": [{"attributes": {"POSITION": p}, "indices": i}]})
    }

    /// The whole document, `rest` holding nodes, meshes and the like; the
    /// buffer is `uri` (None: a base64 data URI).
    pub fn document(&self, rest: Value, uri: Option<&str>) -> Value {
        let mut doc = rest;
        let uri = uri.map_or_else(
            || {
                format!(
                    "data:application/octet-stream;base64,{}",
                    base64::engine::general_purpose::STANDARD.encode(&self.bin)
                )
            },
            str::to_string,
        );
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{"byteLength": self.bin.len(), "uri": uri}]);
        doc["bufferViews"] = Value::Array(self.views.clone());
        doc["accessors"] = Value::Array(self.accessors.clone());
        doc
    }

    /// The document and buffer as one GLB file's bytes.
    pub fn glb(&self, rest: Value) -> Vec<u8> {
        let mut doc = self.document(rest, None);
        doc["buffers"] = json!([{"byteLength": self.bin.len()}]);
        let mut json = serde_json::to_vec(&doc).expect("JSON");
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let mut out = b"glTF".to_vec();
        out.extend(2u32.to_le_bytes());
        out.extend(((28 + json.len() + bin.len()) as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(&json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(&bin);
        out
    }
}

/// Writes `doc` as `name` in `dir`; its path.
pub fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, serde_json::to_vec_pretty(doc).expect("JSON")).expect("the glTF file");
    p
}

/// The unit right triangle in the z = 0 plane, facing +z.
const TRIANGLE: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

fn load(path: &Path, view: &ModelView) -> Description {
    luster::scene::load_viewed(path, view).unwrap_or_else(|e| panic!("{e}"))
}

/// The world positions of a mesh object's (or its base's) vertices.
fn world_vertices(desc: &Description, o: usize) -> Vec<Vec3> {
    let obj = &desc.objects[o];
    let base = match obj.shape {
        Shape::Instance { mesh } => &desc.objects[mesh],
        _ => obj,
    };
    let Shape::Mesh { source: MeshSource::Arrays(a), .. } = &base.shape else {
        panic!("not a mesh: {:?}", base.shape)
    };
    a.positions.iter().map(|&p| obj.transform.point(p)).collect()
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// A parent with translation, rotation and scale and a child with a matrix
/// put the triangle where the composed transforms say (worked by hand:
/// child translate (0, 0, 1), then scale 2, a quarter turn about +y taking
/// x to −z, then translate (1, 2, 3)). A mirroring node keeps glTF's front
/// face: with a negative determinant the front is the side the triangle's
/// world winding turns clockwise from, which the normal transform gives.
#[test]
fn node_transforms_compose_parent_after_child() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    let mesh = g.mesh(&TRIANGLE, &[0, 1, 2]);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let rest = json!({
        "scene": 0, "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"translation": [1, 2, 3], "rotation": [0, h, 0, h], "scale": [2, 2, 2], "children": [1]},
            {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1], "mesh": 0},
            {"scale": [1, 1, -1], "mesh": 0}
        ],
        "meshes": [mesh],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional"}]}}
    });
    let path = write(dir.path(), "t.gltf", &g.document(rest, None));
    let desc = load(&path, &ModelView::default());
    let v = world_vertices(&desc, 0);
    let want = [Vec3::new(3.0, 2.0, 3.0), Vec3::new(3.0, 2.0, 1.0), Vec3::new(3.0, 4.0, 3.0)];
    for (got, want) in v.iter().zip(want) {
        assert!(close(*got, want), "vertex at {got:?}, expected {want:?}");
    }
    // The mirrored one: same triangle in z = 0, its front now facing −z.
    let obj = &desc.objects[1];
    assert!(matches!(obj.shape, Shape::Instance { mesh: 0 }), "{:?}", obj.shape);
    assert!(obj.transform.swaps_handedness());
    let n = obj.transform.normal_to_world(Vec3::Z).normalize();
    assert!(close(n, -Vec3::Z), "front normal {n:?}");
}

/// Two nodes drawing one mesh: one geometry (the second object is an
/// instance of the first), each placed by its own node.
#[test]
fn a_mesh_drawn_twice_is_one_geometry_and_two_objects() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    let mesh = g.mesh(&TRIANGLE, &[0, 1, 2]);
    let rest = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "translation": [-2, 0, 0]}, {"mesh": 0, "translation": [2, 0, 0]}],
        "meshes": [mesh]
    });
    let path = write(dir.path(), "i.gltf", &g.document(rest, None));
    let desc = load(&path, &ModelView::default());
    let meshes: Vec<usize> =
        (0..desc.objects.len()).filter(|&i| matches!(desc.objects[i].shape, Shape::Mesh { .. })).collect();
    assert_eq!(meshes, [0], "one geometry");
    assert!(matches!(desc.objects[1].shape, Shape::Instance { mesh: 0 }), "{:?}", desc.objects[1].shape);
    assert!(close(world_vertices(&desc, 0)[1], Vec3::new(-1.0, 0.0, 0.0)));
    assert!(close(world_vertices(&desc, 1)[1], Vec3::new(3.0, 0.0, 0.0)));
    // Without lights the studio's ground comes last: only those three objects.
    assert_eq!(desc.objects.len(), 3);
    assert!(matches!(desc.objects[2].shape, Shape::Plane { .. }));
}

/// A scene with two cameras: camera 1 (turned to look down −x from +x)
/// sees a small square at the pixel its pinhole projection gives, and
/// nothing at the mirrored pixel; `--camera 2` is refused naming the count.
#[test]
fn a_camera_sees_a_known_point_at_its_pixel() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    // A square of side 0.2 in the x = 0 plane facing +x, centred at (0, 0.5, 1).
    let sq = [0.0, 0.4, 0.9, 0.0, 0.4, 1.1, 0.0, 0.6, 1.1, 0.0, 0.6, 0.9];
    let mesh = g.mesh(&sq, &[0, 2, 1, 0, 3, 2]);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let rest = json!({
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"camera": 0, "translation": [0, 0, 9]},
            // A quarter turn about +y takes −z (the camera's view) to −x.
            {"camera": 0, "translation": [5, 0, 0], "rotation": [0, h, 0, h]},
            {"mesh": 0},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [0, h, 0, h]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "aspectRatio": 1.0, "znear": 0.1}}],
        "meshes": [mesh],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 2000}]}}
    });
    let path = write(dir.path(), "c.gltf", &g.document(rest, None));
    let view = ModelView { camera: Some(1), ..ModelView::default() };
    let desc = load(&path, &view);
    let cam = &desc.cameras[0];
    assert_eq!(cam.resolution, (600, 600), "aspectRatio 1 sets the width");
    let view = ModelView { camera: Some(1), width: 64, height: 64, sized: true, ..ModelView::default() };
    let desc = load(&path, &view);
    let img = render_spp(&desc, 4, 0);
    // Seen from (5, 0, 0) looking down −x, +z is to the left... the camera's
    // right is its node's +x, which the quarter turn takes to −z.
    let t = (0.25f32).tan();
    let px = 32.0 + (-1.0 / 5.0) / t * 32.0;
    let py = 32.0 - (0.5 / 5.0) / t * 32.0;
    let at = |x: f32, y: f32| img.pixels[(y as usize) * 64 + x as usize];
    assert!(at(px, py).x > 1.0, "the square is not at ({px}, {py}): {:?}", at(px, py));
    assert_eq!(at(64.0 - px, py), Vec3::ZERO, "something at the mirrored pixel");
    assert_eq!(at(px, 64.0 - py), Vec3::ZERO, "something at the flipped pixel");
    let bad = ModelView { camera: Some(2), ..ModelView::default() };
    let e = luster::scene::load_viewed(&path, &bad).expect_err("no camera 2").to_string();
    assert!(e.contains("--camera 2: the file has 2 perspective cameras"), "{e}");
}

/// A diffuse closure of albedo 0.5 on every object.
fn diffuse_everywhere(desc: &mut Description, dir: &Path) {
    let script = dir.join("m.lua");
    let code = "function material(s) return diffuse{albedo = 0.5} end".to_string();
    std::fs::write(&script, &code).expect("the shader");
    desc.texture_maps.push(TextureMapDesc {
        id: "m".into(),
        source: TextureSource::Shader { path: script, code, params: Vec::new() },
        decal: DecalMode::Material,
        bump_factor: 1.0,
        loc: Default::default(),
    });
    let m = desc.texture_maps.len() - 1;
    for o in &mut desc.objects {
        o.textures = vec![m];
    }
}

/// The analytic irradiance of `KHR_lights_punctual` lights on a diffuse
/// plane: a point light of `cd` candela 2 above the plane gives
/// `E = (255 cd / 683) · 2 / (4 + r²)^1.5` at distance r from its foot, a
/// directional light of `lux` straight down gives `E = 255 lux / 683`, and
/// a diffuse surface of albedo 0.5 shows `0.5 E / π`. Each pixel's value is
/// compared with the formula at the point its centre sees; the mean ratio
/// is judged against 1 with the standard error of two seeds.
#[test]
fn punctual_lights_give_the_analytic_irradiance() {
    for (kind, light) in [
        ("point", json!({"type": "point", "intensity": 300.0, "color": [1.0, 0.5, 0.25]})),
        ("directional", json!({"type": "directional", "intensity": 1000.0, "color": [1.0, 0.5, 0.25]})),
    ] {
        let dir = tempfile::tempdir().expect("temp dir");
        let mut g = Gltf::default();
        let plane = [-10.0, -10.0, 0.0, 10.0, -10.0, 0.0, 10.0, 10.0, 0.0, -10.0, 10.0, 0.0];
        let mesh = g.mesh(&plane, &[0, 1, 2, 0, 2, 3]);
        let rest = json!({
            "scenes": [{"nodes": [0, 1, 2]}],
            "nodes": [
                {"mesh": 0},
                {"camera": 0, "translation": [0, 0, 4]},
                // Lights shine down their node's −z: straight down here.
                {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 0, 2]}
            ],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1}}],
            "meshes": [mesh],
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [light]}}
        });
        let path = write(dir.path(), "l.gltf", &g.document(rest, None));
        let view = ModelView { width: 24, height: 24, sized: true, ..ModelView::default() };
        let mut desc = load(&path, &view);
        diffuse_everywhere(&mut desc, dir.path());
        let (a, b) = (render_spp(&desc, 4, 1), render_spp(&desc, 4, 2));
        let half = (0.3f32).tan() * 4.0;
        let colour = Vec3::new(1.0, 0.5, 0.25);
        let expected = |i: usize| -> Vec3 {
            let x = ((i % 24) as f32 + 0.5) / 24.0 * 2.0 - 1.0;
            let y = ((i / 24) as f32 + 0.5) / 24.0 * 2.0 - 1.0;
            let r2 = Vec2::new(x, y).length_squared() * half * half;
            let e = match kind {
                "point" => 255.0 * 300.0 / 683.0 * 2.0 / (4.0 + r2).powf(1.5),
                _ => 255.0 * 1000.0 / 683.0,
            };
            colour * (0.5 * e / std::f32::consts::PI)
        };
        for ch in 0..3 {
            let ratio = |img: &luster::render::RenderedImage| -> Vec<f64> {
                (0..img.pixels.len()).map(|i| f64::from(img.pixels[i][ch] / expected(i)[ch])).collect()
            };
            let (mean, se) = two_seed_mean(&ratio(&a), &ratio(&b));
            // Float accumulation in the film allows ~1e-5 beyond the noise.
            assert!(
                (mean - 1.0).abs() <= 4.0 * se + 1e-4,
                "{kind} light, channel {ch}: rendered/analytic = {mean} ± {se}"
            );
        }
    }
}

/// The same document as a GLB and as a .gltf with a .bin file beside it
/// loads to the same description.
#[test]
fn glb_and_gltf_with_bin_load_alike() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    let mesh = g.mesh(&TRIANGLE, &[0, 1, 2]);
    let rest = json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "translation": [0, 1, 0]}], "meshes": [mesh]});
    std::fs::write(dir.path().join("m b.bin"), &g.bin).expect("bin");
    let a = write(dir.path(), "a.gltf", &g.document(rest.clone(), Some("m%20b.bin")));
    let b = dir.path().join("b.glb");
    std::fs::write(&b, g.glb(rest)).expect("glb");
    let (da, db) = (load(&a, &ModelView::default()), load(&b, &ModelView::default()));
    assert_eq!(da.objects.len(), db.objects.len());
    assert_eq!(format!("{:?}", da.objects), format!("{:?}", db.objects).replace("b.glb", "a.gltf"));
    assert_eq!(world_vertices(&da, 0), world_vertices(&db, 0));
    assert!(close(world_vertices(&da, 0)[2], Vec3::new(0.0, 2.0, 0.0)));
}

/// Without a camera the studio's framing camera looks at the model's
/// bounding sphere (here centred at (5, 0.5, 0)) from the view's azimuth
/// and elevation, and the studio lights it.
#[test]
fn a_file_without_a_camera_is_framed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    let mesh = g.mesh(&TRIANGLE, &[0, 1, 2]);
    let rest = json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "translation": [4.5, 0, 0]}], "meshes": [mesh]});
    let path = write(dir.path(), "f.gltf", &g.document(rest, None));
    let view = ModelView { azimuth: 0.0, elevation: 0.0, ..ModelView::default() };
    let desc = load(&path, &view);
    let cam = &desc.cameras[0];
    assert_eq!((cam.resolution, cam.image_name.as_str()), ((800, 600), "f.png"));
    match cam.projection {
        luster::scene::description::Projection::LookAt { gaze_point, .. } => {
            assert!(close(gaze_point, Vec3::new(5.0, 0.5, 0.0)), "{gaze_point:?}")
        }
        p => panic!("not a framing camera: {p:?}"),
    }
    assert!(cam.position.z > 1.0 && (cam.position.x - 5.0).abs() < 1e-4, "{:?}", cam.position);
    assert_eq!(desc.point_lights.len(), 2, "the studio's key and fill");
    // The triangle is in view and lit: the pixel just left of and below the
    // centre sees (4.9, 0.4, 0), inside it, brighter than the background.
    let view = ModelView {
        azimuth: 0.0,
        elevation: 0.0,
        width: 32,
        height: 24,
        sized: true,
        ..ModelView::default()
    };
    let desc = load(&path, &view);
    let img = render_spp(&desc, 2, 0);
    let p = img.pixels[13 * 32 + 14];
    assert!(p.x > desc.background.x + 5.0, "the triangle's pixel is {p:?}");
}

/// A CENG795 scene's `<Faces gltfFile>`: the glTF's nodes placed, then the
/// Mesh's transformation; a mesh drawn twice stays one geometry; with a
/// `<Material>` every object takes it, without one the glTF's materials
/// follow the scene's own; an instance of a many-object glTF is refused.
#[test]
fn a_course_scene_places_a_gltf_mesh() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = Gltf::default();
    let mesh = g.mesh(&TRIANGLE, &[0, 1, 2]);
    let rest = json!({
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0, "translation": [1, 0, 0]}, {"mesh": 0, "translation": [0, 0, -1]}, {"camera": 0}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "meshes": [mesh],
        "materials": [{"name": "Body"}]
    });
    std::fs::write(dir.path().join("m.glb"), g.glb(rest)).expect("glb");
    let scene = |material: &str, extra: &str| {
        format!(
            r#"<Scene>
  <Cameras><Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
    <ImageName>a.png</ImageName></Camera></Cameras>
  <Materials><Material id="1"><DiffuseReflectance>1 0 0</DiffuseReflectance></Material></Materials>
  <Transformations><Translation id="1">0 10 0</Translation></Transformations>
  <Objects><Mesh id="7">{material}<Transformations>t1</Transformations><Faces gltfFile="m.glb"/></Mesh>{extra}</Objects>
</Scene>"#
        )
    };
    let desc = crate::common::load_with(dir.path(), &scene("<Material>1</Material>", ""), &[]);
    assert_eq!(desc.objects.len(), 2);
    assert!(matches!(desc.objects[0].shape, Shape::Mesh { .. }));
    assert!(matches!(desc.objects[1].shape, Shape::Instance { mesh: 0 }), "{:?}", desc.objects[1].shape);
    assert!(close(world_vertices(&desc, 0)[1], Vec3::new(2.0, 10.0, 0.0)));
    assert!(close(world_vertices(&desc, 1)[2], Vec3::new(0.0, 11.0, -1.0)));
    assert!(desc.objects.iter().all(|o| o.material == 0 && o.id == "7"));
    assert!(
        desc.warnings.iter().any(|w| w.message.contains("cameras and lights are not used")),
        "{:?}",
        desc.warnings
    );
    // Without a <Material>: the glTF's material, after the scene's one.
    let desc = crate::common::load_with(dir.path(), &scene("", ""), &[]);
    assert_eq!(desc.materials.len(), 2);
    assert!(
        desc.objects.iter().all(|o| o.material == 1),
        "{:?}",
        desc.objects.iter().map(|o| o.material).collect::<Vec<_>>()
    );
    // Two objects: an instance of the Mesh cannot choose between them.
    let text = scene(
        "<Material>1</Material>",
        r#"<MeshInstance id="8" baseMeshId="7"><Material>1</Material></MeshInstance>"#,
    );
    std::fs::write(dir.path().join("s.xml"), text).expect("scene");
    let e = luster::scene::load(&dir.path().join("s.xml")).expect_err("refused").to_string();
    assert!(e.contains("makes several objects"), "{e}");
}
