//! OBJ/MTL models: an OBJ cube with MTL shaders renders as the equivalent
//! CENG795 scene does; groups, materials, normals, texture coordinates and
//! image maps are read as the files say; `luster render model.obj` frames
//! the model. Assets are in `tests/obj/`.

use luster::math::Vec3;
use luster::render::{try_render_with, RenderOptions, Scene};
use luster::scene::description::{DecalMode, Interpolation, MaterialKind, MeshSource, Shape, TextureSource};
use luster::scene::obj::{self, ModelView};
use std::path::{Path, PathBuf};
use std::process::Command;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/obj").join(name)
}

fn render_rgb(scene: &Path) -> (u32, u32, Vec<u8>) {
    let desc = luster::scene::load(scene).unwrap_or_else(|e| panic!("{e}"));
    let s = Scene::build(&desc).unwrap_or_else(|e| panic!("{e}"));
    let img = try_render_with(&s, 0, &RenderOptions::default(), &|_| {}).expect("no shader fails");
    (img.width, img.height, img.to_rgb8())
}

/// (pixels whose 8-bit channels differ at all, largest channel difference).
fn diff(a: &[u8], b: &[u8]) -> (usize, u8) {
    assert_eq!(a.len(), b.len());
    let differing = a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p != q).count();
    let max = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
    (differing, max)
}

/// The bar of issue #7: the cube of `cube.obj`, whose MTL gives its material
/// and a `texture_shader` (and in the second pair a `bump_shader` too),
/// renders exactly as the CENG795 scene with the same cube inline, the same
/// material and `type="shader"` maps. The texture coordinates, the
/// triangulation, the material mapping and the shader parameters all have to
/// agree for that; the bar is no pixel differing at all.
#[test]
fn obj_cube_with_shaders_matches_the_inline_scene() {
    for (from_obj, inline) in
        [("cube_obj.xml", "cube_inline.xml"), ("cube_bump_obj.xml", "cube_bump_inline.xml")]
    {
        let (w, h, a) = render_rgb(&asset(from_obj));
        let (_, _, b) = render_rgb(&asset(inline));
        let (differing, max) = diff(&a, &b);
        assert_eq!(
            (differing, max),
            (0, 0),
            "{from_obj} against {inline}: {differing} pixels differ, by up to {max}"
        );
        // And the cube is there: a good part of the image is not background.
        let covered = a.chunks(3).filter(|p| p != &[30, 40, 60]).count();
        assert!(covered > (w * h / 8) as usize, "{from_obj}: the cube covers only {covered} pixels");
    }
    // The bump map changes the picture.
    let (_, _, plain) = render_rgb(&asset("cube_obj.xml"));
    let (_, _, bumped) = render_rgb(&asset("cube_bump_obj.xml"));
    assert!(diff(&plain, &bumped).0 > 1000, "the bump_shader should change the shading");
}

/// Groups and several materials: one part per material in order of first
/// use, with that material; quads and a pentagon triangulated; normals and
/// texture coordinates read (v flipped); an unused material left out.
#[test]
fn groups_and_materials_become_parts() {
    let m = obj::load(&asset("groups.obj")).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = m.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["red", "glass", "mirror"]);
    let tris: Vec<usize> = m.parts.iter().map(|p| p.arrays.triangles.len()).collect();
    assert_eq!(tris, [3, 3, 2], "quad + triangle, pentagon, quad");
    let red = &m.parts[0].material;
    assert_eq!(
        (red.kind, red.diffuse, red.ambient),
        (MaterialKind::Plain, Vec3::new(0.8, 0.1, 0.1), red.diffuse)
    );
    assert_eq!((red.specular, red.phong_exponent), (Vec3::splat(0.5), 80.0));
    let glass = &m.parts[1].material;
    assert_eq!((glass.kind, glass.refraction_index), (MaterialKind::Dielectric, 1.45));
    let mirror = &m.parts[2].material;
    assert_eq!((mirror.kind, mirror.mirror), (MaterialKind::Mirror, Vec3::splat(0.9)));
    assert!(m.has_normals());
    let floor = &m.parts[0].arrays;
    assert_eq!(floor.normals.as_ref().map(|n| n[0]), Some(Vec3::Y));
    let uvs = floor.uvs.as_ref().expect("texture coordinates");
    assert_eq!(uvs[0], luster::math::Vec2::new(0.0, 1.0), "vt 0 0 is the image's bottom-left: v flipped");
    // The pentagon's corners came through negative indices.
    let glass_xs: Vec<f32> = m.parts[1].arrays.positions.iter().map(|p| p.x).collect();
    assert!(glass_xs.contains(&4.3) && glass_xs.contains(&2.7), "{glass_xs:?}");
    assert!(m.warnings.iter().any(|w| w.to_string().contains("`l` statements")), "{:?}", m.warnings);
}

