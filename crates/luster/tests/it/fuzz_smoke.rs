//! The fuzz smoke run CI does on every build: for each fuzz target
//! ([`luster::fuzzing::Target`], the same entry points the coverage-guided
//! targets in `fuzz/` call) a deterministic mutation loop over seeds from the
//! repository's own fixtures. Mutations are the classic ones (bit flips,
//! interesting bytes, deletions, duplications, splices between seeds) plus
//! tokens each format is sensitive to (`\z`, `[==[`, `1e39`, `element vertex
//! 4294967295`, ...). Any panic fails the test and names the input, which is
//! written to `target/fuzz-smoke/` for replay. The watch server's request
//! parser gets the same loop over request heads (`watch_request`).
//!
//! Each target gets [`ITERATIONS`] inputs or [`BUDGET`] of time, whichever
//! ends first, so the whole run stays well under two minutes. For a long run
//! outside CI, `LUSTER_FUZZ_ITERATIONS` and `LUSTER_FUZZ_SECONDS` override
//! both (per target).

use luster::fuzzing::Target;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Inputs per target (the shader target, which starts a Lua state per input,
/// gets a tenth).
const ITERATIONS: usize = 20_000;

/// Time per target.
const BUDGET: Duration = Duration::from_secs(8);

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

/// A count from the environment, if set.
fn env(name: &str) -> Option<usize> {
    std::env::var(name).ok().map(|v| v.parse().unwrap_or_else(|_| panic!("{name} must be a whole number")))
}

/// The repository's root (this crate sits at `crates/luster`).
fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Files under `dir` (recursively) whose names end with one of `exts`, at most 64 KiB each.
fn files(dir: &Path, exts: &[&str], out: &mut Vec<Vec<u8>>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = rd.flatten().map(|e| e.path()).collect();
    paths.sort();
    for p in paths {
        let meta = std::fs::symlink_metadata(&p).expect("metadata of a fixture");
        if meta.is_dir() {
            files(&p, exts, out);
        } else if meta.is_file()
            && meta.len() <= 65536
            && exts.iter().any(|e| p.to_string_lossy().to_ascii_lowercase().ends_with(e))
        {
            out.push(std::fs::read(&p).expect("a fixture"));
        }
    }
}

/// Seeds and format-specific tokens of a target.
fn seeds(t: Target) -> (Vec<Vec<u8>>, &'static [&'static str]) {
    let (exts, tokens): (&[&str], &[&str]) = match t {
        Target::SceneXml => (
            &[".xml"],
            &[
                "<Mesh id=\"1\">",
                "</",
                "<![CDATA[",
                "&amp;",
                "<!--",
                "1e39",
                "3.4e38",
                "-0",
                "nan",
                "4294967296",
                "<Faces plyFile=\"m.ply\"/>",
                "<Scaling id=\"1\">1e30 1e30 1e30</Scaling>",
            ],
        ),
        Target::SceneJson => (
            &[".json"],
            &[
                "null",
                "{",
                "}",
                "[",
                "]",
                "\"_id\": \"1\", ",
                "1e400",
                "\"\\ud800\"",
                "3.4e38",
                "\"Sphere\": ",
                ",",
                "-1",
            ],
        ),
        Target::Ply => (
            &[".ply"],
            &[
                "element vertex 4294967295\n",
                "element face 3\n",
                "property list uchar int vertex_indices\n",
                "end_header\n",
                "format binary_little_endian 1.0\n",
                "nan ",
                "1e39 ",
                "255 ",
                "\u{ff}\u{ff}\u{7f}\u{0}",
            ],
        ),
        Target::Obj => (
            &[".obj"],
            &[
                "f 1 2 3\n",
                "v 1e39 0 0\n",
                "v 1e9 1e9 1e9\n",
                "f -1 -2 -3\n",
                "f 0 1 2\n",
                "mtllib m.mtl\n",
                "usemtl m\n",
                "\n#-mtl-\nnewmtl m\n",
                "map_Kd /dev/zero\n",
                "Kd 1\n",
                "d -halo 0.5\n",
            ],
        ),
        Target::Image => {
            (&[".png", ".jpg", ".exr", ".hdr"], &["IHDR", "IDAT", "IEND", "\u{0}\u{0}\u{ff}\u{ff}"])
        }
        Target::Shader => (
            &[".lua"],
            &[
                "while true do end",
                "\\z",
                "\r\n",
                "\\\r\n",
                "[[",
                "]]",
                "--[==[",
                "]==]",
                "'",
                "\"",
                "0x1e+",
                "function(",
                "goto l ::l::",
                "pcall(",
                ":find('.-.-b')",
                "1/0",
                "return 0/0",
            ],
        ),
    };
    let mut out = Vec::new();
    for dir in ["crates/luster/tests", "examples", "docs"] {
        files(&repo().join(dir), exts, &mut out);
    }
    if t == Target::Obj {
        // Models with their material library after the marker, as the target reads them.
        out.push(b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 3/1\n#-mtl-\nnewmtl m\nKd 1 0.5 0.2\nNs 10\nmap_Kd t.png\n".to_vec());
    }
    if t == Target::Image {
        // One small image of each format read, encoded here.
        let img = image::DynamicImage::ImageRgb32F(image::ImageBuffer::from_fn(5, 3, |x, y| {
            image::Rgb([x as f32 / 4.0, y as f32 / 2.0, 0.5])
        }));
        for format in [
            image::ImageFormat::Png,
            image::ImageFormat::Jpeg,
            image::ImageFormat::OpenExr,
            image::ImageFormat::Hdr,
        ] {
            let mut bytes = std::io::Cursor::new(Vec::new());
            let encoded = match format {
                image::ImageFormat::Png | image::ImageFormat::Jpeg => {
                    img.to_rgb8().write_to(&mut bytes, format)
                }
                _ => img.write_to(&mut bytes, format),
            };
            encoded.expect("a small image encodes");
            out.push(bytes.into_inner());
        }
    }
    if t == Target::Shader {
        out.push(b"function color(s) local x = 0 for i = 1, 10 do x = x + i end return x, 0, 1 end".to_vec());
    }
    (out, tokens)
}

fn mutate(rng: &mut Rng, seeds: &[Vec<u8>], tokens: &[&str]) -> Vec<u8> {
    let mut d = seeds[rng.below(seeds.len())].clone();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(d.len() + 1);
        match rng.below(7) {
            0 if !d.is_empty() => {
                let i = rng.below(d.len());
                d[i] ^= 1 << rng.below(8);
            }
            1 if !d.is_empty() => {
                const BYTES: &[u8] = b"\0\xff<>\"'{}[]\\\n\r 09-.e=/&;:";
                let i = rng.below(d.len());
                d[i] = BYTES[rng.below(BYTES.len())];
            }
            2 => {
                let end = (at + rng.below(64)).min(d.len());
                d.drain(at..end);
            }
            3 => {
                let start = rng.below(d.len() + 1);
                let end = (start + rng.below(256)).min(d.len());
                let chunk = d[start..end].to_vec();
                d.splice(at..at, chunk);
            }
            4 => {
                let other = &seeds[rng.below(seeds.len())];
                let from = rng.below(other.len() + 1);
                d.truncate(at);
                d.extend_from_slice(&other[from..]);
            }
            _ => {
                let tok = tokens[rng.below(tokens.len())].as_bytes();
                d.splice(at..at, tok.iter().copied());
            }
        }
    }
    d.truncate(1 << 17);
    d
}

