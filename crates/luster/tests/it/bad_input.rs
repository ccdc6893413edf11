//! The bad-input corpus: every scene in `tests/bad_input/` holds one realistic
//! mistake, and `luster render` must refuse it with exit code 2, a one-line
//! error that names the file and the problem, no panic, and nothing written to
//! the output folder (no image, no temporary file).
//!
//! To add a case, drop the scene in `tests/bad_input/` (PLY files it needs go
//! in `tests/bad_input/ply/`, images in `tests/bad_input/textures/`, OBJ and
//! MTL files that scenes or models refer to in `tests/bad_input/obj/`; an
//! `.obj` case is rendered as a model) and add one line to [`CASES`]. A file in the
//! folder without a line in the table fails the test, so a scene that loads
//! fine cannot pass unnoticed.

use crate::common;

use common::{run_limited, Run};
use std::collections::BTreeSet;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Scene (relative to the corpus folder) → substrings the error must contain,
/// besides the scene's file name.
const CASES: &[(&str, &[&str])] = &[
    // Malformed files.
    ("unclosed_tag.xml", &["malformed XML", "line 13", "Camera"]),
    ("trailing_comma.json", &["malformed JSON", "line 31", "trailing comma"]),
    ("missing_brace.json", &["malformed JSON", "EOF"]),
    ("empty.xml", &["the scene file is empty"]),
    ("empty.json", &["the scene file is empty"]),
    ("top_level_array.json", &["top level", "object", "Scene"]),
    ("not_utf8.xml", &["not UTF-8", "line 12"]),
    ("folder_scene.xml", &["is a folder"]),
    (MISSING_SCENE, &["cannot read the scene", "no such file"]),
    // Wrong value counts and tokens.
    ("position_two_numbers.xml", &["<Position>", "3 numbers", "found 2"]),
    ("vertexdata_not_multiple_of_3.xml", &["<VertexData>", "11 numbers", "not a multiple of 3"]),
    ("faces_not_multiple_of_3.json", &["<Faces>", "5 indices", "not a multiple of 3"]),
    ("rotation_three_numbers.xml", &["<Rotation>", "4 numbers", "found 3"]),
    ("composite_fifteen_numbers.xml", &["<Composite>", "16 numbers", "found 15"]),
    ("not_a_number.xml", &["<Radius>", "\"0,3\"", "not a number"]),
    ("vertexdata_nan.json", &["<VertexData>", "non-finite", "NaN"]),
    ("nearplane_three_numbers.json", &["<NearPlane>", "4 numbers", "found 3"]),
    // References.
    ("unknown_material.xml", &["material \"7\"", "not defined"]),
    ("brdf_unknown_id.xml", &["Material[id=1]", "BRDF \"4\"", "does not define"]),
    ("brdf_unknown_type.xml", &["<CookTorrance>", "not a known BRDF", "TorranceSparrow"]),
    ("brdf_exponent_not_a_number.xml", &["<Exponent>", "\"fifty\"", "not a number"]),
    // Object lights and path tracing (hw7).
    ("light_mesh_without_radiance.xml", &["LightMesh[id=1]", "missing its <Radiance>"]),
    ("light_sphere_negative_radiance.xml", &["<Radiance>", "not negative"]),
    ("renderer_params_unknown_word.xml", &["<RendererParams>", "word 2", "unknown", "NextEventEstimation"]),
    ("renderer_params_all_lights_without_mis.xml", &["<RendererParams>", "AllLights", "needs MIS"]),
    ("renderer_params_one_and_all_lights.xml", &["<RendererParams>", "both AllLights and OneLight"]),
    ("renderer_unknown.xml", &["<Renderer>", "unknown", "PathTracing"]),
    ("material_without_id.xml", &["<Material>", "no id"]),
    ("unknown_transformation.xml", &["\"t9\"", "not defined", "Transformations"]),
    ("unknown_base_mesh.xml", &["baseMeshId \"42\"", "MeshInstance[id=2]"]),
    ("instance_cycle.xml", &["MeshInstance 2", "part of a cycle"]),
    ("instance_self.json", &["MeshInstance 2", "part of a cycle"]),
    // Indices and sizes.
    ("face_index_zero.xml", &["face index 0", "out of range", "5 vertices"]),
    ("face_index_beyond_vertexdata.xml", &["face index 9", "out of range", "5 vertices"]),
    ("sphere_center_out_of_range.json", &["Center", "vertex index 12", "out of range"]),
    ("radius_negative.xml", &["<Radius>", "positive", "-0.3"]),
    ("radius_zero.json", &["<Radius>", "positive", "found 0"]),
    ("max_recursion_depth_huge.xml", &["<MaxRecursionDepth>", "1000000", "supported"]),
    // PLY files.
    ("ply_missing.xml", &["PLY", "no_such_mesh.ply", "no such file"]),
    ("ply_empty_file_name.json", &["<Faces>", "empty plyFile"]),
    ("ply_is_a_folder.xml", &["cannot read PLY file", "folder"]),
    ("ply_garbage.xml", &["garbage.ply", "not a PLY file"]),
    ("ply_truncated_binary.json", &["truncated_binary.ply", "face 1", "file ends before"]),
    ("ply_absurd_counts.xml", &["absurd_counts.ply", "4000000000 'vertex'", "only 74 bytes"]),
    ("ply_face_index_out_of_range.xml", &["face_index_out_of_range.ply", "vertex 7", "3 vertices"]),
    ("ply_huge_face_list.xml", &["huge_face_list.ply", "face 0"]),
    // Textures.
    ("texture_image_missing.xml", &["Image[id=1]", "no_such_image.png", "no such file"]),
    ("texture_image_corrupt.xml", &["Image[id=1]", "corrupt.png", "cannot decode image"]),
    ("texture_unknown_decal.xml", &["<DecalMode>", "\"replace_colour\"", "unknown"]),
    ("texture_unknown_image_id.xml", &["TextureMap[id=1]/ImageId", "image \"9\"", "not defined"]),
    ("texture_unknown_type.xml", &["TextureMap[id=1]", "type \"marble\"", "unknown"]),
    ("texture_octaves_huge.xml", &["<NumOctaves>", "1000000"]),
    ("texture_unknown_map.xml", &["Sphere[id=1]/Textures", "texture map \"4\"", "not defined"]),
    ("texture_two_backgrounds.xml", &["TextureMap[id=2]", "second texture map replaces the background"]),
    ("texcoords_odd_count.xml", &["<TexCoordData>", "3 numbers", "multiple of 2"]),
    ("faces_bad_vertex_offset.xml", &["<Faces>", "vertexOffset=\"one\"", "not an integer"]),
    // Cameras and images.
    ("resolution_zero.xml", &["<ImageResolution>", "positive", "0 0"]),
    ("resolution_negative.json", &["<ImageResolution>", "positive", "-5 100"]),
    ("resolution_huge.xml", &["<ImageResolution>", "100000x100000", "supported"]),
    ("near_distance_zero.xml", &["<NearDistance>", "positive", "found 0"]),
    ("fovy_180.json", &["<FovY>", "180"]),
    ("no_camera.xml", &["no <Camera>"]),
    ("missing_image_name.json", &["missing its <ImageName>"]),
    ("image_name_parent.xml", &["<ImageName>", "\"../x.png\"", "output folder"]),
    ("image_name_absolute.json", &["<ImageName>", "\"/tmp/x.png\"", "absolute"]),
    ("image_name_bad_extension.xml", &["<ImageName>", "\"second.bmp\"", ".png"]),
    ("image_name_bad_hdr_extension.xml", &["<ImageName>", "\"out.tiff\"", ".exr"]),
    ("image_name_twice.json", &["Camera[id=2]", "same.png", "already writes"]),
    ("image_name_exr_and_png_clash.xml", &["Camera[id=2]", "cube.png", "already writes"]),
    // Tone mapping (hw5).
    ("tonemap_unknown_tmo.xml", &["<TMO>", "tone-mapping operator", "Photographic, ACES or Filmic"]),
    ("tonemap_options_not_numbers.json", &["<TMOOptions>", "must be numbers"]),
    ("tonemap_burn_100.json", &["<TMOOptions>", "burn-out percentage", "below 100"]),
    ("tonemap_bad_gamma.xml", &["<Gamma>", "positive number or sRGB"]),
    // Ellipsoids (luster's extension).
    ("ellipsoid_radii_two_numbers.xml", &["Ellipsoid[id=1]/Radii", "3 numbers", "found 2"]),
    ("ellipsoid_radius_zero.json", &["Ellipsoid[id=1]/Radii", "three positive numbers", "0.5 0 0.4"]),
    ("ellipsoid_radii_nan.json", &["Ellipsoid[id=1]/Radii", "non-finite", "NaN"]),
    ("ellipsoid_rotation_zero_axis.xml", &["Ellipsoid[id=1]/Rotation", "line 46", "zero axis"]),
    // Shader maps (luster's extension).
    ("shader_missing_script.xml", &["TextureMap[id=5]/Shader", "no_such_shader.lua", "no such file"]),
    ("shader_syntax_error.xml", &["TextureMap[id=5]", "syntax_error.lua:3", "'then' expected"]),
    ("shader_parameter_two_numbers.xml", &["Parameter", "\"tint\"", "2 numbers", "three (a vec3)"]),
    ("shader_missing_entry_point.xml", &["TextureMap[id=5]", "height_only.lua", "no color(s)", "replace_kd"]),
    ("shader_bump_without_height.xml", &["TextureMap[id=5]", "no height(s)", "bump_normal"]),
    // Volumes.
    ("volume_no_bound.xml", &["Volume[id=fog]", "needs a bound"]),
    ("volume_two_bounds.xml", &["Volume[id=fog]", "more than one bound"]),
    ("volume_box_inverted.xml", &["Box", "<Min> must be below <Max>"]),
    ("volume_grid_without_shader.xml", &["GridResolution", "needs a <Shader>"]),
    ("volume_step_tiny.xml", &["Volume[id=fog]", "<StepSize> 0.000000001", "more than 100000 steps"]),
    ("volume_grid_huge.xml", &["GridResolution", "2 to 512", "100000"]),
    ("volume_grid_too_much_memory.xml", &["Volume[id=fire]", "512³ grid of density and emission", "2.1 GB"]),
    ("volume_negative_absorption.xml", &["Absorption", "≥ 0"]),
    ("volume_shader_without_density.xml", &["Volume[id=fog]", "color_only.lua", "no density(s)"]),
    ("hypertexture_without_shader.xml", &["Hypertexture[id=h]", "needs a <Shader>"]),
    ("hypertexture_unknown_material.xml", &["material \"9\"", "not defined"]),
    // OBJ models (rendered on their own, or as a Mesh's objFile) and their MTL files.
    (
        "obj_missing.xml",
        &["Mesh[id=1]/Faces", "no_such_model.obj", "cannot read the OBJ file", "no such file"],
    ),
    ("obj_empty_file_name.json", &["<Faces>", "empty objFile"]),
    ("obj_face_index_out_of_range.xml", &["face_index_out_of_range.obj", "line 6", "vertex 9", "defines 4"]),
    ("obj_instance_of_several_materials.xml", &["MeshInstance[id=2]", "several materials", "<Material>"]),
    (
        "obj_missing_mtl.obj",
        &["line 2", "no_such_library.mtl", "cannot read the material library", "no such file"],
    ),
    (
        "obj_missing_texture.obj",
        &["missing_texture.mtl", "line 3", "map_Kd", "no_such_texture.png", "no such file"],
    ),
    (
        "obj_missing_shader.obj",
        &["missing_shader.mtl", "line 3", "texture_shader", "no_such_shader.lua", "no such file"],
    ),
    ("obj_bad_mtl_statement.obj", &["bad_color.mtl", "line 3", "Kd needs 1 or 3 numbers, found 2"]),
    ("obj_unknown_usemtl.obj", &["line 5", "usemtl \"chrome\"", "cube.mtl"]),
    ("obj_face_index_zero.obj", &["line 5", "vertex index 0", "from 1"]),
    ("obj_garbage.obj", &["line 6", "\"this\" is not an OBJ statement"]),
    ("obj_no_faces.obj", &["no faces"]),
    // hw5 lights and HDR images.
    ("env_map_missing.xml", &["Image[id=1]", "no_such_sky.exr", "no such file"]),
    ("env_map_corrupt_exr.xml", &["Image[id=1]", "corrupt.exr", "cannot decode image"]),
    ("env_map_corrupt_hdr.json", &["Image[id=1]", "corrupt.hdr", "cannot decode image"]),
    ("env_map_nan.xml", &["SphericalDirectionalLight[id=1]", "nan_sky.exr", "a NaN texel at (1, 0)"]),
    ("env_map_infinite.xml", &["SphericalDirectionalLight[id=1]", "infinite_sky.exr", "an infinite texel"]),
    ("env_map_negative.json", &["SphericalDirectionalLight[id=1]", "negative_sky.exr", "a negative texel"]),
    ("env_map_unknown_image.xml", &["SphericalDirectionalLight[id=1]/ImageId", "names no image"]),
    (
        "spot_falloff_larger_than_coverage.xml",
        &["SpotLight[id=1]/FalloffAngle", "30", "larger than <CoverageAngle> 20"],
    ),
    ("spot_missing_coverage.json", &["SpotLight[id=1]", "missing its <CoverageAngle>"]),
    ("directional_missing_radiance.xml", &["DirectionalLight[id=1]", "missing its <Radiance>"]),
    ("directional_zero_direction.json", &["DirectionalLight[id=1]/Direction", "non-zero"]),
];

