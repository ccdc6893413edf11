//! The hostile inputs, one function per class of issue #15: special files
//! for every input kind, nesting and size, malformed XML, malformed JSON,
//! numbers, shaders, leaks, images and the command line.

use super::kit::{imaged, json, mesh_from, obj, png_header, shaded, xml, Case, Content, JSON_SPHERE};

const GIB: u64 = 1 << 30;

fn special_files() -> Vec<Case> {
    use Content::{Dir, Fifo, Link, Sparse};
    let zero = || Link("/dev/zero");
    let r = Case::render;
    vec![
        r("scene FIFO (XML)", "s.xml", &["s.xml", "cannot read the scene", "FIFO"]).special("s.xml", Fifo),
        r("scene FIFO (JSON)", "s.json", &["s.json", "FIFO"]).special("s.json", Fifo),
        r("scene /dev/zero (XML)", "s.xml", &["s.xml", "a device"]).special("s.xml", zero()),
        r("scene /dev/zero (JSON)", "s.json", &["s.json", "a device"]).special("s.json", zero()),
        r("scene /dev/zero (no extension)", "s", &["a device"]).special("s", zero()),
        r("scene of 2 GiB", "s.xml", &["s.xml", "2147483648 bytes"]).special("s.xml", Sparse(2 * GIB)),
        r("model FIFO", "m.obj", &["m.obj", "cannot read the OBJ file", "FIFO"]).special("m.obj", Fifo),
        r("model /dev/zero", "m.obj", &["m.obj", "a device"]).special("m.obj", zero()),
        r("model of 2 GiB", "m.obj", &["m.obj", "bytes, more than"]).special("m.obj", Sparse(2 * GIB)),
        r("model folder", "m.obj", &["m.obj", "folder"]).special("m.obj", Dir),
        r("PLY FIFO", "s.xml", &["m.ply", "FIFO"])
            .text("s.xml", mesh_from("plyFile", "m.ply"))
            .special("m.ply", Fifo),
        r("PLY /dev/zero", "s.xml", &["m.ply", "a device"])
            .text("s.xml", mesh_from("plyFile", "m.ply"))
            .special("m.ply", zero()),
        r("PLY of 9 GiB", "s.xml", &["m.ply", "bytes, more than"])
            .text("s.xml", mesh_from("plyFile", "m.ply"))
            .special("m.ply", Sparse(9 * GIB)),
        r("objFile FIFO", "s.xml", &["m.obj", "FIFO"])
            .text("s.xml", mesh_from("objFile", "m.obj"))
            .special("m.obj", Fifo),
        r("objFile /dev/zero", "s.xml", &["m.obj", "a device"])
            .text("s.xml", mesh_from("objFile", "m.obj"))
            .special("m.obj", zero()),
        r("texture FIFO", "s.xml", &["t.png", "FIFO"]).text("s.xml", imaged("t.png")).special("t.png", Fifo),
        r("texture /dev/zero", "s.xml", &["t.png", "a device"])
            .text("s.xml", imaged("t.png"))
            .special("t.png", zero()),
        r("texture of 2 GiB", "s.xml", &["t.png", "bytes, more than"])
            .text("s.xml", imaged("t.png"))
            .special("t.png", Sparse(2 * GIB)),
        r("texture folder", "s.xml", &["t.png", "folder"])
            .text("s.xml", imaged("t.png"))
            .special("t.png", Dir),
        r("shader FIFO", "s.xml", &["x.lua", "FIFO"]).text("s.xml", shaded("x.lua")).special("x.lua", Fifo),
        r("shader /dev/zero", "s.xml", &["x.lua", "a device"])
            .text("s.xml", shaded("x.lua"))
            .special("x.lua", zero()),
        r("shader of 5 MiB", "s.xml", &["x.lua", "bytes, more than"])
            .text("s.xml", shaded("x.lua"))
            .special("x.lua", Sparse(5 << 20)),
        r("shader folder", "s.xml", &["x.lua", "folder"])
            .text("s.xml", shaded("x.lua"))
            .special("x.lua", Dir),
        r("mtllib FIFO", "m.obj", &["m.mtl", "FIFO"])
            .text("m.obj", obj(Some("m.mtl")))
            .special("m.mtl", Fifo),
        r("mtllib /dev/zero", "m.obj", &["m.mtl", "a device"])
            .text("m.obj", obj(Some("m.mtl")))
            .special("m.mtl", zero()),
        r("mtllib of 65 MiB", "m.obj", &["m.mtl", "bytes, more than"])
            .text("m.obj", obj(Some("m.mtl")))
            .special("m.mtl", Sparse(65 << 20)),
        r("map_Kd FIFO", "m.obj", &["m.mtl", "map_Kd", "t.png", "FIFO"])
            .text("m.obj", obj(Some("m.mtl")))
            .text("m.mtl", "newmtl m\nKd 1 1 1\nmap_Kd t.png\n")
            .special("t.png", Fifo),
        r("map_Kd /dev/zero", "m.obj", &["m.mtl", "map_Kd", "t.png", "a device"])
            .text("m.obj", obj(Some("m.mtl")))
            .text("m.mtl", "newmtl m\nKd 1 1 1\nmap_Kd t.png\n")
            .special("t.png", zero()),
        r("map_Kd folder", "m.obj", &["m.mtl", "map_Kd", "folder"])
            .text("m.obj", obj(Some("m.mtl")))
            .text("m.mtl", "newmtl m\nKd 1 1 1\nmap_Kd t.png\n")
            .special("t.png", Dir),
        r("texture_shader FIFO", "m.obj", &["m.mtl", "x.lua", "FIFO"])
            .text("m.obj", obj(Some("m.mtl")))
            .text("m.mtl", "newmtl m\nKd 1 1 1\ntexture_shader x.lua\n")
            .special("x.lua", Fifo),
    ]
}