#[test]
fn fuzz_smoke_run_finds_no_panic() {
    let mut report = Vec::new();
    let mut crashes = Vec::new();
    for (k, t) in Target::ALL.into_iter().enumerate() {
        let (seeds, tokens) = seeds(t);
        assert!(!seeds.is_empty(), "no seeds for {}", t.name());
        let iterations = env("LUSTER_FUZZ_ITERATIONS").unwrap_or(ITERATIONS);
        let iterations = if t == Target::Shader { iterations / 10 } else { iterations };
        let budget = env("LUSTER_FUZZ_SECONDS").map_or(BUDGET, |s| Duration::from_secs(s as u64));
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ (k as u64 + 1));
        let start = Instant::now();
        let mut runs = 0;
        // The seeds themselves first, then mutants.
        let inputs = seeds.iter().cloned().chain(std::iter::repeat_with(|| mutate(&mut rng, &seeds, tokens)));
        for input in inputs.take(iterations) {
            runs += 1;
            if std::panic::catch_unwind(|| t.run(&input)).is_err() {
                let dir = repo().join("target").join("fuzz-smoke");
                let _ = std::fs::create_dir_all(&dir);
                let file = dir.join(format!("crash-{}-{runs}", t.name()));
                let _ = std::fs::write(&file, &input);
                crashes.push(format!("{} panicked on input {runs} (saved as {})", t.name(), file.display()));
            }
            if start.elapsed() > budget {
                break;
            }
        }
        report.push(format!("{}: {runs} inputs in {:.1} s", t.name(), start.elapsed().as_secs_f64()));
    }
    println!("fuzz smoke run:\n  {}", report.join("\n  "));
    assert!(crashes.is_empty(), "{}", crashes.join("\n"));
}

