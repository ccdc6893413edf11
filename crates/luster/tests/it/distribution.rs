//! Distribution ray tracing: the image must not depend on the thread count
//! (volumes included),
//! the area-light estimate must converge as samples grow, and a moving object
//! must be found along its whole path (the BVH's swept bounds).

use luster::render::{render_with, Filter, RenderOptions, RenderedImage, Scene};
use luster::scene::Description;
use std::io::Write;

/// A small box-like scene: a floor and a back wall, a glossy sphere, a sphere
/// moving sideways, an area light overhead and a thin-lens camera.
fn scene(extra_camera: &str, objects: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>3</MaxRecursionDepth>
  <Cameras><Camera id="1"><Position>0 1 6</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>2</NearDistance>{extra_camera}
    <ImageResolution>48 48</ImageResolution><NumSamples>4</NumSamples><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>5 5 5</AmbientLight>
    <AreaLight id="1"><Position>0 3 0</Position><Normal>0 -1 0</Normal><Size>2</Size><Radiance>600 600 600</Radiance></AreaLight></Lights>
  <Materials>
    <Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance></Material>
    <Material id="2" type="mirror"><DiffuseReflectance>0.1 0.1 0.1</DiffuseReflectance>
      <MirrorReflectance>0.8 0.8 0.8</MirrorReflectance><Roughness>0.2</Roughness></Material>
  </Materials>
  <VertexData>-4 0 4  4 0 4  4 0 -4  -4 0 -4  -4 4 -4  4 4 -4  -0.8 0.6 0  0.9 0.5 0.5</VertexData>
  <Objects>
    <Mesh id="1"><Material>1</Material><Faces>1 2 3  1 3 4  4 3 6  4 6 5</Faces></Mesh>
    {objects}
  </Objects>
</Scene>"#
    )
}

fn load(xml: &str) -> (tempfile::TempDir, Description) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.xml");
    std::fs::File::create(&p).unwrap().write_all(xml.as_bytes()).unwrap();
    let d = luster::scene::load(&p).unwrap();
    (dir, d)
}

fn rgb(img: &RenderedImage) -> Vec<f32> {
    img.pixels.iter().flat_map(|p| p.to_array()).collect()
}

