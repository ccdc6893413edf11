//! Attributes end to end (docs/attributes.md): one mesh drawn by several
//! `MeshInstance`s, each with its own `tint`, shaded by one script that
//! returns `getattribute("tint", ...)`; the same through a glTF file's node
//! and mesh `extras`; and bad attributes refused with exit code 2.

use crate::common::{folder, run_limited};
use crate::gltf::Gltf;
use luster::render::{try_render_with, RenderOptions, Scene};
use serde_json::json;
use std::path::Path;
use std::time::Duration;

/// `replace_all` shows the returned colour unlit; 8-bit channels are the
/// colour truncated, so whole numbers come out exactly.
const TINT: &str = r#"function color(s) return getattribute("tint", rgb(77, 77, 77)) end"#;

/// A 160×80 image of z = 0 seen straight on, ten pixels to a unit: x from
/// -8 to 8, y from -4 to 4. `objects` are the scene's objects; the quad
/// is vertices 1–4 (1.6 units across, centred on the origin).
fn scene(objects: &str) -> String {
    format!(
        r#"<Scene>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-8 8 -4 4</NearPlane><NearDistance>10</NearDistance>
    <ImageResolution>160 80</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>0 0 0</AmbientLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
  <Textures><TextureMap id="1" type="shader"><Shader>tint.lua</Shader><DecalMode>replace_all</DecalMode></TextureMap></Textures>
  <Transformations>
    <Translation id="1">-6 0 0</Translation><Translation id="2">-3 0 0</Translation>
    <Translation id="3">0 0 0</Translation><Translation id="4">3 0 0</Translation>
    <Translation id="5">6 0 0</Translation><Translation id="6">0 -2.5 0</Translation>
  </Transformations>
  <VertexData>-0.8 -0.8 0  0.8 -0.8 0  0.8 0.8 0  -0.8 0.8 0</VertexData>
  <Objects>{objects}</Objects>
</Scene>"#
    )
}

/// The pixel of the image at world point (x, y) on z = 0.
fn pixel(img: &[u8], x: f32, y: f32) -> [u8; 3] {
    let (col, row) = (((x + 8.0) * 10.0) as usize, ((4.0 - y) * 10.0) as usize);
    let i = 3 * (row * 160 + col);
    [img[i], img[i + 1], img[i + 2]]
}

