//! Mesh instances: the transform rules of the hw2 spec (eq. 3) checked on the
//! loaded description, and an instance rendering the same pixels as the
//! equivalent mesh.

use luster::math::{Transform, Vec3};
use luster::render::{render, Scene};
use luster::scene::description::Shape;
use std::io::Write;

fn scene(objects: &str) -> String {
    format!(
        r#"<Scene>
  <Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>2</NearDistance>
    <ImageResolution>64 64</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>20 20 20</AmbientLight>
    <PointLight id="1"><Position>3 4 10</Position><Intensity>2000 2000 2000</Intensity></PointLight></Lights>
  <Materials>
    <Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>1 0.5 0.2</DiffuseReflectance>
      <SpecularReflectance>1 1 1</SpecularReflectance><PhongExponent>20</PhongExponent></Material>
    <Material id="2"><AmbientReflectance>0.2 1 0.2</AmbientReflectance><DiffuseReflectance>0.2 1 0.2</DiffuseReflectance></Material>
  </Materials>
  <Transformations>
    <Translation id="1">1 0 0</Translation>
    <Rotation id="1">90 0 0 1</Rotation>
    <Scaling id="1">2 2 2</Scaling>
  </Transformations>
  <VertexData>-1 -1 0  1 -1 0  0 1 0  0 0 -1</VertexData>
  <Objects>{objects}</Objects>
</Scene>"#
    )
}

fn load(xml: &str) -> (tempfile::TempDir, luster::scene::Description) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.xml");
    std::fs::File::create(&p).unwrap().write_all(xml.as_bytes()).unwrap();
    let d = luster::scene::load(&p).unwrap();
    (dir, d)
}

fn close(a: &Transform, b: &Transform) -> bool {
    a.matrix().abs_diff_eq(b.matrix(), 1e-5)
}

#[test]
fn instance_transforms_follow_reset_rules_through_chains() {
    let (_d, desc) = load(&scene(
        r#"<Mesh id="1"><Material>1</Material><Transformations>t1</Transformations><Faces>1 2 3</Faces></Mesh>
           <MeshInstance id="2" baseMeshId="1"><Material>2</Material><Transformations>r1</Transformations></MeshInstance>
           <MeshInstance id="3" baseMeshId="1" resetTransform="true"><Transformations>r1</Transformations></MeshInstance>
           <MeshInstance id="4" baseMeshId="2"><Transformations>s1</Transformations></MeshInstance>"#,
    ));
    let t1 = Transform::translation(Vec3::X);
    let r1 = Transform::rotation(90.0, Vec3::Z).unwrap();
    let s1 = Transform::scaling(Vec3::splat(2.0)).unwrap();
    let o = &desc.objects;
    // Not reset: the base's transform first, then the instance's own (R1 T1).
    assert!(close(&o[1].transform, &t1.then(&r1)));
    // Reset: only its own.
    assert!(close(&o[2].transform, &r1));
    // An instance of an instance composes all the way down (S1 R1 T1).
    assert!(close(&o[3].transform, &t1.then(&r1).then(&s1)));
    for (i, obj) in o.iter().enumerate().skip(1) {
        assert!(matches!(obj.shape, Shape::Instance { mesh: 0 }), "object {i}: {:?}", obj.shape);
    }
    // Material: its own when given, else inherited along the chain.
    assert_eq!(desc.materials[o[1].material].id, "2");
    assert_eq!(desc.materials[o[2].material].id, "1");
    assert_eq!(desc.materials[o[3].material].id, "2");
    // The point (1,-1,0) of the base moves to (1,-1,0)+t1 = (2,-1,0), rotated 90°: (1,2,0).
    assert!((o[1].transform.point(Vec3::new(1.0, -1.0, 0.0)) - Vec3::new(1.0, 2.0, 0.0)).length() < 1e-5);
}

#[test]
fn an_instance_renders_like_the_mesh_it_stands_for() {
    // A smooth tetrahedron as a mesh placed by "t1 r1", against a hidden base
    // mesh moved away and an instance that resets to "t1 r1".
    let faces = "1 2 3  1 4 2  2 4 3  3 4 1";
    let (_a, direct) = load(&scene(&format!(
        r#"<Mesh id="1" shadingMode="smooth"><Material>1</Material><Transformations>t1 r1</Transformations><Faces>{faces}</Faces></Mesh>"#
    )));
    let (_b, via_instance) = load(&scene(&format!(
        r#"<Mesh id="1" shadingMode="smooth"><Material>2</Material><Transformations>s1 t1 s1 s1 s1 s1</Transformations><Faces>{faces}</Faces></Mesh>
           <MeshInstance id="2" baseMeshId="1" resetTransform="true"><Material>1</Material><Transformations>t1 r1</Transformations></MeshInstance>"#
    )));
    let a = render(&Scene::build(&direct).unwrap(), 0, &|_| {}).to_rgb8();
    // The moved-away base is behind the camera, out of view: only the instance shows.
    let mut d2 = via_instance.clone();
    d2.objects[0].transform = Transform::translation(Vec3::new(0.0, 0.0, 100.0));
    let b = render(&Scene::build(&d2).unwrap(), 0, &|_| {}).to_rgb8();
    assert!(a.iter().any(|&c| c > 0), "the direct render is empty");
    assert_eq!(a, b);
}

#[test]
fn renders_do_not_depend_on_the_thread_count() {
    let (_d, desc) = load(&scene(
        r#"<Mesh id="1" shadingMode="smooth"><Material>1</Material><Faces>1 2 3  1 4 2  2 4 3  3 4 1</Faces></Mesh>
           <Sphere id="1"><Material>2</Material><Center>4</Center><Radius>0.5</Radius></Sphere>"#,
    ));
    let s = Scene::build(&desc).unwrap();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let a = one.install(|| render(&s, 0, &|_| {}).to_rgb8());
    let b = two.install(|| render(&s, 0, &|_| {}).to_rgb8());
    assert_eq!(a, b);
}