fn rms(a: &[f32], b: &[f32]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn every_effect_renders_identically_on_one_and_two_threads() {
    let (_d, desc) = load(&scene(
        "<ApertureSize>0.3</ApertureSize><FocusDistance>6</FocusDistance>",
        r#"<Sphere id="1"><Material>2</Material><Center>7</Center><Radius>0.6</Radius></Sphere>
           <Sphere id="2"><Material>1</Material><Center>8</Center><Radius>0.5</Radius><MotionBlur>0.8 0 0</MotionBlur></Sphere>"#,
    ));
    let s = Scene::build(&desc).unwrap();
    for filter in [Filter::Box, Filter::Gaussian] {
        let opts = RenderOptions { spp: Some(9), seed: 3, filter, ..Default::default() };
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let a = one.install(|| render_with(&s, 0, &opts, &|_| {}));
        let b = two.install(|| render_with(&s, 0, &opts, &|_| {}));
        assert_eq!(rgb(&a), rgb(&b), "{filter:?}");
        // Another seed is other noise around the same image.
        let c = render_with(&s, 0, &RenderOptions { seed: 4, ..opts }, &|_| {});
        assert_ne!(rgb(&a), rgb(&c));
    }
}

/// Volumes draw jitter and light samples from the pixel's sampler and run
/// scripts in per-thread Lua states: the image must still not depend on the
/// thread count.
#[test]
fn volumes_render_identically_on_one_and_two_threads() {
    let volumes = r#"<Volumes>
        <Volume id="fog"><Sphere><Center>0.3 1.2 0</Center><Radius>0.9</Radius></Sphere><Shader>fog.lua</Shader>
          <Absorption>0.2 0.2 0.2</Absorption><Scattering>1.5 1.5 1.5</Scattering><Anisotropy>0.4</Anisotropy></Volume>
        <Hypertexture id="ball"><Sphere><Center>-1 0.7 0.5</Center><Radius>0.7</Radius></Sphere><Material>1</Material>
          <Shader>fuzz.lua</Shader></Hypertexture>
      </Volumes></Scene>"#;
    let xml = scene("", "").replace("</Scene>", volumes);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.xml"), xml).unwrap();
    std::fs::write(
        dir.path().join("fog.lua"),
        "function density(s) return 0.5 + 0.5 * fbm(s.P.x * 3, s.P.y * 3, s.P.z * 3, 3) end",
    )
    .unwrap();
    std::fs::write(dir.path().join("fuzz.lua"), "function density(s) return 1 - length(s.P) / 0.6 + 0.3 * turbulence(s.P.x * 4, s.P.y * 4, s.P.z * 4, 3) end").unwrap();
    let desc = luster::scene::load(&dir.path().join("s.xml")).unwrap();
    let s = Scene::build(&desc).unwrap();
    let opts = RenderOptions { spp: Some(4), seed: 1, ..Default::default() };
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let a = one.install(|| render_with(&s, 0, &opts, &|_| {}));
    let b = two.install(|| render_with(&s, 0, &opts, &|_| {}));
    assert_eq!(rgb(&a), rgb(&b));
    // The volumes are in the picture (the test is not of an empty room).
    let (_d, plain) = load(&scene("", ""));
    let without = render_with(&Scene::build(&plain).unwrap(), 0, &opts, &|_| {});
    assert!(rms(&rgb(&a), &rgb(&without)) > 1.0);
}

#[test]
fn area_light_error_falls_with_the_sample_count() {
    let (_d, desc) = load(&scene("", ""));
    let s = Scene::build(&desc).unwrap();
    let at = |spp: u32, seed: u32| {
        rgb(&render_with(&s, 0, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {}))
    };
    let reference = at(1024, 99);
    let errors: Vec<f64> = [4u32, 16, 64]
        .iter()
        .map(|&n| (0..3).map(|seed| rms(&at(n, seed), &reference)).sum::<f64>() / 3.0)
        .collect();
    // Independent sampling would halve the error for every 4× the samples
    // (1/√N); stratification may do better, never worse.
    assert!(errors[0] / errors[1] > 1.8, "{errors:?}");
    assert!(errors[1] / errors[2] > 1.8, "{errors:?}");
}

#[test]
fn a_moving_sphere_is_found_along_its_whole_path() {
    // The sphere starts far left, outside the view, and ends in the middle:
    // only swept bounds let the BVH find it there.
    let (_d, moving) = load(&scene(
        "",
        r#"<Sphere id="2"><Material>1</Material><Center>7</Center><Radius>0.4</Radius><MotionBlur>-6 0 0</MotionBlur>
           <Transformations>t1</Transformations></Sphere>"#,
    )
    .replace("<VertexData>", "<Transformations><Translation id=\"1\">6.8 0 0</Translation></Transformations><VertexData>"));
    let s = Scene::build(&moving).unwrap();
    let img = render_with(&s, 0, &RenderOptions { spp: Some(64), ..Default::default() }, &|_| {});
    let (_e, still) = load(&scene("", ""));
    let empty = render_with(
        &Scene::build(&still).unwrap(),
        0,
        &RenderOptions { spp: Some(64), ..Default::default() },
        &|_| {},
    );
    // The sphere's streak covers the centre of the image at some times: the
    // pixel differs from the empty room, but is not the sphere's full colour
    // either (it is there only part of the shutter interval).
    let centre = (24 * 48 + 24) as usize;
    let (a, b) = (img.pixels[centre], empty.pixels[centre]);
    assert!((a - b).length() > 1.0, "moving sphere not seen at the centre: {a:?} vs {b:?}");
}
