//! What the integration tests share.

use std::path::{Path, PathBuf};

/// The course folder beside the repository, when it is there.
///
/// Without it a golden test cannot run. On a developer's machine it says so
/// and skips; on CI (`CI=true`, as every CI service sets it) a missing folder
/// is a broken checkout, and the test fails rather than pass unseen.
#[allow(dead_code)] // the golden tests use it, the others do not
pub fn course_root(what: &str) -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/ceng795");
    if root.is_dir() {
        return Some(root);
    }
    let on_ci = std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1");
    assert!(
        !on_ci,
        "CI=true but {} is missing, so the {what} golden images cannot be checked",
        root.display()
    );
    eprintln!("skipped: {} is absent, so the {what} golden images were not checked", root.display());
    None
}

/// Writes `files` (name, text) into a fresh temporary folder; returns it.
#[allow(dead_code)] // not every test crate that shares this module writes files
pub fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a temporary folder");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("a test file");
    }
    dir
}

/// How a run of the luster binary ended: its exit code (`None` when it was
/// killed at the time limit or by a signal) and everything it wrote.
#[allow(dead_code)] // only the command-line tests run the binary
pub struct Run {
    /// Exit code.
    pub code: Option<i32>,
    /// Standard output, lossily decoded.
    pub stdout: String,
    /// Standard error, lossily decoded.
    pub stderr: String,
}

/// Runs `cmd` with no backtraces, stdin closed and both outputs captured,
/// killing it after `limit`, so a hang fails a test instead of stalling the
/// suite.
#[allow(dead_code)] // only the command-line tests run the binary
pub fn run_limited(mut cmd: std::process::Command, limit: std::time::Duration) -> Run {
    use std::io::Read;
    use std::process::Stdio;
    let mut child = cmd
        .env_remove("RUST_BACKTRACE")
        .env_remove("RUST_LIB_BACKTRACE")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the luster binary starts");
    // Each pipe drained on its own thread, so a full one never stalls the child.
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            String::from_utf8_lossy(&bytes).into_owned()
        })
    };
    let out = drain(Box::new(child.stdout.take().expect("stdout is piped")));
    let err = drain(Box::new(child.stderr.take().expect("stderr is piped")));
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("waiting for luster") {
            break Some(status);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    Run {
        code: status.and_then(|s| s.code()),
        stdout: out.join().unwrap_or_default(),
        stderr: err.join().unwrap_or_default(),
    }
}

/// Writes `sky.exr` into `dir`: a constant-radiance lat-long sky of radiance
/// 1, for white furnaces.
pub fn white_sky(dir: &Path) {
    let img = image::Rgb32FImage::from_pixel(16, 8, image::Rgb([1.0, 1.0, 1.0]));
    image::DynamicImage::ImageRgb32F(img).save(dir.join("sky.exr")).expect("EXR written");
}

/// The mean of two seeds' renders of the same values `a` and `b` (pixel by
/// pixel), and its standard error: the pixels' differences give each
/// pixel's variance (var(a − b) = 2σ²) without assuming the pixels share
/// one true value, and the mean of 2n estimates has error σ / sqrt(2n).
pub fn two_seed_mean(a: &[f64], b: &[f64]) -> (f64, f64) {
    let n = a.len() as f64;
    let var = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / (2.0 * n);
    let mean = (a.iter().sum::<f64>() + b.iter().sum::<f64>()) / (2.0 * n);
    (mean, (var / (2.0 * n)).sqrt())
}

/// Writes `files` (name, text) and the scene `text` as `s.xml` into `dir`,
/// and loads the scene.
#[allow(dead_code)]
pub fn load_with(dir: &Path, text: &str, files: &[(&str, &str)]) -> luster::scene::Description {
    for (name, body) in files {
        std::fs::write(dir.join(name), body).expect("temp file");
    }
    let p = dir.join("s.xml");
    std::fs::write(&p, text).expect("temp file");
    luster::scene::load(&p).expect("scene loads")
}

/// The first camera's image of `desc` at `spp` samples per pixel and `seed`.
#[allow(dead_code)]
pub fn render_spp(desc: &luster::scene::Description, spp: u32, seed: u32) -> luster::render::RenderedImage {
    use luster::render::{render_with, RenderOptions, Scene};
    let scene = Scene::build(desc).expect("scene builds");
    render_with(&scene, 0, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {})
}

/// A black-lit plane `y = 0` seen at a grazing angle (from `(0, 1, 0)`
/// towards `(0, gaze_y, -4)`), shaded only by the `replace_all` shader
/// `shader` with the number parameter `param = value`: the scene the
/// antialiasing tests render at 1 sample against a converged reference.
pub fn grazing_plane(width: u32, height: u32, gaze_y: f32, shader: &str, param: &str, value: &str) -> String {
    format!(
        r#"<Scene>
    <BackgroundColor>0 0 0</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0 1 0</Position><GazePoint>0 {gaze_y} -4</GazePoint><Up>0 1 0</Up>
            <FovY>50</FovY><NearDistance>1</NearDistance>
            <ImageResolution>{width} {height}</ImageResolution><ImageName>out.png</ImageName>
        </Camera>
    </Cameras>
    <Lights><AmbientLight>0 0 0</AmbientLight></Lights>
    <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
    <Textures>
        <TextureMap id="1" type="shader">
            <Shader>{shader}</Shader>
            <DecalMode>replace_all</DecalMode>
            <Parameter name="{param}">{value}</Parameter>
        </TextureMap>
    </Textures>
    <VertexData>0 0 0</VertexData>
    <Objects>
        <Plane id="1"><Material>1</Material><Textures>1</Textures><Point>1</Point><Normal>0 1 0</Normal></Plane>
    </Objects>
</Scene>"#
    )
}

/// The 8-bit image of the scene file `path`'s first camera at `spp`
/// samples per pixel and sampler seed `seed`.
pub fn render_rgb8(path: &Path, spp: u32, seed: u32) -> Vec<u8> {
    let desc = luster::scene::load(path).expect("the scene loads");
    let s = luster::render::Scene::build(&desc).expect("the scene builds");
    let opts = luster::render::RenderOptions { spp: Some(spp), seed, ..Default::default() };
    luster::render::try_render_with(&s, 0, &opts, &|_| {}).expect("no shader fails").to_rgb8()
}

/// Peak signal-to-noise ratio of two 8-bit images, in dB.
pub fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let mse =
        a.iter().zip(b).map(|(x, y)| (f64::from(*x) - f64::from(*y)).powi(2)).sum::<f64>() / a.len() as f64;
    10.0 * (255.0f64 * 255.0 / mse).log10()
}
