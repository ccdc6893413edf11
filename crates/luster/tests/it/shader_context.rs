//! The shading context end to end: `s.P` is each object's own space for a
//! transformed sphere, an inline mesh, a `MeshInstance` of it and an OBJ
//! mesh; `s.Pc`, `s.V`, `s.Ng`, `s.depth` and `s.filterwidth` agree with the
//! camera; instances share `s.object_id` and differ in `s.instance_id` and
//! `s.random`. The shader raises an error at the first inconsistency, which
//! fails the render.

use crate::common;
use common::folder;
use luster::render::{try_render_with, RenderOptions, Scene};
use std::collections::BTreeSet;

const CHECK: &str = r#"params { shape = "cube", eye = vec3(0, 0, 0) }
local abs, max = math.abs, math.max
function color(s)
  if param.shape == "cube" then
    if max(abs(s.P.x), abs(s.P.y), abs(s.P.z)) > 0.5001 then error("P off the unit cube: " .. tostring(s.P)) end
  elseif abs(length(s.P) - 1) > 1e-3 then
    error("P off the unit sphere: " .. tostring(s.P))
  end
  local d = length(s.Pw - param.eye)
  if abs(length(s.Pc) - d) > 1e-3 * d or s.Pc.z >= 0 then error("Pc is not camera space: " .. tostring(s.Pc)) end
  if abs(dot(s.I, normalize(s.Pw - param.eye)) - 1) > 1e-3 then error("I is not the view ray") end
  if dot(s.V, s.Ng) <= 0 then error("a camera ray sees a back face") end
  if s.depth ~= 0 then error("depth " .. s.depth) end
  -- At least half a pixel at this distance (FovY 40, 80 rows), in object
  -- units (scaled by at most 1.5); at most 20 times that where the surface
  -- turns away.
  local pixel = -s.Pc.z * 2 * math.tan(math.rad(20)) / 80
  if not (s.filterwidth > 0.5 * pixel / 1.5 and s.filterwidth < 20 * pixel / 0.7 * 1.2) then
    error("filterwidth " .. s.filterwidth)
  end
  return 255, 255 * s.random, 50 * s.object_id
end"#;

const CUBE_OBJ: &str = "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n\
v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n\
f 5 6 7 8\nf 2 1 4 3\nf 6 2 3 7\nf 1 5 8 4\nf 8 7 3 4\nf 1 2 6 5\n";

const SCENE: &str = r#"<Scene>
    <BackgroundColor>0 0 0</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0.5 2 9</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
            <FovY>40</FovY><NearDistance>1</NearDistance>
            <ImageResolution>120 80</ImageResolution><ImageName>out.png</ImageName>
        </Camera>
    </Cameras>
    <Lights><AmbientLight>0 0 0</AmbientLight></Lights>
    <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
    <Textures>
        <TextureMap id="1" type="shader">
            <Shader>check.lua</Shader><DecalMode>replace_all</DecalMode>
            <Parameter name="shape">sphere</Parameter><Parameter name="eye">0.5 2 9</Parameter>
        </TextureMap>
        <TextureMap id="2" type="shader">
            <Shader>check.lua</Shader><DecalMode>replace_all</DecalMode>
            <Parameter name="eye">0.5 2 9</Parameter>
        </TextureMap>
    </Textures>
    <Transformations>
        <Translation id="1">-3 0 0</Translation>
        <Translation id="2">-1 0.5 0</Translation>
        <Translation id="3">1 -0.5 0</Translation>
        <Translation id="4">3 0 0</Translation>
        <Scaling id="1">1.2 0.7 1</Scaling>
        <Scaling id="2">1.5 1.5 1.5</Scaling>
        <Rotation id="1">35 1 2 0</Rotation>
    </Transformations>
    <VertexData>0 0 0
        -0.5 -0.5 -0.5
        0.5 -0.5 -0.5
        0.5 0.5 -0.5
        -0.5 0.5 -0.5
        -0.5 -0.5 0.5
        0.5 -0.5 0.5
        0.5 0.5 0.5
        -0.5 0.5 0.5
    </VertexData>
    <Objects>
        <Sphere id="1"><Material>1</Material><Textures>1</Textures><Transformations>s1 r1 t1</Transformations>
            <Center>1</Center><Radius>1</Radius></Sphere>
        <Mesh id="2"><Material>1</Material><Textures>2</Textures><Transformations>r1 t2</Transformations>
            <Faces>6 7 8 6 8 9 3 2 5 3 5 4 7 3 4 7 4 8 2 6 9 2 9 5 9 8 4 9 4 5 2 3 7 2 7 6</Faces></Mesh>
        <MeshInstance id="3" baseMeshId="2" resetTransform="true">
            <Material>1</Material><Textures>2</Textures><Transformations>s2 r1 t3</Transformations>
        </MeshInstance>
        <Mesh id="4"><Material>1</Material><Textures>2</Textures><Transformations>s1 r1 t4</Transformations>
            <Faces objFile="cube.obj"/></Mesh>
    </Objects>
</Scene>"#;

#[test]
fn every_object_sees_its_own_space_and_ids() {
    let dir = folder(&[("scene.xml", SCENE), ("check.lua", CHECK), ("cube.obj", CUBE_OBJ)]);
    let desc = luster::scene::load(&dir.path().join("scene.xml")).expect("the scene loads");
    let s = Scene::build(&desc).expect("the scene builds");
    let img = match try_render_with(&s, 0, &RenderOptions::default(), &|_| {}) {
        Ok(img) => img.to_rgb8(),
        Err(e) => panic!("{e}"),
    };
    let shaded: Vec<&[u8]> = img.chunks(3).filter(|p| p[0] == 255).collect();
    let randoms: BTreeSet<u8> = shaded.iter().map(|p| p[1]).collect();
    let objects: BTreeSet<u8> = shaded.iter().map(|p| p[2]).collect();
    // Objects 0 (sphere), 1 (the mesh, and its instance 2), 3 (the OBJ mesh).
    assert_eq!(objects, BTreeSet::from([0, 50, 150]), "object ids");
    assert_eq!(randoms.len(), 4, "one random number per instance: {randoms:?}");
}
