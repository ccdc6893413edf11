//! Tests of the PLY loader: encodings, layouts, course files and every error.

use super::header::UV_NAMES;
use super::*;
use std::path::PathBuf;
use std::time::Instant;

/// A small mesh written in any encoding: header lines after `format`,
/// and the body as either text or raw bytes.
fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect("test file is writable");
    path
}

fn ok(path: &Path) -> PlyMesh {
    match read_ply(path) {
        Ok(mesh) => mesh,
        Err(e) => panic!("{e}"),
    }
}

/// Reads `path`, expects an error, and checks that its message names the
/// file and contains every one of `parts`.
fn err(path: &Path, parts: &[&str]) -> PlyError {
    let e = match read_ply(path) {
        Ok(mesh) => panic!("expected an error, got {mesh:?}"),
        Err(e) => e,
    };
    let text = e.to_string();
    println!("{text}");
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("?");
    assert!(text.contains(name), "'{text}' does not name {name}");
    for part in parts {
        assert!(text.contains(part), "'{text}' does not contain '{part}'");
    }
    assert!(!text.contains('\n'), "'{text}' spans several lines");
    e
}

const QUAD_ASCII: &str = "ply
format ascii 1.0
comment a unit quad with normals and uvs
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float u
property float v
element face 1
property list uchar int vertex_indices
end_header
0 0 0 0 0 1 0 0
1 0 0 0 0 1 1 0
1 1 0 0 0 1 1 1
0 1 0 0 0 1 0 1
4 0 1 2 3
";

/// The quad above in a binary encoding, built by hand.
fn quad_binary(big_endian: bool) -> Vec<u8> {
    let format = if big_endian { "binary_big_endian" } else { "binary_little_endian" };
    let mut out =
        QUAD_ASCII.split("end_header\n").next().unwrap_or_default().replace("ascii", format).into_bytes();
    out.extend_from_slice(b"end_header\n");
    let f =
        |out: &mut Vec<u8>, v: f32| out.extend(if big_endian { v.to_be_bytes() } else { v.to_le_bytes() });
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for v in [x, y, 0.0, 0.0, 0.0, 1.0, x, y] {
            f(&mut out, v);
        }
    }
    out.push(4);
    for i in 0i32..4 {
        out.extend(if big_endian { i.to_be_bytes() } else { i.to_le_bytes() });
    }
    out
}

fn header(vertex_props: &str, faces: &str) -> String {
    format!("ply\nformat ascii 1.0\nelement vertex 4\n{vertex_props}element face {faces}end_header\n")
}

#[test]
fn ascii_quad_becomes_two_triangles_with_normals_and_uvs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mesh = ok(&write(&dir, "quad.ply", QUAD_ASCII.as_bytes()));
    assert_eq!(mesh.positions.len(), 4);
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.normals, Some(vec![Vec3::Z; 4]));
    let uvs = mesh.uvs.expect("uvs");
    assert_eq!(uvs[2], Vec2::new(1.0, 1.0));
    assert_eq!(mesh.skipped_degenerate, 0);
}

#[test]
fn binary_encodings_read_the_same_as_ascii() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ascii = ok(&write(&dir, "a.ply", QUAD_ASCII.as_bytes()));
    let le = ok(&write(&dir, "le.ply", &quad_binary(false)));
    let be = ok(&write(&dir, "be.ply", &quad_binary(true)));
    assert_eq!(le, ascii);
    assert_eq!(be, ascii);
    let crlf = ok(&write(&dir, "crlf.ply", QUAD_ASCII.replace('\n', "\r\n").as_bytes()));
    assert_eq!(crlf, ascii);
}

#[test]
fn vertex_index_name_double_coords_and_small_index_types() {
    let dir = tempfile::tempdir().expect("tempdir");
    for list in ["uchar uint", "ushort ushort", "int short", "uint8 char", "uchar uint8"] {
        let text = header(
            "property double x\nproperty double y\nproperty double z\n",
            &format!("2\nproperty list {list} vertex_index\n"),
        ) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
        let mesh = ok(&write(&dir, "vi.ply", text.as_bytes()));
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]], "{list}");
        assert!(mesh.normals.is_none() && mesh.uvs.is_none());
    }
}