/// In a CENG795 scene, `objFile` without a `<Material>` makes one object per
/// material, with the MTL's materials after the scene's own; with one, a
/// single object; an instance of the multi-material mesh is refused.
#[test]
fn obj_meshes_in_ceng795_scenes() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    for f in ["groups.obj", "groups.mtl"] {
        std::fs::copy(asset(f), dir.path().join(f)).expect("copy");
    }
    let scene = |objects: &str| {
        format!(
            r#"{{"Scene": {{
            "Cameras": {{"Camera": {{"_id": "1", "Position": "0 3 6", "Gaze": "0 -0.4 -1", "Up": "0 1 0",
                "NearPlane": "-1 1 -1 1", "NearDistance": "1", "ImageResolution": "32 32", "ImageName": "o.png"}}}},
            "Materials": {{"Material": {{"_id": "own", "DiffuseReflectance": "0 1 0"}}}},
            "Objects": {objects}}}}}"#
        )
    };
    let write = |name: &str, text: String| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).expect("write");
        p
    };
    let multi = write("multi.json", scene(r#"{"Mesh": {"_id": "1", "Faces": {"_objFile": "groups.obj"}}}"#));
    let d = luster::scene::load(&multi).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(d.objects.len(), 3);
    let ids: Vec<&str> = d.objects.iter().map(|o| d.materials[o.material].id.as_str()).collect();
    assert_eq!(ids, ["red", "glass", "mirror"]);
    assert_eq!(d.materials[0].id, "own", "the scene's materials come first");
    assert!(d
        .objects
        .iter()
        .all(|o| matches!(o.shape, Shape::Mesh { source: MeshSource::Arrays(_), smooth: true })));
    assert!(d.objects[1].loc.path.contains("(material glass)"), "{}", d.objects[1].loc.path);
    Scene::build(&d).unwrap_or_else(|e| panic!("{e}"));

    let one = write(
        "one.json",
        scene(
            r#"{"Mesh": {"_id": "1", "_shadingMode": "flat", "Material": "own", "Faces": {"_objFile": "groups.obj"}}}"#,
        ),
    );
    let d = luster::scene::load(&one).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((d.objects.len(), d.materials.len(), d.objects[0].material), (1, 1, 0));
    match &d.objects[0].shape {
        Shape::Mesh { source: MeshSource::Arrays(a), smooth: false } => assert_eq!(a.triangles.len(), 8),
        other => panic!("{other:?}"),
    }

    let inst = write(
        "inst.json",
        scene(
            r#"{"Mesh": {"_id": "1", "Faces": {"_objFile": "groups.obj"}},
                "MeshInstance": {"_id": "2", "_baseMeshId": "1", "Material": "own"}}"#,
        ),
    );
    let e = luster::scene::load(&inst).unwrap_err().to_string();
    assert!(e.contains("several materials") && e.contains("MeshInstance[id=2]"), "{e}");
}

/// `map_Kd` is a bilinear `replace_kd` image map, and the image shows upright:
/// the quadrants of `textures/quadrants.png` land where the texture
/// coordinates put them (red top left, green top right, blue bottom left).
/// Other map statements map to their decal modes.
#[test]
fn image_maps() {
    let m = obj::load(&asset("quad.obj")).unwrap_or_else(|e| panic!("{e}"));
    let map = &m.parts[0].maps[0];
    assert_eq!(map.map.decal, DecalMode::ReplaceKd);
    assert!(matches!(map.map.source, TextureSource::Image { interpolation: Interpolation::Bilinear, .. }));
    assert!(map.image.as_ref().is_some_and(|i| i.path.ends_with("textures/quadrants.png")));

    let view = ModelView {
        width: 64,
        height: 64,
        samples: 1,
        azimuth: 0.0,
        elevation: 0.0,
        ground: false,
        ..Default::default()
    };
    let desc = obj::model_scene(&asset("quad.obj"), &view).unwrap_or_else(|e| panic!("{e}"));
    let s = Scene::build(&desc).unwrap_or_else(|e| panic!("{e}"));
    let img = try_render_with(&s, 0, &RenderOptions::default(), &|_| {}).expect("renders").to_rgb8();
    let px = |x: usize, y: usize| {
        let i = (y * 64 + x) * 3;
        [img[i], img[i + 1], img[i + 2]]
    };
    let dominant = |p: [u8; 3]| (0..3).max_by_key(|&c| p[c]).unwrap_or(0);
    // The square fills the middle of the view; sample well inside each quadrant.
    assert_eq!(dominant(px(24, 24)), 0, "top left is red: {:?}", px(24, 24));
    assert_eq!(dominant(px(40, 24)), 1, "top right is green: {:?}", px(40, 24));
    assert_eq!(dominant(px(24, 40)), 2, "bottom left is blue: {:?}", px(24, 40));
    let white = px(40, 40);
    assert!(
        white.iter().all(|&c| c > 60) && white.iter().max().unwrap() - white.iter().min().unwrap() < 20,
        "{white:?}"
    );

    // Specular, bump and normal maps, with options, from an MTL written here.
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::create_dir(dir.path().join("textures")).expect("mkdir");
    std::fs::copy(asset("textures/quadrants.png"), dir.path().join("textures/q.png")).expect("copy");
    std::fs::copy(asset("quad.obj"), dir.path().join("quad.obj")).expect("copy");
    std::fs::write(
        dir.path().join("quad.mtl"),
        "newmtl picture\nmap_Ks -clamp on textures/q.png\nbump -bm 0.25 textures/q.png\nnorm textures/q.png\n",
    )
    .expect("write");
    let m = obj::load(&dir.path().join("quad.obj")).unwrap_or_else(|e| panic!("{e}"));
    let decals: Vec<(DecalMode, f32)> =
        m.parts[0].maps.iter().map(|p| (p.map.decal, p.map.bump_factor)).collect();
    assert_eq!(
        decals,
        [(DecalMode::BumpNormal, 0.25), (DecalMode::ReplaceNormal, 1.0), (DecalMode::ReplaceKs, 1.0)]
    );
    assert!(m.warnings.iter().any(|w| w.to_string().contains("-clamp")), "{:?}", m.warnings);
    // One image file read once, however many maps use it.
    let desc = obj::model_scene(&dir.path().join("quad.obj"), &ModelView::default())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((desc.images.len(), desc.texture_maps.len()), (1, 3));
}

