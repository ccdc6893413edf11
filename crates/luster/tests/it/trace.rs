//! Rays from shaders in the renderer: `trace()` from a floor up to a
//! sphere against the analytic distance and normal per pixel;
//! `occlusion()` of a floor in the open (0), under a sphere that encloses
//! it (1) and beside a wall against the analytic cosine-weighted fraction
//! (statistically, over two renders); the same bytes on one and two
//! threads and from a split render; and the ray cap's error on the
//! command line (the script's line, exit code 2).

use crate::common::{self, folder, run_limited};
use luster::math::Vec3;
use luster::render::{try_render_with, RenderOptions, RenderedImage, Scene, TileSelection};
use std::process::Command;
use std::time::Duration;

const W: u32 = 48;
const H: u32 = 40;
/// The camera at `(0, 0, cz)` looking down −z, an image plane at
/// distance 1 spanning [−1.2, 1.2] × [−1, 1]; the floor `y = −1`.
const HALF_W: f32 = 1.2;
const FLOOR_Y: f32 = -1.0;
/// The sphere the floor traces up to: above the camera's horizon, so the
/// camera sees the floor unhidden.
const SPHERE: (Vec3, f32) = (Vec3::new(0.0, 1.5, -3.0), 1.5);

/// A scene of the floor carrying `script` (as `s.lua`, `replace_all`: the
/// pixel is its colour) and `objects`, seen from `(0, 0, cz)`.
fn scene(cz: f32, objects: &str) -> String {
    format!(
        r#"<Scene>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 {cz}</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-{HALF_W} {HALF_W} -1 1</NearPlane><NearDistance>1</NearDistance>
    <ImageResolution>{W} {H}</ImageResolution><ImageName>a.exr</ImageName></Camera></Cameras>
  <Lights><AmbientLight>0 0 0</AmbientLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
  <Textures><TextureMap id="1" type="shader"><Shader>s.lua</Shader><DecalMode>replace_all</DecalMode></TextureMap></Textures>
  <VertexData>0 {FLOOR_Y} 0  {} {} {}  0 0 0</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Textures>1</Textures><Point>1</Point><Normal>0 1 0</Normal></Plane>
    {objects}
  </Objects>
</Scene>"#,
        SPHERE.0.x, SPHERE.0.y, SPHERE.0.z
    )
}

/// The floor point the centre ray of pixel `(x, y)` meets, if any.
fn floor_point(x: u32, y: u32, cz: f32) -> Option<Vec3> {
    let d = Vec3::new(
        -HALF_W + (x as f32 + 0.5) * 2.0 * HALF_W / W as f32,
        1.0 - (y as f32 + 0.5) * 2.0 / H as f32,
        -1.0,
    );
    (d.y < 0.0).then(|| Vec3::new(0.0, 0.0, cz) + d * (FLOOR_Y / d.y))
}

fn render(text: &str, script: &str, opts: &RenderOptions) -> RenderedImage {
    let dir = folder(&[("s.xml", text), ("s.lua", script)]);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("the scene loads");
    let s = Scene::build(&desc).expect("the scene builds");
    try_render_with(&s, 0, opts, &|_| {}).unwrap_or_else(|e| panic!("{e}"))
}

const SPHERE_XML: &str =
    r#"<Sphere id="2"><Material>1</Material><Center>2</Center><Radius>1.5</Radius></Sphere>"#;

#[test]
fn trace_finds_the_sphere_above_the_floor_where_geometry_says() {
    // Straight up from each floor point: the distance and the normal where
    // the ray meets the sphere, the sphere's ids, or nothing (0).
    let script = "function color(s)
  local h = trace(s.Pw, vec3(0, 1, 0))
  if h == nil then return 0, 0, 0 end
  if h.instance_id ~= 1 or h.object_id ~= 1 then error('ids ' .. h.object_id .. ' ' .. h.instance_id) end
  if math.abs(length(h.P - s.Pw) - h.t) > 1e-4 then error('P is not t along the ray') end
  return h.t, h.N.x + 2, h.N.z + 2
end";
    let img = render(&scene(0.0, SPHERE_XML), script, &RenderOptions::default());
    let (c, r) = SPHERE;
    let (mut hits, mut misses) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            let Some(p) = floor_point(x, y, 0.0) else { continue };
            let got = img.pixels[(y * W + x) as usize];
            let rim = r * r - (p.x - c.x).powi(2) - (p.z - c.z).powi(2);
            if rim.abs() < 0.02 {
                continue;
            }
            if rim < 0.0 {
                assert_eq!(got, Vec3::ZERO, "pixel ({x}, {y}) at {p} should miss");
                misses += 1;
                continue;
            }
            let hit_y = c.y - rim.sqrt();
            let t = hit_y - FLOOR_Y;
            let n = (Vec3::new(p.x, hit_y, p.z) - c) / r;
            assert!((got.x - t).abs() < 1e-4 * t.max(1.0), "pixel ({x}, {y}): t {} for {t}", got.x);
            assert!((got.y - 2.0 - n.x).abs() < 1e-3, "pixel ({x}, {y}): N.x {} for {}", got.y - 2.0, n.x);
            assert!((got.z - 2.0 - n.z).abs() < 1e-3, "pixel ({x}, {y}): N.z {} for {}", got.z - 2.0, n.z);
            hits += 1;
        }
    }
    assert!(hits > 100 && misses > 100, "{hits} hits, {misses} misses");
}

