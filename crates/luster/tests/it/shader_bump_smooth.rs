//! A bump shader whose `height` is flat must leave every surface exactly as
//! it is without the map: on a sphere, a smooth-shaded mesh, an OBJ mesh with
//! its own normals and an instance of the smooth mesh. A bumped normal built
//! from the flat triangle's tangents instead of the interpolated normal would
//! turn the meshes faceted.

use crate::common;
use common::folder;
use luster::render::{try_render_with, RenderOptions, Scene};
use std::fmt::Write as _;
use std::path::Path;

/// A coarse UV sphere of radius 0.8: (positions, triangles as 0-based indices).
fn coarse_sphere() -> (Vec<[f32; 3]>, Vec<[usize; 3]>) {
    let (rings, segments) = (6usize, 8usize);
    let mut pos = vec![[0.0, 0.8, 0.0]];
    for i in 1..rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let ph = std::f32::consts::TAU * j as f32 / segments as f32;
            pos.push([0.8 * th.sin() * ph.cos(), 0.8 * th.cos(), 0.8 * th.sin() * ph.sin()]);
        }
    }
    pos.push([0.0, -0.8, 0.0]);
    let last = pos.len() - 1;
    let at = |i: usize, j: usize| 1 + (i - 1) * segments + j % segments;
    let mut tris = Vec::new();
    for j in 0..segments {
        tris.push([0, at(1, j + 1), at(1, j)]);
        tris.push([last, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            tris.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    (pos, tris)
}

/// The OBJ file of the coarse sphere, with exact sphere normals.
fn obj_text() -> String {
    let (pos, tris) = coarse_sphere();
    let mut s = String::new();
    for p in &pos {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for p in &pos {
        let _ = writeln!(s, "vn {} {} {}", p[0] / 0.8, p[1] / 0.8, p[2] / 0.8);
    }
    for t in &tris {
        let _ = writeln!(s, "f {0}//{0} {1}//{1} {2}//{2}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// Four objects in a row; `textures` is the `<Textures>` element each gets.
fn scene(textures: &str) -> String {
    let (pos, tris) = coarse_sphere();
    let sphere_center = pos.len() + 1;
    let vertices: String = pos.iter().map(|p| format!("{} {} {}\n", p[0], p[1], p[2])).collect();
    let faces: String = tris.iter().map(|t| format!("{} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1)).collect();
    format!(
        r#"<Scene>
    <BackgroundColor>10 10 10</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0 1 7</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
            <FovY>40</FovY><NearDistance>1</NearDistance>
            <ImageResolution>160 60</ImageResolution><ImageName>out.png</ImageName>
        </Camera>
    </Cameras>
    <Lights>
        <AmbientLight>20 20 20</AmbientLight>
        <PointLight id="1"><Position>2 4 6</Position><Intensity>20000 20000 20000</Intensity></PointLight>
    </Lights>
    <Materials>
        <Material id="1">
            <AmbientReflectance>1 1 1</AmbientReflectance>
            <DiffuseReflectance>0.6 0.5 0.4</DiffuseReflectance>
            <SpecularReflectance>0.5 0.5 0.5</SpecularReflectance>
            <PhongExponent>30</PhongExponent>
        </Material>
    </Materials>
    <Textures>
        <TextureMap id="1" type="shader">
            <Shader>flat.lua</Shader>
            <DecalMode>bump_normal</DecalMode>
            <BumpFactor>3</BumpFactor>
        </TextureMap>
    </Textures>
    <Transformations>
        <Translation id="1">-2.7 0 0</Translation>
        <Translation id="2">-0.9 0 0</Translation>
        <Translation id="3">0.9 0 0</Translation>
        <Translation id="4">2.7 0 0</Translation>
        <Rotation id="1">30 1 1 0</Rotation>
        <Scaling id="1">1 0.7 1.2</Scaling>
    </Transformations>
    <VertexData>{vertices}-2.7 0 0
    </VertexData>
    <Objects>
        <Sphere id="1"><Material>1</Material>{textures}<Center>{sphere_center}</Center><Radius>0.8</Radius></Sphere>
        <Mesh id="2" shadingMode="smooth">
            <Material>1</Material>{textures}<Transformations>t2</Transformations>
            <Faces>{faces}</Faces>
        </Mesh>
        <Mesh id="3"><Material>1</Material>{textures}<Transformations>r1 t3</Transformations>
            <Faces objFile="sphere.obj"/></Mesh>
        <MeshInstance id="4" baseMeshId="2" resetTransform="true">
            <Material>1</Material>{textures}<Transformations>s1 r1 t4</Transformations>
        </MeshInstance>
    </Objects>
</Scene>"#
    )
}

fn render(path: &Path) -> Vec<u8> {
    let desc = luster::scene::load(path).expect("the scene loads");
    let s = Scene::build(&desc).expect("the scene builds");
    try_render_with(&s, 0, &RenderOptions::default(), &|_| {}).expect("no shader fails").to_rgb8()
}

fn renders(height_lua: &str) -> (Vec<u8>, Vec<u8>) {
    let obj = obj_text();
    let dir = folder(&[
        ("plain.xml", &scene("")),
        ("bumped.xml", &scene("<Textures>1</Textures>")),
        ("sphere.obj", &obj),
        ("flat.lua", height_lua),
    ]);
    (render(&dir.path().join("plain.xml")), render(&dir.path().join("bumped.xml")))
}

/// Zero and constant heights: the same bytes as no bump map at all.
#[test]
fn a_flat_height_leaves_smooth_surfaces_unchanged() {
    for code in ["function height(s) return 0 end", "function height(s) return 0.25 end"] {
        let (plain, bumped) = renders(code);
        let differing = plain.chunks(3).zip(bumped.chunks(3)).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{code}: {differing} of {} pixels differ", plain.len() / 3);
    }
}

/// The comparison can fail: a real bump changes the same scene.
#[test]
fn a_sloped_height_changes_the_image() {
    let (plain, bumped) = renders("function height(s) return 0.05 * math.sin(20 * s.P.y) end");
    let differing = plain.chunks(3).zip(bumped.chunks(3)).filter(|(a, b)| a != b).count();
    assert!(differing * 20 > plain.len() / 3, "only {differing} pixels differ");
}