#[test]
fn uv_names_are_detected() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (u, v) in UV_NAMES {
        let text = header(
            &format!("property float x\nproperty float y\nproperty float z\nproperty float {u}\nproperty float {v}\n"),
            "1\nproperty list uchar int vertex_indices\n",
        ) + "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 0.5\n4 0 1 2 3\n";
        let mesh = ok(&write(&dir, "uv.ply", text.as_bytes()));
        let uvs = mesh.uvs.expect("uvs");
        assert_eq!(uvs[3], Vec2::new(0.0, 0.5), "{u} {v}");
        assert!(mesh.normals.is_none());
    }
}

#[test]
fn other_elements_and_properties_are_ignored() {
    let dir = tempfile::tempdir().expect("tempdir");
    let text = "ply
format ascii 1.0
element material 1
property uchar red
property list uchar float weights
element vertex 3
property float x
property uchar red
property float y
property float z
property float nx
element face 1
property uchar flags
property list uchar int vertex_indices
property list uchar float texcoord
element edge 2
property int vertex1
property int vertex2
end_header
7 2 0.5 0.25
0 255 0 0 9
1 255 0 0 9
0 255 1 0 9
3 3 0 1 2 6 0 0 1 0 0 1
0 1
1 2
";
    let mesh = ok(&write(&dir, "extra.ply", text.as_bytes()));
    assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(mesh.positions[2], Vec3::Y);
    assert!(mesh.normals.is_none(), "nx alone is not a normal");
}

#[test]
fn degenerate_triangles_are_skipped_and_counted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let text = header(
        "property float x\nproperty float y\nproperty float z\n",
        "4\nproperty list uchar int vertex_indices\n",
    ) + "0 0 0\n1 0 0\n1 1 0\n1 0 0\n3 0 1 2\n3 0 1 1\n3 0 1 3\n4 2 0 0 1\n";
    let mesh = ok(&write(&dir, "degenerate.ply", text.as_bytes()));
    // Kept: (0,1,2) and the quad's second half (2,0,1); dropped: (0,1,1),
    // (0,1,3) whose 1 and 3 coincide, and the quad's (2,0,0).
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [2, 0, 1]]);
    assert_eq!(mesh.skipped_degenerate, 3);
}

#[test]
fn missing_file_and_non_ply_files_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let e = err(&dir.path().join("absent.ply"), &["cannot read", "no such file"]);
    assert!(matches!(e, PlyError::Unreadable { .. }));
    err(Path::new("/dev/zero"), &["cannot read", "a device"]);
    err(&write(&dir, "mesh.obj", b"v 0 0 0\nf 1 2 3\n"), &["not a PLY file"]);
    err(&write(&dir, "empty.ply", b""), &["not a PLY file"]);
    err(&write(&dir, "plywood.ply", b"plywood\n"), &["not a PLY file"]);
}

#[test]
fn malformed_headers_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad_property = "ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n";
    err(&write(&dir, "typo.ply", bad_property.as_bytes()), &["malformed PLY header", "line 4"]);
    let no_end = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n";
    err(&write(&dir, "noend.ply", no_end.as_bytes()), &["malformed PLY header", "end_header"]);
    let no_format = "ply\nelement vertex 0\nend_header\n";
    err(&write(&dir, "noformat.ply", no_format.as_bytes()), &["malformed PLY header", "format"]);
    let mut binary = b"ply\nformat ascii 1.0\ncomment ".to_vec();
    binary.extend([0xff, 0xfe, 0x80, b'\n']);
    err(&write(&dir, "bytes.ply", &binary), &["malformed PLY header", "not text"]);
}