#[test]
fn occlusion_is_zero_in_the_open_and_one_inside_a_closed_surface() {
    let script = "function color(s) return occlusion(s, 64), 0, 0 end";
    let open = render(&scene(0.0, ""), script, &RenderOptions::default());
    let floor_pixels = |img: &RenderedImage| -> Vec<f32> {
        (0..H)
            .flat_map(|y| (0..W).map(move |x| (x, y)))
            .filter(|&(x, y)| floor_point(x, y, 0.0).is_some_and(|p| p.length() < 40.0))
            .map(|(x, y)| img.pixels[(y * W + x) as usize].x)
            .collect()
    };
    let v = floor_pixels(&open);
    assert!(v.len() > 500 && v.iter().all(|&o| o == 0.0), "{v:?}");
    // A sphere of radius 50 around the camera and the floor it sees.
    let big = r#"<Sphere id="2"><Material>1</Material><Center>3</Center><Radius>50</Radius></Sphere>"#;
    let shut = render(&scene(0.0, big), script, &RenderOptions::default());
    let v = floor_pixels(&shut);
    assert!(v.len() > 500 && v.iter().all(|&o| o == 1.0), "{v:?}");
}

/// The cosine-weighted fraction of a floor point's hemisphere whose rays
/// meet a wall `d` away within `reach`: the directions project uniformly
/// onto the unit disc, and those with a component towards the wall over
/// `d / reach` meet it, a segment of the disc.
fn wall_fraction(d: f64, reach: f64) -> f64 {
    let a = (d / reach).min(1.0);
    (a.acos() - a * (1.0 - a * a).sqrt()) / std::f64::consts::PI
}

/// The wall `x = 0.6`, facing −x: the floor's pixels left of it lie in
/// the corner between the two.
const WALL_XML: &str =
    r#"<Plane id="2"><Material>1</Material><Point>3</Point><Normal>-1 0 0</Normal></Plane>"#;
const WALL_X: f32 = 0.6;
const REACH: f64 = 1.5;

fn corner(cz: f32, opts: &RenderOptions) -> RenderedImage {
    let text = scene(cz, WALL_XML).replace("0 0 0</VertexData>", &format!("{WALL_X} 0 0</VertexData>"));
    let script = format!("function color(s) return occlusion(s, 16, {REACH}), {WALL_X} - s.Pw.x, 0 end");
    render(&text, &script, opts)
}

#[test]
fn occlusion_in_a_corner_matches_the_analytic_fraction() {
    // Two renders, the camera moved along the wall between them: each
    // floor point gets its own rotation of the direction set, so the
    // errors are independent, and their differences measure their spread.
    let errors = |cz: f32| -> Vec<f64> {
        let img = corner(cz, &RenderOptions::default());
        let mut e = Vec::new();
        for y in 0..H {
            for x in 0..W {
                let Some(p) = floor_point(x, y, cz) else { continue };
                if p.x >= WALL_X || p.length() > 30.0 {
                    continue;
                }
                let got = img.pixels[(y * W + x) as usize];
                // The shader's distance to the wall is the point's.
                assert!((f64::from(got.y) - f64::from(WALL_X - p.x)).abs() < 1e-4);
                e.push(f64::from(got.x) - wall_fraction(f64::from(got.y), REACH));
            }
        }
        e
    };
    let (a, b) = (errors(0.0), errors(-0.37));
    let n = a.len().min(b.len());
    assert!(n > 400, "{n} floor pixels");
    let (mean, se) = common::two_seed_mean(&a[..n], &b[..n]);
    assert!(mean.abs() < 4.0 * se, "mean error {mean} (standard error {se})");
    // Each estimate is a fraction of 16 stratified directions.
    let worst = a.iter().chain(&b).fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(worst < 0.25, "largest error {worst}");
    assert!(se < 0.01, "standard error {se}");
}

#[test]
fn occlusion_is_the_same_on_one_and_two_threads_and_in_parts() {
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("a thread pool");
    let opts = RenderOptions { spp: Some(2), ..RenderOptions::default() };
    let one = pool(1).install(|| corner(0.0, &opts));
    let two = pool(2).install(|| corner(0.0, &opts));
    assert_eq!(one.pixels, two.pixels);
    // Two parts, every other tile each: each tile's pixels as in the whole.
    let tiles = luster::render::tile_origins(W, H);
    for first in 0..2 {
        let sel = TileSelection { first, step: 2, end: tiles.len() as u32 };
        let part = pool(2).install(|| corner(0.0, &RenderOptions { tiles: Some(sel), ..opts }));
        for (i, &o) in tiles.iter().enumerate().filter(|&(i, _)| sel.contains(i as u32)) {
            let (x0, y0, x1, y1) = luster::render::tile_rect(W, H, o);
            for y in y0..y1 {
                for x in x0..x1 {
                    let k = (y * W + x) as usize;
                    assert_eq!(part.pixels[k], one.pixels[k], "tile {i}, pixel ({x}, {y})");
                }
            }
        }
    }
}