fn nesting_and_size() -> Vec<Case> {
    let r = Case::render;
    let deep_xml = format!("<Scene>{}{}</Scene>", "<a>".repeat(100_000), "</a>".repeat(100_000));
    let just_too_deep = format!("<Scene>{}{}</Scene>", "<a>".repeat(64), "</a>".repeat(64));
    let deep_json = format!("{{\"Scene\": {}{}}}", "[".repeat(100_000), "]".repeat(100_000));
    let deep_objects = format!("{}1{}", "{\"a\": ".repeat(100_000), "}".repeat(100_000));
    let mut spheres = String::new();
    for i in 1..100_000 {
        spheres.push_str(&format!(
            "<Sphere id=\"{i}\"><Material>1</Material><Center>1</Center><Radius>0.5</Radius></Sphere>\n"
        ));
    }
    spheres.push_str(
        "<Sphere id=\"100000\"><Material>1</Material><Center>1</Center><Radius>-1</Radius></Sphere>",
    );
    let siblings = format!("<Scene>\n{}<Cameras>\n</Scene>", "<Unknown/>\n".repeat(100_000));
    let mut json_spheres = Vec::new();
    for i in 1..=100_000 {
        let radius = if i == 100_000 { "-1" } else { "0.5" };
        json_spheres.push(format!(
            "{{\"_id\": \"{i}\", \"Material\": \"1\", \"Center\": \"1\", \"Radius\": \"{radius}\"}}"
        ));
    }
    let json_spheres = format!("{{\"Sphere\": [{}]}}", json_spheres.join(",\n"));
    vec![
        r("XML nested 100,000 deep", "s.xml", &["s.xml", "nested more than 64 deep"]).text("s.xml", deep_xml),
        r("XML nested 65 deep", "s.xml", &["s.xml", "line 1", "nested more than 64 deep"])
            .text("s.xml", just_too_deep),
        r("JSON arrays nested 100,000 deep", "s.json", &["s.json", "recursion limit"])
            .text("s.json", deep_json),
        r("JSON objects nested 100,000 deep", "s.json", &["s.json", "recursion limit"])
            .text("s.json", deep_objects),
        r("XML with 100,000 spheres", "s.xml", &["s.xml", "Sphere[id=100000]", "line 100020", "positive"])
            .text("s.xml", xml(&spheres, "")),
        r("XML with 100,000 siblings", "s.xml", &["s.xml", "line 100003", "malformed XML"])
            .text("s.xml", siblings),
        r("JSON with 100,000 spheres", "s.json", &["s.json", "Sphere[id=100000]", "positive"])
            .text("s.json", json(&json_spheres)),
    ]
}

