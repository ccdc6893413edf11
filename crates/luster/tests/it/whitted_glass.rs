//! The recursive integrator's shortcuts at clear glass: a dielectric that
//! reflects no direct light traces no shadow rays, yet the image is the one
//! the full computation gives (its light samples are still drawn, so every
//! later random draw is where it was).

use luster::render::{render_with, RenderOptions, RenderedImage, Scene};
use std::io::Write;

/// A diffuse floor and back wall under an area light, seen through a glass
/// sphere whose diffuse reflectance is `glass_diffuse`.
fn scene(glass_diffuse: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>6</MaxRecursionDepth>
  <Cameras><Camera id="1"><Position>0 1 6</Position><Gaze>0 -0.1 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>2</NearDistance>
    <ImageResolution>40 40</ImageResolution><NumSamples>4</NumSamples><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>5 5 5</AmbientLight>
    <AreaLight id="1"><Position>0.5 3 1</Position><Normal>0 -1 0</Normal><Size>2</Size><Radiance>600 600 600</Radiance></AreaLight></Lights>
  <Materials>
    <Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance></Material>
    <Material id="2" type="dielectric"><DiffuseReflectance>{glass_diffuse}</DiffuseReflectance>
      <AbsorptionCoefficient>0.05 0.05 0.05</AbsorptionCoefficient><RefractionIndex>1.5</RefractionIndex></Material>
  </Materials>
  <VertexData>-4 0 4  4 0 4  4 0 -4  -4 0 -4  -4 4 -4  4 4 -4  0 0.9 0.5</VertexData>
  <Objects>
    <Mesh id="1"><Material>1</Material><Faces>1 2 3  1 3 4  4 3 6  4 6 5</Faces></Mesh>
    <Sphere id="1"><Material>2</Material><Center>7</Center><Radius>0.9</Radius></Sphere>
  </Objects>
</Scene>"#
    )
}

fn render(xml: &str, spp: u32) -> RenderedImage {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("s.xml");
    std::fs::File::create(&p).unwrap().write_all(xml.as_bytes()).unwrap();
    let desc = luster::scene::load(&p).unwrap();
    let s = Scene::build(&desc).unwrap();
    render_with(&s, 0, &RenderOptions { spp: Some(spp), seed: 5, ..Default::default() }, &|_| {})
}

#[test]
fn clear_glass_traces_no_shadow_rays_and_renders_as_if_it_did() {
    for spp in [1, 4] {
        // Clear glass, and glass with a diffuse part too small to change a
        // single float of the image but large enough that its shadow rays
        // are traced.
        let clear = render(&scene("0 0 0"), spp);
        let faint = render(&scene("1e-30 1e-30 1e-30"), spp);
        assert!(
            clear.stats.shadow < faint.stats.shadow,
            "{spp} spp: clear glass traced {} shadow rays, faint glass {}",
            clear.stats.shadow,
            faint.stats.shadow
        );
        // Every pixel equal: had the skipped light samples not been drawn,
        // the floor's area-light samples seen through the glass would come
        // from other dimensions and differ by their noise.
        let worst = clear
            .pixels
            .iter()
            .zip(&faint.pixels)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0, f32::max);
        assert!(worst <= 1e-4, "{spp} spp: pixels differ by up to {worst}");
        let seen_through = clear.pixels.iter().filter(|p| p.max_element() > 1.0).count();
        assert!(seen_through > clear.pixels.len() / 2, "the test scene is too dark to tell");
    }
}
