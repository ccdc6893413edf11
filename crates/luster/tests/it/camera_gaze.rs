//! The 2022 course files write look-at cameras with a `<Gaze>` direction
//! instead of a `<GazePoint>`: both forms must describe the same view, and a
//! left-handed camera is refused rather than silently mirrored.

use luster::scene::description::Projection;
use std::io::Write;

fn camera(view: &str, attrs: &str) -> String {
    format!(
        r#"<Scene>
  <Cameras><Camera id="1" type="lookAt"{attrs}><Position>1 2 3</Position>{view}<Up>0 1 0</Up>
    <FovY>45</FovY><NearDistance>0.1</NearDistance>
    <ImageResolution>8 8</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#
    )
}

fn load(xml: &str) -> Result<luster::scene::Description, luster::scene::SceneError> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.xml");
    std::fs::File::create(&p).unwrap().write_all(xml.as_bytes()).unwrap();
    luster::scene::load(&p)
}

fn gaze_point(xml: &str) -> [f32; 3] {
    let d = load(xml).unwrap();
    match d.cameras[0].projection {
        Projection::LookAt { gaze_point, .. } => gaze_point.to_array(),
        _ => panic!("a lookAt camera must give a look-at projection"),
    }
}

#[test]
fn a_gaze_direction_names_the_same_view_as_a_gaze_point() {
    let by_point = gaze_point(&camera("<GazePoint>1 2 -7</GazePoint>", ""));
    let by_direction = gaze_point(&camera("<Gaze>0 0 -10</Gaze>", r#" handedness="right""#));
    assert_eq!(by_point, [1.0, 2.0, -7.0]);
    assert_eq!(by_direction, by_point);
}

#[test]
fn a_left_handed_or_aimless_camera_is_refused() {
    let left =
        load(&camera("<GazePoint>0 0 0</GazePoint>", r#" handedness="left""#)).unwrap_err().to_string();
    assert!(left.contains("handedness") && left.contains("Camera"), "{left}");
    let zero = load(&camera("<Gaze>0 0 0</Gaze>", "")).unwrap_err().to_string();
    assert!(zero.contains("<Gaze> vector is zero"), "{zero}");
    let none = load(&camera("", "")).unwrap_err().to_string();
    assert!(none.contains("GazePoint"), "{none}");
}