fn malformed_xml() -> Vec<Case> {
    let r = |name, text: &str, expect: &[&'static str]| {
        Case::render(name, "s.xml", &[&["s.xml"][..], expect].concat()).text("s.xml", text.to_string())
    };
    let laughs = format!(
        "<!DOCTYPE s [<!ENTITY a \"aaaaaaaaaa\">{}]>\n<Scene>&j;</Scene>",
        (b'b'..=b'j')
            .map(|c| {
                let prev = (c - 1) as char;
                format!("<!ENTITY {} \"{}\">", c as char, format!("&{prev};").repeat(10))
            })
            .collect::<String>()
    );
    vec![
        r("XML unclosed", "<Scene><Cameras>", &["malformed XML"]),
        r("XML mismatched tags", "<Scene><Cameras></Lights></Scene>", &["malformed XML", "line 1"]),
        r("XML undefined entity", "<Scene>&nope;</Scene>", &["malformed XML"]),
        r("XML billion laughs", &laughs, &["malformed XML"]),
        r("XML NUL byte", "<Scene>\0</Scene>", &["malformed XML"]),
        r("XML two roots", "<Scene/><Scene/>", &["malformed XML"]),
        r("XML text only", "hello", &["malformed XML"]),
        r("XML byte-order mark only", "\u{feff}", &["malformed XML"]),
        r("XML duplicate attribute", "<Scene a=\"1\" a=\"2\"/>", &["malformed XML"]),
        r("XML unterminated comment", "<Scene><!-- </Scene>", &["malformed XML"]),
        r("XML unterminated CDATA", "<Scene><![CDATA[ </Scene>", &["malformed XML"]),
        r("XML bad character reference", "<Scene>&#0;</Scene>", &["malformed XML"]),
        Case::render("XML not UTF-8", "s.xml", &["s.xml", "not UTF-8", "line 2"])
            .bytes("s.xml", b"<Scene>\n\xe9</Scene>".to_vec()),
    ]
}