/// A scene path that must not exist.
const MISSING_SCENE: &str = "no_such_scene.xml";

/// Scenes that are accepted: (file, image it writes, words the warning must contain).
const ACCEPTED: &[(&str, &str, &[&str])] =
    &[("ok_nearplane_five_numbers.xml", "out.png", &["NearPlane", "5 numbers"])];

/// Text that means a crash rather than an error message.
const CRASH_TEXT: &[&str] =
    &["panicked", "RUST_BACKTRACE", "stack overflow", "fatal runtime error", "memory allocation"];

/// Longest a case may take; anything slower is a hang.
const TIMEOUT: Duration = Duration::from_secs(60);

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("bad_input")
}

/// Runs `luster render -q -o OUT scene` from inside a fresh temporary folder,
/// so a write that escapes OUT still lands where it can be seen.
fn render(scene: &Path, root: &Path, out: &Path) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.arg("render").arg("-q").arg("--threads").arg("2").arg("-o").arg(out).arg(scene).current_dir(root);
    run_limited(cmd, TIMEOUT)
}

/// Every file and folder under `dir`, relative to it.
fn entries(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            out.push(p.strip_prefix(dir).unwrap_or(&p).to_path_buf());
            if p.is_dir() {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

/// What is wrong with one bad case, or `None` when it behaved.
fn check_bad(name: &str, expected: &[&str]) -> Option<String> {
    let root = tempfile::tempdir().expect("a temporary folder");
    let out = root.path().join("out");
    std::fs::create_dir(&out).expect("the output folder");
    let run = render(&corpus().join(name), root.path(), &out);
    let err = run.stderr.trim_end();
    let mut problems = Vec::new();
    match run.code {
        Some(2) => {}
        None => problems.push(format!("did not finish within {TIMEOUT:?} (or was killed by a signal)")),
        Some(c) => problems.push(format!("exit code {c}, expected 2")),
    }
    if err.lines().count() != 1 {
        problems.push(format!("stderr has {} lines, expected one error line", err.lines().count()));
    }
    if !err.starts_with("error: ") {
        problems.push("stderr does not start with \"error: \"".to_string());
    }
    let file_name = Path::new(name).file_name().and_then(|n| n.to_str()).unwrap_or(name);
    if !err.contains(file_name) {
        problems.push(format!("stderr lacks the file name {file_name:?}"));
    }
    // The key words must be in the message itself, not only in the file name.
    let message = err.replace(file_name, "");
    for word in expected {
        if !message.contains(word) {
            problems.push(format!("stderr lacks {word:?}"));
        }
    }
    for crash in CRASH_TEXT {
        if err.contains(crash) {
            problems.push(format!("stderr contains {crash:?}"));
        }
    }
    let left = entries(root.path());
    if left != [PathBuf::from("out")] {
        problems.push(format!("files left behind: {left:?}"));
    }
    (!problems.is_empty()).then(|| format!("{name}: {}\n    stderr: {err}", problems.join("; ")))
}

#[test]
fn bad_scenes_are_refused_cleanly() {
    let failures: Vec<String> =
        CASES.iter().filter_map(|(name, expected)| check_bad(name, expected)).collect();
    assert!(
        failures.is_empty(),
        "{} of {} bad scenes misbehaved:\n{}",
        failures.len(),
        CASES.len(),
        failures.join("\n")
    );
}

#[test]
fn accepted_quirks_render_with_a_warning() {
    for (name, image, words) in ACCEPTED {
        let root = tempfile::tempdir().expect("a temporary folder");
        let out = root.path().join("out");
        let run = render(&corpus().join(name), root.path(), &out);
        assert_eq!(run.code, Some(0), "{name} should render; stderr: {}", run.stderr);
        assert!(run.stderr.contains("warning"), "{name}: no warning in {:?}", run.stderr);
        for w in *words {
            assert!(run.stderr.contains(w), "{name}: the warning lacks {w:?}: {:?}", run.stderr);
        }
        let left = entries(&out);
        assert_eq!(left, [PathBuf::from(image)], "{name}: the output folder should hold only its image");
    }
}

/// Every scene in the corpus has a line in the table (and every line a scene),
/// and every PLY file and shader script is used by some scene.
#[test]
fn table_covers_the_corpus() {
    let dir = corpus();
    let on_disk: BTreeSet<String> = std::fs::read_dir(&dir)
        .expect("the corpus folder")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !["ply", "textures", "shaders", "obj"].contains(&n.as_str()) && !n.starts_with('.'))
        .collect();
    let in_table: BTreeSet<String> = CASES
        .iter()
        .map(|(n, _)| n.to_string())
        .chain(ACCEPTED.iter().map(|(n, _, _)| n.to_string()))
        .filter(|n| n != MISSING_SCENE)
        .collect();
    assert_eq!(CASES.len() + ACCEPTED.len(), in_table.len() + 1, "a scene is listed twice");
    let untested: Vec<_> = on_disk.difference(&in_table).collect();
    assert!(untested.is_empty(), "scenes in tests/bad_input without a line in CASES: {untested:?}");
    let absent: Vec<_> = in_table.difference(&on_disk).collect();
    assert!(absent.is_empty(), "CASES lines without a scene in tests/bad_input: {absent:?}");
    assert!(!dir.join(MISSING_SCENE).exists(), "{MISSING_SCENE} must not exist");

    let texts: Vec<String> = on_disk
        .iter()
        .filter_map(|n| std::fs::read(dir.join(n)).ok())
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .collect();
    for folder in ["ply", "textures", "shaders", "obj"] {
        for file in std::fs::read_dir(dir.join(folder)).expect("the asset folder").flatten() {
            let name = format!("{folder}/{}", file.file_name().to_string_lossy());
            assert!(texts.iter().any(|t| t.contains(&name)), "{name} is used by no scene");
        }
    }
}