#[test]
fn missing_elements_and_properties_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let no_face = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    err(&write(&dir, "noface.ply", no_face.as_bytes()), &["no 'face' element"]);
    let no_vertex =
        "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
    err(&write(&dir, "novertex.ply", no_vertex.as_bytes()), &["no 'vertex' element"]);
    let no_z = header("property float x\nproperty float y\n", "0\nproperty list uchar int vertex_indices\n");
    err(&write(&dir, "noz.ply", no_z.as_bytes()), &["'vertex'", "no property z"]);
    let no_list = header(
        "property float x\nproperty float y\nproperty float z\n",
        "0\nproperty list uchar int corners\n",
    );
    err(&write(&dir, "nolist.ply", no_list.as_bytes()), &["'face'", "vertex_indices"]);
    let float_list = header(
        "property float x\nproperty float y\nproperty float z\n",
        "0\nproperty list uchar float vertex_indices\n",
    );
    err(
        &write(&dir, "floatlist.ply", float_list.as_bytes()),
        &["'vertex_indices'", "list uchar float", "list of integers"],
    );
    let int_x = header(
        "property int x\nproperty float y\nproperty float z\n",
        "0\nproperty list uchar int vertex_indices\n",
    );
    err(&write(&dir, "intx.ply", int_x.as_bytes()), &["'x'", "'int'", "'float' or 'double'"]);
}

#[test]
fn absurd_counts_fail_before_allocating() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_owned();
    text.push_str(&"\0".repeat(300 - text.len()));
    let start = Instant::now();
    err(
        &write(&dir, "huge.ply", text.as_bytes()),
        &["4000000000 'vertex' elements", "48000000000 bytes", "follow the header"],
    );
    assert!(start.elapsed().as_millis() < 100);
    let ascii = header(
        "property float x\nproperty float y\nproperty float z\n",
        "18446744073709551615\nproperty list uchar int vertex_indices\n",
    ) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n";
    err(&write(&dir, "hugeascii.ply", ascii.as_bytes()), &["18446744073709551615 'face' elements"]);
    let nothing = "ply\nformat binary_big_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nelement empty 999999999999\nend_header\n";
    // Elements without properties take no bytes in a binary file, so any
    // count is fine, and they are not looped over.
    let start = Instant::now();
    let mesh = ok(&write(&dir, "empty_elements.ply", nothing.as_bytes()));
    assert!(mesh.positions.is_empty() && mesh.triangles.is_empty());
    assert!(start.elapsed().as_millis() < 100);
}

#[test]
fn truncated_bodies_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let full = quad_binary(false);
    err(
        &write(&dir, "cut.ply", &full[..full.len() - 3]),
        &["face 0", "ends before the 1 declared 'face' elements"],
    );
    let vertices_cut = &full[..full.len() - 60];
    err(&write(&dir, "cutvertex.ply", vertices_cut), &["4 'vertex' elements", "at least 128 bytes"]);
    // Long numbers so that the bytes could hold the face: the count check
    // passes and the reader meets the end of the file.
    let ascii =
        QUAD_ASCII.replace("4 0 1 2 3\n", "").replace("0 0 0 0 0 1 0 0", "0.000000000000 0 0 0 0 1 0 0");
    err(&write(&dir, "cut_ascii.ply", ascii.as_bytes()), &["face 0 (line 20)", "ends before"]);
    let short_line = QUAD_ASCII.replace("1 1 0 0 0 1 1 1", "1 1 0 0 0 1 1");
    err(&write(&dir, "shortline.ply", short_line.as_bytes()), &["vertex 2 (line 18)"]);
    let junk = QUAD_ASCII.replace("1 1 0 0 0 1 1 1", "1 1 zero 0 0 1 1 1");
    err(&write(&dir, "junk.ply", junk.as_bytes()), &["vertex 2 (line 18)"]);
}

#[test]
fn bad_faces_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out_of_range = QUAD_ASCII.replace("4 0 1 2 3", "4 0 1 2 4");
    err(
        &write(&dir, "range.ply", out_of_range.as_bytes()),
        &["face 0 (line 20)", "vertex 4", "has 4 vertices"],
    );
    let negative = QUAD_ASCII.replace("4 0 1 2 3", "3 0 -1 2");
    err(&write(&dir, "negative.ply", negative.as_bytes()), &["face 0", "vertex -1"]);
    let two = QUAD_ASCII.replace("4 0 1 2 3", "2 0 1");
    err(&write(&dir, "two.ply", two.as_bytes()), &["face 0", "2 vertex indices", "at least 3"]);
    let none = QUAD_ASCII.replace("4 0 1 2 3", "0");
    err(&write(&dir, "zero.ply", none.as_bytes()), &["0 vertex indices"]);
    let mut binary = quad_binary(false);
    let n = binary.len();
    binary[n - 4..].copy_from_slice(&100i32.to_le_bytes());
    err(&write(&dir, "range_le.ply", &binary), &["face 0 in", "vertex 100"]);
}