fn malformed_json() -> Vec<Case> {
    let r = |name, text: &str, expect: &[&'static str]| {
        Case::render(name, "s.json", &[&["s.json"][..], expect].concat()).text("s.json", text.to_string())
    };
    let sphere = r#"{"_id": "1", "Material": "1", "Center": "1", "Radius": "0.5"}"#;
    vec![
        r(
            "JSON duplicate top-level key",
            "{\"Scene\": {},\n\"Scene\": {}}",
            &["line 2", "\"Scene\" is given twice"],
        ),
        r(
            "JSON duplicate element key",
            &json(&format!("{{\"Sphere\": {sphere},\n \"Sphere\": {sphere}}}")),
            &["\"Sphere\" is given twice"],
        ),
        r(
            "JSON duplicate attribute",
            &json(r#"{"Sphere": {"_id": "1", "_id": "2", "Material": "1", "Center": "1", "Radius": "0.5"}}"#),
            &["\"_id\" is given twice"],
        ),
        r("JSON null scene", r#"{"Scene": null}"#, &["<Scene> is null"]),
        r("JSON null objects", &json("null"), &["Scene/Objects", "<Objects> is null"]),
        r("JSON null sphere", &json(r#"{"Sphere": null}"#), &["<Sphere> is null"]),
        r(
            "JSON null in an array",
            &json(&format!("{{\"Sphere\": [{sphere}, null]}}")),
            &["<Sphere> is null"],
        ),
        r(
            "JSON null camera",
            &json(JSON_SPHERE).replacen(r#""Camera": {"_id": "1""#, r#""Camera": null, "X": {"_id": "1""#, 1),
            &["<Camera> is null"],
        ),
        r("JSON top-level null", "null", &["top level"]),
        r("JSON empty object", "{}", &["top level"]),
        r("JSON number out of range", &json(JSON_SPHERE).replace("\"0.5\"", "1e400"), &["malformed JSON"]),
        r("JSON lone surrogate", r#"{"Scene": "\ud800"}"#, &["malformed JSON"]),
        r("JSON bad escape", r#"{"Scene": "\q"}"#, &["malformed JSON"]),
        r("JSON trailing garbage", &format!("{} x", json(JSON_SPHERE)), &["malformed JSON"]),
        r("JSON nested array", &json(&format!("{{\"Sphere\": [[{sphere}]]}}")), &["nested arrays"]),
        r("JSON control character", "{\"Scene\": \"\u{1}\"}", &["malformed JSON"]),
    ]
}

fn numbers() -> Vec<Case> {
    let r = |name, objects: &str, extra: &str, expect: &[&'static str]| {
        Case::render(name, "s.xml", &[&["s.xml"][..], expect].concat()).text("s.xml", xml(objects, extra))
    };
    let sphere = |center: &str, radius: &str, xf: &str| {
        format!(
            "<Sphere id=\"1\"><Material>1</Material>{xf}<Center>{center}</Center><Radius>{radius}</Radius></Sphere>"
        )
    };
    let scale = "<Transformations><Scaling id=\"1\">10 10 10</Scaling><Translation id=\"1\">1e39 0 0</Translation></Transformations>";
    let huge_vertex = xml(
        &sphere("4", "1", "<Transformations>s1</Transformations>"),
        "<Transformations><Scaling id=\"1\">10 10 10</Scaling></Transformations>",
    )
    .replace("<VertexData>0 0 -3 1 0 -3 0 1 -3", "<VertexData>0 0 -3 1 0 -3 0 1 -3 3.4e38 0 -3");
    vec![
        r("vertex inf", "", "", &["<VertexData>", "non-finite"]).text("s.xml", xml("", "").replace("1 0 -3", "inf 0 -3")),
        r("vertex 1e39 (inf in f32)", "", "", &["<VertexData>", "non-finite"])
            .text("s.xml", xml("", "").replace("1 0 -3", "1e39 0 -3")),
        r("vertex NaN", "", "", &["<VertexData>", "non-finite"]).text("s.xml", xml("", "").replace("1 0 -3", "NaN 0 -3")),
        r("radius inf", &sphere("1", "inf", ""), "", &["<Radius>", "non-finite"]),
        r("sphere box beyond f32", "", "", &["Sphere[id=1]", "beyond the range"]).text(
            "s.xml",
            xml(&sphere("4", "1e38", ""), "").replace("0 1 -3</VertexData>", "0 1 -3 3e38 0 -3</VertexData>"),
        ),
        r("3.4e38 under a scaling", "", "", &["Sphere[id=1]", "beyond the range"]).text("s.xml", huge_vertex),
        r("translation 1e39", &sphere("1", "1", "<Transformations>t1</Transformations>"), scale, &["<Translation>", "non-finite"]),
        r(
            "mesh at 3e38 under a scaling",
            "<Mesh id=\"1\"><Material>1</Material><Transformations>s1</Transformations><Faces>1 2 4</Faces></Mesh>",
            scale,
            &["Mesh[id=1]", "beyond the range"],
        )
        .text(
            "s.xml",
            xml(
                "<Mesh id=\"1\"><Material>1</Material><Transformations>s1</Transformations><Faces>1 2 4</Faces></Mesh>",
                "<Transformations><Scaling id=\"1\">10 10 10</Scaling></Transformations>",
            )
            .replace("0 1 -3</VertexData>", "0 1 -3 0 3e38 -3</VertexData>"),
        ),
        Case::render("OBJ vertex inf", "m.obj", &["m.obj", "line 2", "non-finite"]).text("m.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n"),
        Case::render("OBJ vertex 1e39", "m.obj", &["m.obj", "line 1", "non-finite"]).text("m.obj", "v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        Case::render("OBJ face index beyond u32", "m.obj", &["m.obj", "line 4"]).text("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n"),
        Case::render("PLY vertex NaN", "s.xml", &["m.ply", "vertex 1"])
            .text("s.xml", mesh_from("plyFile", "m.ply"))
            .text("m.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 -3\nnan 0 -3\n0 1 -3\n3 0 1 2\n"),
        r(
            "volume box of 1e30",
            "",
            "<Volumes><Volume id=\"fog\"><Box><Min>-1e30 -1e30 -1e30</Min><Max>1e30 1e30 1e30</Max></Box></Volume></Volumes>",
            &["Volume[id=fog]", "at most 1e7"],
        ),
        r(
            "volume sphere of radius 1e20",
            "",
            "<Volumes><Volume id=\"fog\"><Sphere><Center>0 0 -3</Center><Radius>1e20</Radius></Sphere></Volume></Volumes>",
            &["Volume[id=fog]", "at most 1e7"],
        ),
    ]
}

fn shaders() -> Vec<Case> {
    let r = |name, code: &str, expect: &[&'static str]| {
        Case::render(name, "s.xml", &[&["s.xml: ", "shader 'x'"][..], expect].concat())
            .text("s.xml", shaded("x.lua"))
            .text("x.lua", code.to_string())
    };
    let spin = "function color(s) while true do end end";
    vec![
        r("endless loop", spin, &["time limit"]),
        r("endless loop at load", "while true do end", &["time limit"]),
        r(
            "pcall swallows the timeout",
            "function color(s) pcall(function() while true do end end) return 1, 1, 1 end",
            &["time limit", "caught"],
        ),
        r(
            "pcall in the loop",
            "function color(s) while true do pcall(function() while true do end end) end end",
            &["time limit"],
        ),
        r("\\z hides a loop", &format!("local a = 'x\\z\n   '\n{spin}"), &["time limit"]),
        r("\\z with CRLF hides a loop", &format!("local a = 'x\\z\r\n  \r\n'\r\n{spin}"), &["time limit"]),
        r("backslash-CRLF hides a loop", &format!("local a = 'x\\\r\ny'\r\n{spin}"), &["time limit"]),
        r("backslash-LFCR hides a loop", &format!("local a = 'x\\\n\ry'\n{spin}"), &["time limit"]),
        r("CR-ended comment hides a loop", &format!("-- note\rlocal b = 1\r{spin}"), &["time limit"]),
        r("long bracket levels hide a loop", &format!("local a = [==[ ]] ]=] ]==]\n{spin}"), &["time limit"]),
        r(
            "hex exponent hides a function",
            "local f = 0x1e+function() while true do end end\nfunction color(s) return 1, 1, 1 end",
            &["arithmetic"],
        ),
        r(
            "coroutine loop",
            "function color(s) coroutine.wrap(function() while true do end end)() end",
            &["time limit"],
        ),
        r(
            "backtracking find",
            "function color(s) string.find(string.rep('a', 1e5), '.-.-.-.-b') return 1, 1, 1 end",
            &["x.lua:1", "magic characters"],
        ),
        r(
            "backtracking match method",
            "function color(s) ('a'):rep(5e4):match('(a*)*b') return 1, 1, 1 end",
            &["magic characters"],
        ),
        r(
            "pattern gsub",
            "function color(s) string.gsub('abc', '%a+', 'x') return 1, 1, 1 end",
            &["string.gsub", "magic characters"],
        ),
        r(
            "pattern gmatch",
            "function color(s) for w in string.gmatch('abc', '.') do end return 1, 1, 1 end",
            &["string.gmatch", "magic characters"],
        ),
        r("returns inf", "function color(s) return 1/0, 0, 0 end", &["color() returned inf"]),
        r(
            "returns -inf in a vec3",
            "function color(s) return vec3(0, -1/0, 0) end",
            &["returned -inf as its green value"],
        ),
        r("returns NaN", "function color(s) return 0/0, 0, 0 end", &["NaN"]),
        r(
            "memory bomb",
            "function color(s) local s = 'x' for i = 1, 40 do s = s .. s end return 1, 1, 1 end",
            &["ran out of memory"],
        )
        .shader_timeout("20"),
        r("string.rep bomb", "function color(s) return #string.rep('x', 1e12), 0, 0 end", &["string.rep"]),
        r(
            "reserved name",
            "__luster_tick = nil\nfunction color(s) return 1, 1, 1 end",
            &["x.lua:1", "reserved"],
        ),
        r(
            "unterminated string",
            "local a = 'abc\nfunction color(s) return 1, 1, 1 end",
            &["x.lua:1", "unfinished string"],
        ),
        r(
            "unterminated long comment",
            "--[==[ ]]\nfunction color(s) return 1, 1, 1 end",
            &["unfinished long comment"],
        ),
        r("os.execute", "os.execute('touch pwned')", &["os"]),
        r("io.open", "io.open('/etc/passwd')", &["io"]),
        r("require", "require('ffi')", &["require"]),
        r("load", "load('while true do end')()", &["load"]),
        r("string.dump", "string.dump(print)", &["dump"]),
        r("string metatable", "getmetatable('').__index.find = nil", &["x.lua:1"]),
        Case::render("shader not UTF-8", "s.xml", &["x.lua", "not UTF-8"])
            .text("s.xml", shaded("x.lua"))
            .bytes("x.lua", b"-- \xe9\nfunction color(s) return 1, 1, 1 end".to_vec()),
    ]
}

fn leaks() -> Vec<Case> {
    let passwd = "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n";
    let r = |name, scene: &'static str, expect: &[&'static str]| {
        Case::render(name, scene, expect)
            .text("secret", passwd)
            .absent(&["root", "daemon", "/bin", "nologin"])
    };
    vec![
        r("mtllib a password file", "m.obj", &["m.obj", "secret", "line 1"])
            .text("m.obj", obj(Some("secret"))),
        r("mtllib ../../etc/passwd", "m.obj", &["m.obj"])
            .text("m.obj", obj(Some("../../../../../../../../etc/passwd"))),
        r("objFile a password file", "s.xml", &["secret", "line 1", "not an OBJ statement"])
            .text("s.xml", mesh_from("objFile", "secret")),
        r("plyFile a password file", "s.xml", &["secret", "not a PLY file"])
            .text("s.xml", mesh_from("plyFile", "secret")),
        r("texture a password file", "s.xml", &["secret", "cannot decode"]).text("s.xml", imaged("secret")),
        r("scene a password file", "secret", &["secret", "malformed XML"]),
        r("shader a password file", "s.xml", &["secret"]).text("s.xml", shaded("secret")),
        r("map_Kd a password file", "m.obj", &["m.obj"])
            .text("m.obj", obj(Some("m.mtl")))
            .text("m.mtl", "newmtl m\nmap_Kd secret\n"),
        r("MTL garbage before newmtl", "m.obj", &["m.mtl", "line 1", "characters before any newmtl"])
            .text("m.obj", obj(Some("m.mtl")))
            .text("m.mtl", format!("{passwd}newmtl m\n")),
    ]
}

fn images() -> Vec<Case> {
    let r = |name, bytes: Vec<u8>, expect: &[&'static str]| {
        Case::render(name, "s.xml", &[&["t.png"][..], expect].concat())
            .text("s.xml", imaged("t.png"))
            .bytes("t.png", bytes)
    };
    vec![
        r("PNG header of 100000×100000", png_header(100_000, 100_000), &["cannot decode image"]),
        r("PNG header of 4000000000×1", png_header(4_000_000_000, 1), &["cannot decode image"]),
        r("PNG header only", png_header(8, 8), &["cannot decode image"]),
        r("empty image", Vec::new(), &["cannot"]),
        r("text as PNG", b"hello".to_vec(), &["cannot"]),
        r("truncated signature", b"\x89PN".to_vec(), &["cannot"]),
        r("EXR magic only", b"\x76\x2f\x31\x01\x02\0\0\0".to_vec(), &["cannot decode image"]),
        r(
            "HDR header without size",
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n".to_vec(),
            &["cannot decode image"],
        ),
        r("JPEG start only", b"\xff\xd8\xff\xe0\0\x10JFIF\0".to_vec(), &["cannot decode image"]),
    ]
}

fn command_line() -> Vec<Case> {
    let c = |name, args: &[&str], expect: &[&'static str]| {
        Case::render(name, "s.xml", expect).text("s.xml", xml("", "")).args(args)
    };
    vec![
        c(
            "--threads 100000000",
            &["render", "--threads", "100000000", "-o", "{out}", "s.xml"],
            &["--threads", "100000000", "1..=1024"],
        ),
        c("--threads 0", &["render", "--threads", "0", "-o", "{out}", "s.xml"], &["--threads", "1..=1024"]),
        c("--threads -1", &["render", "--threads=-1", "-o", "{out}", "s.xml"], &["--threads"]),
        c("suite --threads 70000", &["suite", "--threads", "70000", "-o", "{out}", "."], &["--threads"]),
        c("bench --threads 5000", &["bench", "--threads", "1,5000", "m.ply"], &["--threads", "5000"]),
    ]
}

pub fn all_cases() -> Vec<Case> {
    [
        special_files(),
        nesting_and_size(),
        malformed_xml(),
        malformed_json(),
        numbers(),
        shaders(),
        leaks(),
        images(),
        command_line(),
        super::terminal::names(),
    ]
    .into_iter()
    .flatten()
    .collect()
}
