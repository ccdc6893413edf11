//! The case language of the hostile-input corpus (`hostile.rs`): a case
//! is a few files written into a fresh folder (text, bytes, FIFOs, links to
//! devices, sparse files of absurd size), the command line to run there, and
//! what the one-line error must say.

use std::path::Path;

/// What to put at a path of a case's folder.
pub enum Content {
    /// A file with these bytes.
    Bytes(Vec<u8>),
    /// A named pipe no one writes to: reading it would block forever.
    Fifo,
    /// A symbolic link to this target (such as `/dev/zero`).
    Link(&'static str),
    /// An empty folder.
    Dir,
    /// A sparse file of this many bytes (no disk used): only its size is absurd.
    Sparse(u64),
}

/// One hostile input.
pub struct Case {
    /// Name, for failure messages.
    pub name: &'static str,
    /// Files of the case's folder.
    pub files: Vec<(&'static str, Content)>,
    /// Arguments after `luster`; `{out}` is the output folder.
    pub args: Vec<String>,
    /// Substrings the error line must hold.
    pub expect: Vec<&'static str>,
    /// Substrings it must not hold (contents of files that must not leak).
    pub absent: Vec<&'static str>,
    /// Whether the error may span several lines (clap's usage errors).
    pub multiline: bool,
}

impl Case {
    /// `luster render -q --threads 2 -o {out} SCENE`, expecting these words.
    pub fn render(name: &'static str, scene: &str, expect: &[&'static str]) -> Case {
        Case {
            name,
            files: Vec::new(),
            args: ["render", "-q", "--threads", "2", "--shader-timeout", "0.3", "-o", "{out}", scene]
                .map(String::from)
                .to_vec(),
            expect: expect.to_vec(),
            absent: Vec::new(),
            multiline: false,
        }
    }

    /// Adds a text file.
    pub fn text(mut self, path: &'static str, text: impl Into<String>) -> Case {
        self.files.push((path, Content::Bytes(text.into().into_bytes())));
        self
    }

    /// Adds a file of bytes.
    pub fn bytes(mut self, path: &'static str, bytes: Vec<u8>) -> Case {
        self.files.push((path, Content::Bytes(bytes)));
        self
    }

    /// Adds a special file.
    pub fn special(mut self, path: &'static str, content: Content) -> Case {
        self.files.push((path, content));
        self
    }

    /// Runs with this `--shader-timeout` (seconds) instead of 0.3 s: for a
    /// case that must fail by another limit first, however loaded the machine.
    pub fn shader_timeout(mut self, seconds: &str) -> Case {
        if let Some(i) = self.args.iter().position(|a| a == "--shader-timeout") {
            self.args[i + 1] = seconds.to_string();
        }
        self
    }