/// Part files of split renders ([`luster::cluster::partfile::fuzz`], whose
/// target is in `luster` rather than `luster::fuzzing`): valid part files
/// and a checkpoint as seeds, counts and the magic word as tokens. Most
/// mutants fail the header's checks or the checksum, which is the point.
#[test]
fn partfile_fuzz_smoke_run_finds_no_panic() {
    use luster::cluster::partfile::{fuzz, pixels_in, PartFile};
    use luster::math::Vec3;
    use luster::tonemap::{Display, Tonemap};
    let mut seeds = Vec::new();
    for (w, h, n, k, tiles, tonemaps) in [
        (8, 8, 1, 1, vec![0], vec![]),
        (40, 20, 3, 2, vec![1, 4], vec![Tonemap::COURSE_DEFAULT]),
        (33, 17, 2, 1, vec![0, 2, 4], vec![Tonemap::COURSE_DEFAULT, Tonemap::DISPLAY]),
        (5, 5, 4, 4, vec![], vec![]),
    ] {
        let p = pixels_in(&tiles, w, h);
        let part = PartFile {
            finished: k != 4,
            job: [3; 32],
            n,
            k,
            images: 1,
            image: 0,
            width: w,
            height: h,
            image_name: "f.png".into(),
            tonemaps,
            display: Display::Srgb,
            tiles,
            pixels: (0..p).map(|i| Vec3::new(i as f32, 0.5, 2.0)).collect(),
            passes: Default::default(),
            aov: Vec::new(),
        };
        seeds.push(part.encode());
    }
    // Counts of one, two and 2^31-1, the version, a tile edge.
    let tokens: &[&str] = &[
        "LUSTPART",
        "\u{1}\0\0\0",
        "\u{2}\0\0\0",
        "\u{3}\0\0\0",
        "\u{7f}\u{7f}\u{7f}\u{7f}",
        "\u{10}\0\0\0",
    ];
    let iterations = env("LUSTER_FUZZ_ITERATIONS").unwrap_or(ITERATIONS);
    let budget = env("LUSTER_FUZZ_SECONDS").map_or(BUDGET, |s| Duration::from_secs(s as u64));
    let mut rng = Rng(0x005e_ed0f_9a27_f11e);
    let start = Instant::now();
    let (mut runs, mut crashes) = (0, Vec::new());
    let inputs = seeds.iter().cloned().chain(std::iter::repeat_with(|| mutate(&mut rng, &seeds, tokens)));
    for input in inputs.take(iterations) {
        runs += 1;
        if std::panic::catch_unwind(|| fuzz(&input)).is_err() {
            let dir = repo().join("target").join("fuzz-smoke");
            let _ = std::fs::create_dir_all(&dir);
            let file = dir.join(format!("crash-partfile-{runs}"));
            let _ = std::fs::write(&file, &input);
            crashes.push(format!("partfile panicked on input {runs} (saved as {})", file.display()));
        }
        if start.elapsed() > budget {
            break;
        }
    }
    println!("fuzz smoke run: partfile: {runs} inputs in {:.1} s", start.elapsed().as_secs_f64());
    assert!(crashes.is_empty(), "{}", crashes.join("\n"));
}

/// Request heads as browsers and tools send them to `luster watch`.
const WATCH_REQUESTS: &[&str] = &[
    "GET /state HTTP/1.1\r\nHost: 127.0.0.1:8795\r\n\r\n",
    "GET /frame.png?n=12 HTTP/1.1\r\nHost: localhost:8795\r\nConnection: keep-alive\r\nUser-Agent: Mozilla/5.0\r\n\
     Accept: */*\r\nSec-Fetch-Site: same-origin\r\nCookie: a=1; b=2\r\n\r\n",
    "GET /events HTTP/1.1\r\nHost: [::1]:8795\r\nAccept: text/event-stream\r\n\r\n",
    "POST /shader HTTP/1.1\r\nHost: 127.0.0.1:8795\r\nOrigin: http://127.0.0.1:8795\r\nContent-Length: 5\r\n\
     Expect: 100-continue\r\n\r\nhelloHEAD / HTTP/1.0\r\nHost: localhost\r\nConnection: close\r\n\r\n",
];

/// Tokens the request parser is sensitive to.
const WATCH_TOKENS: &[&str] = &[
    "\r\n",
    "\r\n\r\n",
    "\n",
    " ",
    "\0",
    "Content-Length: ",
    "Content-Length: 4\r\n",
    "99999999999999999999",
    "Transfer-Encoding: chunked\r\n",
    "Host: ",
    ":8795",
    "Origin: null\r\n",
    "Expect: 100-continue\r\n",
    "Connection: close\r\n",
    "HTTP/1.1",
    "\u{ff}",
];

#[test]
fn watch_request_smoke_run_finds_no_panic() {
    let seeds: Vec<Vec<u8>> = WATCH_REQUESTS.iter().map(|s| s.as_bytes().to_vec()).collect();
    let iterations = env("LUSTER_FUZZ_ITERATIONS").unwrap_or(ITERATIONS);
    let budget = env("LUSTER_FUZZ_SECONDS").map_or(BUDGET, |s| Duration::from_secs(s as u64));
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ 0x77);
    let start = Instant::now();
    let inputs =
        seeds.iter().cloned().chain(std::iter::repeat_with(|| mutate(&mut rng, &seeds, WATCH_TOKENS)));
    let mut runs = 0;
    for input in inputs.take(iterations) {
        runs += 1;
        if std::panic::catch_unwind(|| luster::watch::request::fuzz(&input)).is_err() {
            let dir = repo().join("target").join("fuzz-smoke");
            let _ = std::fs::create_dir_all(&dir);
            let file = dir.join(format!("crash-watch_request-{runs}"));
            let _ = std::fs::write(&file, &input);
            panic!("watch_request panicked on input {runs} (saved as {})", file.display());
        }
        if start.elapsed() > budget {
            break;
        }
    }
    println!("fuzz smoke run: watch_request: {runs} inputs in {:.1} s", start.elapsed().as_secs_f64());
}
