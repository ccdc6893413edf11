//! The light samples' fast path at a vertex of constant BRDF value
//! ([`next_event_diffuse`], with and without MIS, its light point drawn
//! ahead) against the general one ([`next_event_any`], drawing it in turn
//! or ahead): the same sum to the bit, the same draws and the same shadow
//! rays, at hits all over a box lit by a point light and a light box.

use super::*;
use crate::bsdf::Bsdf;
use crate::integrator::{surface_at, RayStats};
use crate::render::sampler::PixelSampler;
use luster_scene::description::LightSamples;

/// A box lit by a point light and a light box, every surface diffuse (also
/// read by `vertex_tests.rs`).
pub(in crate::integrator::path) const SCENE: &str = r#"<Scene>
  <MaxRecursionDepth>3</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 1.8</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>60</FovY><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams></Camera></Cameras>
  <Lights><PointLight id="1"><Position>0.5 1.5 0.5</Position><Intensity>2 2 2</Intensity></PointLight></Lights>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.7 0.6 0.5</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <VertexData>-2 -2 -2  2 -2 -2  2 2 -2  -2 2 -2  -2 -2 2  2 -2 2  2 2 2  -2 2 2
    0 -1.2 0
    -0.3 1.7 -0.3  0.3 1.7 -0.3  0.3 1.7 0.3  -0.3 1.7 0.3  -0.3 2 -0.3  0.3 2 -0.3  0.3 2 0.3  -0.3 2 0.3</VertexData>
  <Objects>
    <Mesh id="1"><Material>1</Material><Faces>1 2 3 1 3 4  1 5 6 1 6 2  2 6 7 2 7 3  4 3 7 4 7 8  1 4 8 1 8 5</Faces></Mesh>
    <Sphere id="1"><Material>1</Material><Center>9</Center><Radius>0.6</Radius></Sphere>
    <LightMesh id="1"><Material>2</Material><Radiance>6 6 6</Radiance>
      <Faces>10 11 12 10 12 13  10 14 15 10 15 11  11 15 16 11 16 12  12 16 17 12 17 13  13 17 14 13 14 10</Faces></LightMesh>
  </Objects>
</Scene>"#;

/// The render scene of the scene file `text`.
pub(in crate::integrator::path) fn scene_of(text: &str) -> Scene {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("box.xml");
    std::fs::write(&path, text).expect("scene written");
    Scene::build(&luster_scene::load(&path).expect("scene loads")).expect("scene builds")
}

#[test]
fn the_constant_brdf_light_samples_are_the_general_ones() {
    let scene = scene_of(SCENE);
    let bits = |v: Vec3A| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let (mut lit, mut checked) = (0, 0);
    for mis in [false, true] {
        let p = PathParams { next_event: !mis, mis, lights: LightSamples::Auto, ..Default::default() };
        for k in 0..400u32 {
            // Rays from points in the box in directions spread over the sphere.
            let (a, b) = (k as f32 * 0.618_034, k as f32 * 0.381_966 + 0.1);
            let o = Vec3::new((a * 7.0).sin() * 1.5, (a * 5.0).cos() * 1.5, (b * 3.0).sin() * 1.5);
            let z = (b * 11.0).fract() * 2.0 - 1.0;
            let r = (1.0 - z * z).sqrt();
            let ray = Ray::new(o, Vec3::new(r * (a * 13.0).cos(), r * (a * 13.0).sin(), z));
            let Some(hit) = scene.intersect(&ray, 0.0, false) else { continue };
            let mut st = PathState::new(RayStats::default(), 0.0, PixelSampler::new(3, k % 8, k / 8, 0, 16));
            st.sampler.restart(k % 16);
            let Surface::Lit(m, ns) = surface_at(&scene, &ray, &hit, 1, &mut st) else { continue };
            if !m.traits.reflects {
                continue;
            }
            let entering = ray.d.dot(hit.ng) < 0.0;
            let (n, ng) = if entering { (ns, hit.ng) } else { (-ns, -hit.ng) };
            let at = Bsdf::new(&m, n, ray.d);
            assert!(at.f.is_some() && m.traits.diffuse_only, "ray {k}: every surface is diffuse only");
            let origin = hit.p + ng * scene.offset(hit.p, ray.o);
            // The light box's point drawn ahead (as `shade` does), or in turn.
            let (mut fast, mut general, mut any) = (st.clone(), st.clone(), st);
            let ahead = LightAhead::draw(&scene, p, hit.p, &mut fast);
            assert!(ahead.is_some(), "ray {k}: the light box is the first light that draws");
            let a = if mis {
                next_event_diffuse::<true>(&scene, &hit, &at, origin, 1, p, ahead, &mut fast)
            } else {
                next_event_diffuse::<false>(&scene, &hit, &at, origin, 1, p, ahead, &mut fast)
            };
            let b = next_event_any(&scene, &hit, &at, origin, 1, p, None, &mut general);
            let ahead = LightAhead::draw(&scene, p, hit.p, &mut any);
            let c = next_event_any(&scene, &hit, &at, origin, 1, p, ahead, &mut any);
            assert_eq!(bits(b), bits(c), "ray {k}, MIS {mis}: drawn ahead");
            assert_eq!(any.sampler.calls(), general.sampler.calls(), "ray {k}: draws");
            assert_eq!(bits(a), bits(b), "ray {k}, MIS {mis}");
            assert_eq!(fast.stats.shadow, general.stats.shadow, "ray {k}, MIS {mis}: shadow rays");
            assert_eq!(
                fast.sampler.next_1d().to_bits(),
                general.sampler.next_1d().to_bits(),
                "ray {k}: draws"
            );
            checked += 1;
            lit += usize::from(a != Vec3A::ZERO);
        }
    }
    assert!(checked > 600 && lit > 300, "{checked} vertices checked, {lit} lit");
}