    /// Words that must not appear.
    pub fn absent(mut self, words: &[&'static str]) -> Case {
        self.absent.extend_from_slice(words);
        self
    }

    /// Replaces the arguments.
    pub fn args(mut self, args: &[&str]) -> Case {
        self.args = args.iter().map(|a| a.to_string()).collect();
        self.multiline = true;
        self
    }

    /// Writes the case's files under `dir`.
    pub fn materialize(&self, dir: &Path) {
        for (path, content) in &self.files {
            let p = dir.join(path);
            if let Some(parent) = p.parent() {
                std::fs::create_dir_all(parent).expect("a case folder");
            }
            match content {
                Content::Bytes(b) => std::fs::write(&p, b).expect("a case file"),
                Content::Fifo => {
                    let ok = std::process::Command::new("mkfifo").arg(&p).status().expect("mkfifo runs");
                    assert!(ok.success(), "mkfifo {}", p.display());
                }
                Content::Link(target) => std::os::unix::fs::symlink(target, &p).expect("a link"),
                Content::Dir => std::fs::create_dir_all(&p).expect("a folder"),
                Content::Sparse(len) => {
                    std::fs::File::create(&p).and_then(|f| f.set_len(*len)).expect("a sparse file")
                }
            }
        }
    }
}

/// A small valid XML scene (8×8 camera, one light, material 1, vertices 1 to
/// 3 around z = -3, sphere 1 of radius 2 at vertex 1, filling the view) with `objects` in `<Objects>` (the
/// sphere when empty) and `extra` before `</Scene>`.
pub fn xml(objects: &str, extra: &str) -> String {
    let objects = if objects.is_empty() {
        r#"<Sphere id="1"><Material>1</Material><Center>1</Center><Radius>2</Radius></Sphere>"#
    } else {
        objects
    };
    format!(
        r#"<Scene>
  <Cameras>
    <Camera id="1">
      <Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
      <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance>
      <ImageResolution>8 8</ImageResolution><ImageName>out.png</ImageName>
    </Camera>
  </Cameras>
  <Lights>
    <AmbientLight>25 25 25</AmbientLight>
    <PointLight id="1"><Position>0 0 0</Position><Intensity>1000 1000 1000</Intensity></PointLight>
  </Lights>
  <Materials>
    <Material id="1">
      <AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
      <SpecularReflectance>1 1 1</SpecularReflectance><PhongExponent>1</PhongExponent>
    </Material>
  </Materials>
  <VertexData>0 0 -3 1 0 -3 0 1 -3</VertexData>
  <Objects>
    {objects}
  </Objects>
{extra}
</Scene>
"#
    )
}

/// The XML scene with a texture map on sphere 1: `map` is the `<Textures>`
/// body, whose texture map must have id 5.
pub fn textured(map: &str) -> String {
    xml(
        r#"<Sphere id="1"><Material>1</Material><Textures>5</Textures><Center>1</Center><Radius>2</Radius></Sphere>"#,
        &format!("<Textures>{map}</Textures>"),
    )
}

/// The XML scene shading sphere 1 with the script at `path`.
pub fn shaded(path: &str) -> String {
    textured(&format!(
        r#"<TextureMap id="5" type="shader"><Shader>{path}</Shader><DecalMode>replace_kd</DecalMode></TextureMap>"#
    ))
}

/// The XML scene with an image texture read from `path`.
pub fn imaged(path: &str) -> String {
    textured(&format!(
        r#"<Images><Image id="1">{path}</Image></Images>
<TextureMap id="5" type="image"><ImageId>1</ImageId><DecalMode>replace_kd</DecalMode></TextureMap>"#
    ))
}

/// The XML scene with one mesh whose faces come from `attr="file"`.
pub fn mesh_from(attr: &str, file: &str) -> String {
    xml(&format!(r#"<Mesh id="1"><Material>1</Material><Faces {attr}="{file}"/></Mesh>"#), "")
}

/// A small valid JSON scene (as [`xml`]) with `objects` as the body of `"Objects"`.
pub fn json(objects: &str) -> String {
    format!(
        r#"{{"Scene": {{
  "Cameras": {{"Camera": {{"_id": "1", "Position": "0 0 0", "Gaze": "0 0 -1", "Up": "0 1 0",
    "NearPlane": "-1 1 -1 1", "NearDistance": "1", "ImageResolution": "8 8", "ImageName": "out.png"}}}},
  "Lights": {{"AmbientLight": "25 25 25",
    "PointLight": {{"_id": "1", "Position": "0 0 0", "Intensity": "1000 1000 1000"}}}},
  "Materials": {{"Material": {{"_id": "1", "AmbientReflectance": "1 1 1", "DiffuseReflectance": "1 1 1",
    "SpecularReflectance": "1 1 1", "PhongExponent": "1"}}}},
  "VertexData": {{"_data": "0 0 -3 1 0 -3 0 1 -3", "_type": "xyz"}},
  "Objects": {objects}
}}}}
"#
    )
}

/// The sphere of [`json`]'s default scene.
pub const JSON_SPHERE: &str = r#"{"Sphere": {"_id": "1", "Material": "1", "Center": "1", "Radius": "0.5"}}"#;

/// An OBJ triangle using material `m` from `mtl` (when given).
pub fn obj(mtl: Option<&str>) -> String {
    let lib = mtl.map_or(String::new(), |m| format!("mtllib {m}\nusemtl m\n"));
    format!("{lib}v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
}

/// A PNG of `width`×`height` with only a signature and a header chunk: enough
/// for a decoder to learn the size it would have to allocate.
pub fn png_header(width: u32, height: u32) -> Vec<u8> {
    let mut chunk = b"IHDR".to_vec();
    chunk.extend_from_slice(&width.to_be_bytes());
    chunk.extend_from_slice(&height.to_be_bytes());
    chunk.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend_from_slice(&13u32.to_be_bytes());
    png.extend_from_slice(&chunk);
    png.extend_from_slice(&crc32(&chunk).to_be_bytes());
    png
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xedb8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// `check` of every case, two cases at a time (they are independent, and
/// most of their time is the process start); what went wrong, in order.
pub fn check_two_at_a_time<T: Sync>(cases: &[T], check: impl Fn(&T) -> Option<String> + Sync) -> Vec<String> {
    std::thread::scope(|s| {
        let workers: Vec<_> = (0..2)
            .map(|k| {
                let check = &check;
                s.spawn(move || cases.iter().skip(k).step_by(2).filter_map(check).collect::<Vec<_>>())
            })
            .collect();
        workers.into_iter().flat_map(|w| w.join().expect("a worker")).collect()
    })
}