fn render(dir: &Path, name: &str) -> Vec<u8> {
    let desc = luster::scene::load(&dir.join(name)).expect("the scene loads");
    let s = Scene::build(&desc).expect("the scene builds");
    match try_render_with(&s, 0, &RenderOptions::default(), &|_| {}) {
        Ok(img) => img.to_rgb8(),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn each_instance_shows_its_own_tint() {
    let objects = r#"
      <Mesh id="1"><Material>1</Material><Textures>1</Textures><Transformations>t1</Transformations>
        <Faces>1 2 3 1 3 4</Faces><Attribute name="tint">10 20 30</Attribute></Mesh>
      <MeshInstance id="2" baseMeshId="1" resetTransform="true"><Transformations>t2</Transformations>
        <Attribute name="tint">200 40 10</Attribute></MeshInstance>
      <MeshInstance id="3" baseMeshId="1" resetTransform="true"><Transformations>t3</Transformations>
        <Attribute name="tint">40 200 10</Attribute></MeshInstance>
      <MeshInstance id="4" baseMeshId="1" resetTransform="true"><Transformations>t4</Transformations></MeshInstance>
      <MeshInstance id="5" baseMeshId="2" resetTransform="true"><Transformations>t5</Transformations></MeshInstance>
      <Mesh id="6"><Material>1</Material><Textures>1</Textures><Transformations>t6</Transformations>
        <Faces>1 2 3 1 3 4</Faces></Mesh>"#;
    let dir = folder(&[("s.xml", &scene(objects)), ("tint.lua", TINT)]);
    let img = render(dir.path(), "s.xml");
    // The mesh itself, two instances with their own tints, one without (the
    // mesh's), an instance of an instance (its base's), and a mesh without
    // attributes (the default).
    assert_eq!(pixel(&img, -6.0, 0.0), [10, 20, 30]);
    assert_eq!(pixel(&img, -3.0, 0.0), [200, 40, 10]);
    assert_eq!(pixel(&img, 0.0, 0.0), [40, 200, 10]);
    assert_eq!(pixel(&img, 3.0, 0.0), [10, 20, 30]);
    assert_eq!(pixel(&img, 6.0, 0.0), [200, 40, 10]);
    assert_eq!(pixel(&img, 0.0, -2.5), [77, 77, 77]);
    assert_eq!(pixel(&img, 0.0, 2.5), [0, 0, 0], "the background");
}

#[test]
fn gltf_extras_are_attributes() {
    // One quad mesh drawn by three nodes: two with their own tints, one
    // taking the mesh's; a fourth node's extras hold a nested object, which
    // is skipped with a warning.
    let mut g = Gltf::default();
    let mut quad =
        g.mesh(&[-0.8, -0.8, 0.0, 0.8, -0.8, 0.0, 0.8, 0.8, 0.0, -0.8, 0.8, 0.0], &[0, 1, 2, 0, 2, 3]);
    quad["extras"] = json!({"tint": [10, 20, 30]});
    let doc = g.document(
        json!({
            "scenes": [{"nodes": [0, 1, 2, 3]}],
            "nodes": [
                {"mesh": 0, "translation": [-6, 0, 0], "extras": {"tint": [200, 40, 10], "wear": 0.5}},
                {"mesh": 0, "translation": [-3, 0, 0], "extras": {"tint": [40, 200, 10]}},
                {"mesh": 0, "translation": [0, 0, 0]},
                {"mesh": 0, "translation": [3, 0, 0], "extras": {"tint": {"r": 1}}},
            ],
            "meshes": [quad],
        }),
        None,
    );
    let objects =
        r#"<Mesh id="1"><Material>1</Material><Textures>1</Textures><Faces gltfFile="m.gltf"/></Mesh>"#;
    let dir = folder(&[("s.xml", &scene(objects)), ("tint.lua", TINT)]);
    crate::gltf::write(dir.path(), "m.gltf", &doc);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("the scene loads");
    let warned: Vec<String> = desc.warnings.iter().map(ToString::to_string).collect();
    let skipped: Vec<&String> = warned.iter().filter(|w| w.contains("extras")).collect();
    assert_eq!(skipped.len(), 1, "{warned:?}");
    assert!(skipped[0].contains("nodes[3].extras.tint"), "{skipped:?}");
    let img = render(dir.path(), "s.xml");
    assert_eq!(pixel(&img, -6.0, 0.0), [200, 40, 10]);
    assert_eq!(pixel(&img, -3.0, 0.0), [40, 200, 10]);
    assert_eq!(pixel(&img, 0.0, 0.0), [10, 20, 30]);
    assert_eq!(pixel(&img, 3.0, 0.0), [10, 20, 30]);
}

#[test]
fn bad_attributes_exit_2_naming_the_file_and_element() {
    let cases = [
        (r#"<Attribute name="tint">1</Attribute><Attribute name="tint">2</Attribute>"#, "is given twice"),
        (r#"<Attribute>1</Attribute>"#, "has no name attribute"),
        (r#"<Attribute name="tint">1 2</Attribute>"#, "has 2 numbers"),
        (r#"<Attribute name="object:name">x</Attribute>"#, "reserved"),
    ];
    for (attrs, why) in cases {
        let objects = format!(
            r#"<Mesh id="1"><Material>1</Material><Faces>1 2 3</Faces></Mesh>
               <MeshInstance id="7" baseMeshId="1">{attrs}</MeshInstance>"#
        );
        let dir = folder(&[("s.xml", &scene(&objects)), ("tint.lua", TINT)]);
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_luster"));
        cmd.arg("render").arg("-q").arg("-o").arg(dir.path()).arg(dir.path().join("s.xml"));
        let run = run_limited(cmd, Duration::from_secs(60));
        assert_eq!(run.code, Some(2), "{attrs}: {}", run.stderr);
        let err = run.stderr.trim_end();
        assert_eq!(err.lines().count(), 1, "{attrs}: {err}");
        assert!(
            err.contains("s.xml: line ") && err.contains("MeshInstance[id=7]/Attribute"),
            "{attrs}: {err}"
        );
        assert!(err.contains(why), "{attrs}: {err}");
        assert!(!dir.path().join("a.png").exists(), "{attrs}: an image was written");
    }
}