/// The model scene's camera frames the model: its bounding sphere projects
/// inside the image, whatever the view and aspect ratio.
#[test]
fn the_model_scene_frames_the_model() {
    let path = asset("groups.obj");
    let model = obj::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let (center, radius) = obj::model::bounding_sphere(&model);
    for (w, h, az, el) in [(800, 600, 35.0, 25.0), (300, 900, -120.0, 60.0), (1000, 200, 200.0, -10.0)] {
        let view = ModelView { width: w, height: h, azimuth: az, elevation: el, ..Default::default() };
        let d = obj::model_scene(&path, &view).unwrap_or_else(|e| panic!("{e}"));
        let cam = &d.cameras[0];
        let luster::scene::description::Projection::LookAt { gaze_point, fov_y } = cam.projection else {
            panic!("a lookAt camera")
        };
        assert_eq!(gaze_point, center);
        let forward = (gaze_point - cam.position).normalize();
        let right = forward.cross(cam.up).normalize();
        let up = right.cross(forward);
        let tan_y = (fov_y.to_radians() / 2.0).tan();
        let tan_x = tan_y * w as f32 / h as f32;
        // Points of the sphere around its silhouette, in every direction.
        for k in 0..64 {
            let a = k as f32 / 64.0 * std::f32::consts::TAU;
            for dir in [right * a.cos() + up * a.sin(), forward, -forward] {
                let p = center + dir * radius;
                let q = p - cam.position;
                let z = q.dot(forward);
                assert!(z > 0.0, "a point of the sphere is behind the camera");
                let (x, y) = (q.dot(right) / z / tan_x, q.dot(up) / z / tan_y);
                assert!(x.abs() < 1.0 && y.abs() < 1.0, "{w}x{h} az {az} el {el}: ({x}, {y}) is outside");
            }
        }
        assert_eq!(cam.resolution, (w, h));
        assert_eq!(cam.image_name, "groups.png");
        // The ground is under the model only when the camera is above it.
        let has_ground = d.objects.iter().any(|o| matches!(o.shape, Shape::Plane { .. }));
        assert_eq!(has_ground, el > 0.0);
    }
}

/// `luster render model.obj -o dir` writes `dir/<stem>.png`, a picture with
/// the model in it, and the view flags work.
#[test]
fn luster_render_writes_the_model_image() {
    let out = tempfile::tempdir().expect("a temporary folder");
    let run = Command::new(env!("CARGO_BIN_EXE_luster"))
        .args(["render", "-q", "--threads", "2", "--spp", "1", "--size", "96x64", "--azimuth", "-30"])
        .arg("-o")
        .arg(out.path())
        .arg(asset("cube.obj"))
        .output()
        .expect("luster runs");
    assert!(run.status.success(), "stderr: {}", String::from_utf8_lossy(&run.stderr));
    let png = out.path().join("cube.png");
    let img = image::open(&png).expect("a PNG").to_rgb8();
    assert_eq!(img.dimensions(), (96, 64));
    let corner = *img.get_pixel(0, 0);
    let center = *img.get_pixel(48, 32);
    assert_ne!(corner, center, "the model should fill the middle of the picture");
    let colours: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 50, "a shaded model has many colours, found {}", colours.len());
}