#[test]
fn rays_past_the_cap_stop_the_render_naming_the_line() {
    let script = "function color(s)\n  local n = 0\n  for i = 1, 300 do\n    if trace(s.Pw, s.N) then n = n + 1 end\n  end\n  return n, 0, 0\nend\n";
    let dir = folder(&[("s.xml", &scene(0.0, "")), ("s.lua", script)]);
    let out = dir.path().join("out");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(["render", "-q", "-o"]).arg(&out).arg(dir.path().join("s.xml"));
    let run = run_limited(cmd, Duration::from_secs(60));
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    let line = run.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    for word in ["s.lua:4", "trace:", "cap of 256 rays per shader call", "Plane[id=1]"] {
        assert!(line.contains(word), "{word:?} missing from {line:?}");
    }
    assert!(!out.join("a.exr").exists(), "an image was written");
}

#[test]
fn a_bevel_normal_map_rounds_a_cubes_edges_for_the_maps_after_it() {
    // A unit cube 2 in front of the camera: its face z = -1.5 fills the
    // middle of the image. Map 1 rounds its edges over 0.15, map 2 shows
    // the normal it then sees.
    let cube = r#"<Scene>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1.2 1.2 -1 1</NearPlane><NearDistance>1</NearDistance>
    <ImageResolution>48 40</ImageResolution><ImageName>a.exr</ImageName></Camera></Cameras>
  <Lights><AmbientLight>0 0 0</AmbientLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
  <Textures>
    <TextureMap id="1" type="shader"><Shader>round.lua</Shader><DecalMode>replace_normal</DecalMode></TextureMap>
    <TextureMap id="2" type="shader"><Shader>s.lua</Shader><DecalMode>replace_all</DecalMode></TextureMap>
  </Textures>
  <Transformations><Translation id="1">0 0 -2</Translation></Transformations>
  <VertexData>-0.5 -0.5 -0.5  0.5 -0.5 -0.5  0.5 0.5 -0.5  -0.5 0.5 -0.5
    -0.5 -0.5 0.5  0.5 -0.5 0.5  0.5 0.5 0.5  -0.5 0.5 0.5</VertexData>
  <Objects>
    <Mesh id="1"><Material>1</Material><Textures>1 2</Textures><Transformations>t1</Transformations>
      <Faces>5 6 7 5 7 8 2 1 4 2 4 3 6 2 3 6 3 7 1 5 8 1 8 4 8 7 3 8 3 4 1 2 6 1 6 5</Faces></Mesh>
  </Objects>
</Scene>"#;
    let dir = folder(&[
        ("s.xml", cube),
        ("round.lua", "function normal(s) return bevel(s, 0.15, 64) end"),
        ("s.lua", "function color(s) return s.N.x + 2, s.N.y + 2, s.N.z + 2 end"),
    ]);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("the scene loads");
    let img = try_render_with(&Scene::build(&desc).expect("builds"), 0, &RenderOptions::default(), &|_| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let (mut flat, mut rounded) = (0, 0);
    for y in 0..H {
        for x in 0..W {
            // Where the centre ray meets the face's plane, in the face's
            // own coordinates.
            let fx = (-HALF_W + (x as f32 + 0.5) * 2.0 * HALF_W / W as f32) * 1.5;
            let fy = (1.0 - (y as f32 + 0.5) * 2.0 / H as f32) * 1.5;
            if fx.abs() > 0.49 || fy.abs() > 0.49 {
                continue;
            }
            let n = img.pixels[(y * W + x) as usize] - Vec3::splat(2.0);
            assert!((n.length() - 1.0).abs() < 1e-4, "pixel ({x}, {y}): {n}");
            if fx.abs().max(fy.abs()) < 0.3 {
                // Farther than the radius from every edge: the face's own normal.
                assert!((n.z - 1.0).abs() < 1e-5, "pixel ({x}, {y}) at ({fx}, {fy}): {n}");
                flat += 1;
            } else if fx.abs() > 0.42 && fy.abs() < 0.3 {
                // Near a vertical edge: tilted towards it, and only across it.
                assert!(
                    n.x * fx.signum() > 0.1 && n.y.abs() < 0.1 && n.z > 0.5,
                    "pixel ({x}, {y}) at ({fx}, {fy}): {n}"
                );
                rounded += 1;
            }
        }
    }
    assert!(flat > 50 && rounded > 8, "{flat} flat, {rounded} rounded pixels");
}