#[test]
fn non_finite_coordinates_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut binary = quad_binary(true);
    let body = binary.len() - 4 * 8 * 4 - 17;
    binary[body + 32 + 4..body + 32 + 8].copy_from_slice(&f32::NAN.to_be_bytes());
    err(&write(&dir, "nan.ply", &binary), &["vertex 1 in", "non-finite", "NaN"]);
    let huge = header(
        "property double x\nproperty double y\nproperty double z\n",
        "1\nproperty list uchar int vertex_indices\n",
    ) + "0 0 0\n1 0 0\n1 1 1e300\n0 1 0\n3 0 1 2\n";
    err(&write(&dir, "inf.ply", huge.as_bytes()), &["vertex 2 (line 12)", "inf"]);
}

/// The course scenes, when the shared folder is present.
fn shared(relative: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/ceng795").join(relative);
    if path.exists() {
        Some(path)
    } else {
        println!("skipping: {} is absent", path.display());
        None
    }
}

#[test]
fn course_meshes_load() {
    let cases: &[(&str, usize, usize, bool, bool)] = &[
        ("hw1/json/akif_uslu/ton_Roosendaal_smooth_ply/mesh_1.ply", 8190, 16384, false, false),
        ("hw1/json/akif_uslu/ton_Roosendaal_smooth_ply/mesh_2.ply", 31072, 62160, false, false),
        ("hw1/json/akif_uslu/ton_Roosendaal_smooth_ply/mesh_3.ply", 78, 76, false, false),
        ("hw3/json/ply/cube.ply", 8, 12, false, false),
        ("hw4/xml/veach_ajar/models/Mesh000.ply", 23938, 47872, true, true),
        ("hw4/xml/veach_ajar/models/Mesh008.ply", 4, 2, false, true),
        ("hw4/xml/veach_ajar/models/Mesh009.ply", 39086, 78176, true, true),
        ("hw4/xml/veach_ajar/models/Mesh015_fixed.ply", 8622, 2880, true, false),
    ];
    for &(file, vertices, triangles, normals, uvs) in cases {
        let Some(path) = shared(file) else { return };
        let start = Instant::now();
        let mesh = ok(&path);
        println!(
            "{file}: {} vertices, {} triangles (+{} degenerate) in {:.1} ms",
            mesh.positions.len(),
            mesh.triangles.len(),
            mesh.skipped_degenerate,
            start.elapsed().as_secs_f64() * 1e3
        );
        assert_eq!(mesh.positions.len(), vertices, "{file}");
        assert_eq!(mesh.triangles.len() + mesh.skipped_degenerate, triangles, "{file}");
        assert_eq!(mesh.normals.is_some(), normals, "{file}");
        assert_eq!(mesh.uvs.is_some(), uvs, "{file}");
    }
}

#[test]
fn every_veach_ajar_mesh_loads() {
    let Some(dir) = shared("hw4/xml/veach_ajar/models") else {
        return;
    };
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return;
    };
    let mut count = 0;
    for entry in entries.flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "ply") {
            let mesh = ok(&path);
            assert!(!mesh.triangles.is_empty(), "{}", path.display());
            count += 1;
        }
    }
    assert!(count >= 17);
}

/// Times loading the mesh `PLY_BENCH` names, for a look at the loader's speed:
/// `PLY_BENCH=/tmp/mesh/bumpy_sphere_L8.ply cargo test --release -- --ignored --nocapture load_time`
#[test]
#[ignore = "timing; needs PLY_BENCH"]
fn load_time() {
    let Some(path) = std::env::var_os("PLY_BENCH") else {
        return;
    };
    for _ in 0..5 {
        let start = Instant::now();
        let mesh = ok(Path::new(&path));
        println!(
            "{}: {} vertices, {} triangles in {:.1} ms",
            Path::new(&path).display(),
            mesh.positions.len(),
            mesh.triangles.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
    }
}
