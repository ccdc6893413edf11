//! The `<Ellipsoid>` extension: it reads alike from XML and JSON, and a scene
//! of ellipsoids renders the same pixels as the same scene built from unit
//! spheres under "scale by the radii, rotate, translate" transforms — with an
//! image map, a Perlin map, a `Transformations` list on top, motion blur and
//! shadows on a plane.

use luster::math::{Quat, Vec3};
use luster::render::{render, Scene};
use luster::scene::description::{Description, Shape};
use std::io::Write;
use std::path::Path;

/// A scene around `objects`: a camera with 4 samples per pixel (so motion
/// blur is sampled), a point light, a floor, an image map (1) and a Perlin
/// map (2).
fn scene(objects: &str) -> String {
    format!(
        r#"<Scene>
  <Cameras><Camera id="1"><Position>0 1 10</Position><Gaze>0 -0.1 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>4</NearDistance>
    <ImageResolution>96 96</ImageResolution><NumSamples>4</NumSamples><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>25 25 25</AmbientLight>
    <PointLight id="1"><Position>3 6 8</Position><Intensity>20000 20000 20000</Intensity></PointLight></Lights>
  <Materials>
    <Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
      <SpecularReflectance>1 1 1</SpecularReflectance><PhongExponent>40</PhongExponent></Material>
    <Material id="2"><AmbientReflectance>0.5 0.5 0.5</AmbientReflectance><DiffuseReflectance>0.4 0.6 0.3</DiffuseReflectance></Material>
  </Materials>
  <Textures>
    <Images><Image id="1">stripes.png</Image></Images>
    <TextureMap id="1" type="image"><ImageId>1</ImageId><DecalMode>replace_kd</DecalMode></TextureMap>
    <TextureMap id="2" type="perlin"><NoiseScale>3</NoiseScale><NoiseConversion>absval</NoiseConversion><DecalMode>replace_kd</DecalMode></TextureMap>
  </Textures>
  <Transformations>
    <Scaling id="1">1.2 0.5 0.8</Scaling>
    <Rotation id="1">30 1 1 0</Rotation>
    <Translation id="1">1.5 0.5 0</Translation>
    <Scaling id="2">0.6 1 0.4</Scaling>
    <Rotation id="2">45 0 0 1</Rotation>
    <Scaling id="3">0.3 0.6 0.3</Scaling>
    <Translation id="3">-1.5 -0.8 1</Translation>
    <Rotation id="9">-20 0 1 0</Rotation>
    <Translation id="9">-1.2 0.3 -1</Translation>
  </Transformations>
  <VertexData>0 0 0  1.5 0.5 0  -1.5 -0.8 1  0 -1.6 0</VertexData>
  <Objects>
    <Plane id="1"><Material>2</Material><Point>4</Point><Normal>0 1 0</Normal></Plane>
    {objects}
  </Objects>
</Scene>"#
    )
}

/// The three ellipsoids: one with a centre and rotation of its own, one with
/// a `Transformations` list on top, one moving.
const ELLIPSOIDS: &str = r#"
    <Ellipsoid id="1"><Material>1</Material><Textures>1</Textures><Center>2</Center>
      <Radii>1.2 0.5 0.8</Radii><Rotation>30 1 1 0</Rotation></Ellipsoid>
    <Ellipsoid id="2"><Material>1</Material><Textures>2</Textures><Transformations>r9 t9</Transformations>
      <Center>1</Center><Radii>0.6 1 0.4</Radii><Rotation>45 0 0 1</Rotation></Ellipsoid>
    <Ellipsoid id="3"><Material>2</Material><Center>3</Center><Radii>0.3 0.6 0.3</Radii>
      <MotionBlur>0.5 0 0</MotionBlur></Ellipsoid>"#;

/// The same three as unit spheres at the origin, transformed.
const SPHERES: &str = r#"
    <Sphere id="1"><Material>1</Material><Textures>1</Textures><Transformations>s1 r1 t1</Transformations>
      <Center>1</Center><Radius>1</Radius></Sphere>
    <Sphere id="2"><Material>1</Material><Textures>2</Textures><Transformations>s2 r2 r9 t9</Transformations>
      <Center>1</Center><Radius>1</Radius></Sphere>
    <Sphere id="3"><Material>2</Material><Transformations>s3 t3</Transformations><Center>1</Center><Radius>1</Radius>
      <MotionBlur>0.5 0 0</MotionBlur></Sphere>"#;

/// Writes `text` as `name` in `dir`, with the image map's picture beside it,
/// and loads it.
fn load(dir: &Path, name: &str, text: &str) -> Description {
    // 16×8 texels, each its own colour, so a wrong u or v shows as a wrong colour.
    let img = image::RgbImage::from_fn(16, 8, |x, y| {
        image::Rgb([(x * 16) as u8, (y * 32) as u8, if (x + y) % 2 == 0 { 230 } else { 40 }])
    });
    img.save(dir.join("stripes.png")).unwrap();
    let p = dir.join(name);
    std::fs::File::create(&p).unwrap().write_all(text.as_bytes()).unwrap();
    luster::scene::load(&p).unwrap()
}

/// The render's 8-bit pixels.
fn rgb(desc: &Description) -> Vec<[u8; 3]> {
    let bytes = render(&Scene::build(desc).unwrap(), 0, &|_| {}).to_rgb8();
    bytes.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[test]
fn ellipsoids_render_like_transformed_spheres() {
    let dir = tempfile::tempdir().unwrap();
    let a = rgb(&load(dir.path(), "ellipsoids.xml", &scene(ELLIPSOIDS)));
    let b = rgb(&load(dir.path(), "spheres.xml", &scene(SPHERES)));
    let floor_only = rgb(&load(dir.path(), "floor.xml", &scene("")));
    // The objects cover a good part of the frame (so the comparison means something).
    let covered = a.iter().zip(&floor_only).filter(|(p, q)| p != q).count();
    assert!(covered > 1500, "only {covered} pixels show the ellipsoids or their shadows");

    // Metric: the largest difference over the three 8-bit channels, per
    // pixel. The two scenes solve different (but equivalent) quadratics, so
    // float noise may flip a pixel where a ray grazes a silhouette or a uv
    // lands on a texel edge; everywhere else the images must agree to ±1.
    // Threshold: at most 20 of the 9216 pixels off by more than 1, and a
    // mean difference under 0.1.
    let diff: Vec<u8> =
        a.iter().zip(&b).map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0)).collect();
    let off = diff.iter().filter(|&&d| d > 1).count();
    let mean = diff.iter().map(|&d| d as f64).sum::<f64>() / diff.len() as f64;
    assert!(off <= 20, "{off} of {} pixels differ by more than 1", diff.len());
    assert!(mean < 0.1, "mean difference {mean}");
}

#[test]
fn xml_and_json_read_the_same_ellipsoid() {
    let dir = tempfile::tempdir().unwrap();
    let xml = load(dir.path(), "e.xml", &scene(ELLIPSOIDS));
    let json = r#"{"Scene": {
      "Cameras": {"Camera": {"_id": "1", "Position": "0 0 10", "Gaze": "0 0 -1", "Up": "0 1 0",
        "NearPlane": "-1 1 -1 1", "NearDistance": "1", "ImageResolution": "8 8", "ImageName": "a.png"}},
      "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}},
      "Transformations": {"Translation": {"_id": "1", "_data": "0 1 0"}},
      "VertexData": {"_data": "0 0 0  1.5 0.5 0", "_type": "xyz"},
      "Objects": {"Ellipsoid": [
        {"_id": "1", "Material": "1", "Center": "2", "Radii": "1.2 0.5 0.8", "Rotation": "30 1 1 0"},
        {"_id": "2", "Material": "1", "Center": "1", "Radii": "1 2 3", "Transformations": "t1", "MotionBlur": "0 0 1"}
      ]}}}"#;
    let json = load(dir.path(), "e.json", json);
    let (
        Shape::Ellipsoid { center: c0, radii: r0, rotation: q0 },
        Shape::Ellipsoid { center, radii, rotation },
    ) = (&xml.objects[1].shape, &json.objects[0].shape)
    else {
        panic!("not ellipsoids: {:?}, {:?}", xml.objects[1].shape, json.objects[0].shape);
    };
    assert_eq!((c0, r0), (center, radii));
    assert!(q0.abs_diff_eq(*rotation, 1e-7));
    let expected = Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 30f32.to_radians());
    assert!(rotation.abs_diff_eq(expected, 1e-6), "{rotation}");
    // No Rotation: the identity; Transformations and MotionBlur as for spheres.
    let o = &json.objects[1];
    assert!(matches!(o.shape, Shape::Ellipsoid { rotation, .. } if rotation == Quat::IDENTITY));
    assert!((o.transform.point(Vec3::ZERO) - Vec3::Y).length() < 1e-6);
    assert_eq!(o.motion, Vec3::Z);
}
