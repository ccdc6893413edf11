//! The command line's shared argument types and value parsers: the OBJ
//! model view (`--size`, `--azimuth`, `--elevation`, `--fov`, `--distance`,
//! `--no-ground`, `--display`), glTF material overrides (`--material`), the
//! HDRI (`--env`, `--env-rotate`, `--env-strength`), `--filter`, `--threads`, `--shader-lib`,
//! `--shader-timeout`, and the worker pool they configure.

use luster::scene::gltf::material::MaterialOverride;
use std::path::PathBuf;
use std::process::ExitCode;

/// A `--shader-lib` folder: one that exists.
pub(super) fn parse_shader_lib(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if p.is_dir() {
        Ok(p)
    } else {
        Err(format!("{s} is not a folder"))
    }
}

/// A `--shader-timeout`: positive seconds, at most a day.
pub(super) fn parse_timeout(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t <= 86_400.0 => Ok(t),
        Ok(t) => Err(format!("{t} is not a time limit (expected seconds, more than 0 and at most 86400)")),
        Err(_) => Err(format!("\"{s}\" is not a number of seconds")),
    }
}

/// How `luster render` looks at an OBJ model (see `luster::scene::obj::model`).
#[derive(clap::Args)]
#[command(next_help_heading = "OBJ models")]
pub(super) struct ModelArgs {
    /// Image size: of a model's render (default 800x600), or of every camera
    /// of a scene, keeping its view.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub(super) size: Option<(u32, u32)>,
    /// Camera direction around the model, degrees from the front (+z), positive to the right.
    #[arg(long, value_name = "DEG", default_value_t = 35.0, allow_negative_numbers = true)]
    azimuth: f32,
    /// Camera height, degrees above the horizon (-89 to 89).
    #[arg(long, value_name = "DEG", default_value_t = 25.0, allow_negative_numbers = true,
          value_parser = parse_elevation)]
    elevation: f32,
    /// Vertical field of view, degrees.
    #[arg(long, value_name = "DEG", default_value_t = 40.0, value_parser = parse_fov)]
    fov: f32,
    /// Camera distance from the model's centre, in model units (default: the
    /// model's bounding sphere fills the view with a 10% margin).
    #[arg(long, value_name = "UNITS", value_parser = parse_distance)]
    distance: Option<f32>,
    /// Leave out the ground plane under the model.
    #[arg(long)]
    no_ground: bool,
    /// Display transform of the 8-bit images, replacing the scene's
    /// <Display> (a model's default is srgb; a course scene's, course): course
    /// (linear values clamped, as the course's images), or a linear workflow
    /// (8-bit colour textures sRGB-decoded) ending in srgb, aces or filmic.
    #[arg(long, value_name = "MODE", value_parser = parse_display, help_heading = "Output")]
    display: Option<luster::tonemap::Display>,
    /// Replace the glTF material NAME by a Lua material shader (its
    /// material(s) closure or material outputs); repeatable. The path is
    /// relative to the current folder.
    #[arg(long = "material", value_name = "NAME=FILE.lua", value_parser = parse_material,
          help_heading = "glTF scenes")]
    materials: Vec<MaterialOverride>,
}

impl ModelArgs {
    pub(super) fn view(&self) -> luster::scene::obj::ModelView {
        luster::scene::obj::ModelView {
            width: self.size.map_or(800, |s| s.0),
            height: self.size.map_or(600, |s| s.1),
            sized: self.size.is_some(),
            azimuth: self.azimuth,
            elevation: self.elevation,
            fov_y: self.fov,
            distance: self.distance,
            ground: !self.no_ground,
            display: self.display,
            material_shaders: self.materials.clone(),
            ..Default::default()
        }
    }
}

/// An HDRI lighting the scene (see `luster::scene::hdri`).
#[derive(clap::Args)]
#[command(next_help_heading = "HDRI lighting")]
pub(super) struct EnvArgs {
    /// A latitude-longitude HDR image (.hdr or .exr; 1.0 is display white)
    /// that lights the scene and is its background, replacing a
    /// SphericalDirectionalLight or a model's studio lights.
    #[arg(long, value_name = "FILE")]
    env: Option<PathBuf>,
    /// Turns the HDRI about the vertical axis, degrees counter-clockwise
    /// seen from above (0: as Blender's world shows it).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_negative_numbers = true,
          requires = "env", value_parser = parse_env_rotate)]
    env_rotate: f32,
    /// Scales the HDRI's radiance (0 to 1e36).
    #[arg(long, value_name = "S", default_value_t = 1.0, allow_negative_numbers = true, requires = "env",
          value_parser = parse_env_strength)]
    env_strength: f32,
}

impl EnvArgs {
    /// The HDRI, if `--env` names one; an error is one sentence naming the file.
    pub(super) fn hdri(&self) -> Result<Option<luster::scene::hdri::Hdri>, luster::scene::SceneError> {
        self.env
            .as_deref()
            .map(|p| luster::scene::hdri::Hdri::new(p, self.env_rotate, self.env_strength))
            .transpose()
    }
}

/// An `--env-rotate`: finite degrees.
pub(super) fn parse_env_rotate(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if d.is_finite() => Ok(d),
        _ => Err(format!("\"{}\" is not a number of degrees", luster_core::text::shown(s, false))),
    }
}

/// An `--env-strength`: from 0 to 1e36 (255 times it must stay finite).
pub(super) fn parse_env_strength(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if (0.0..=1e36).contains(&v) => Ok(v),
        _ => Err(format!(
            "\"{}\" is not a strength (a number from 0 to 1e36)",
            luster_core::text::shown(s, false)
        )),
    }
}

/// A `--material NAME=FILE.lua`: a material name (up to the first `=`)
/// and a script file that exists.
pub(super) fn parse_material(s: &str) -> Result<MaterialOverride, String> {
    let shown = |t: &str| luster_core::text::shown(t, false).into_owned();
    let Some((name, file)) = s.split_once('=').filter(|(n, f)| !n.is_empty() && !f.is_empty()) else {
        return Err(format!(
            "\"{}\" is not NAME=FILE.lua (a glTF material's name and a Lua script)",
            shown(s)
        ));
    };
    let script = PathBuf::from(file);
    if !script.is_file() {
        return Err(format!("cannot read shader script {}: no such file", shown(file)));
    }
    Ok(MaterialOverride { name: name.to_string(), script })
}

/// A `--display` mode.
pub(super) fn parse_display(s: &str) -> Result<luster::tonemap::Display, String> {
    luster::tonemap::Display::parse(s).ok_or_else(|| {
        format!("\"{s}\" is not a display transform (expected {})", luster::tonemap::Display::NAMES)
    })
}

/// A `--size`: `WIDTHxHEIGHT`, 1 to 16384 pixels a side.
pub(super) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) =
        s.split_once(['x', 'X']).ok_or_else(|| format!("\"{s}\" is not WIDTHxHEIGHT (e.g. 800x600)"))?;
    let side = |t: &str| t.trim().parse::<u32>().ok().filter(|&v| (1..=16384).contains(&v));
    match (side(w), side(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("\"{s}\" is not WIDTHxHEIGHT with 1 to 16384 pixels a side")),
    }
}

/// A number of degrees within `lo..=hi` (`open`: both ends excluded).
fn degrees(s: &str, lo: f32, hi: f32, open: bool) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if (open && d > lo && d < hi) || (!open && d >= lo && d <= hi) => Ok(d),
        _ => Err(format!("\"{s}\" is not a number of degrees between {lo} and {hi}")),
    }
}

pub(super) fn parse_elevation(s: &str) -> Result<f32, String> {
    degrees(s, -89.0, 89.0, false)
}

pub(super) fn parse_fov(s: &str) -> Result<f32, String> {
    degrees(s, 0.0, 180.0, true)
}

/// A `--distance`: a positive number.
pub(super) fn parse_distance(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(d) if d > 0.0 && d.is_finite() => Ok(d),
        _ => Err(format!("\"{s}\" is not a positive distance")),
    }
}

/// The `--filter` choices.
#[derive(Clone, Copy, clap::ValueEnum)]
pub(super) enum FilterArg {
    Box,
    Gaussian,
}

impl FilterArg {
    pub(super) fn filter(self) -> luster::render::Filter {
        match self {
            FilterArg::Box => luster::render::Filter::Box,
            FilterArg::Gaussian => luster::render::Filter::Gaussian,
        }
    }
}

/// Most worker threads accepted: far beyond any machine's cores, and far
/// below the point where starting threads exhausts the system.
pub(super) const MAX_THREADS: u64 = 1024;

/// Thread counts from 1 to [`MAX_THREADS`].
pub(super) fn threads_parser() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(1..=MAX_THREADS)
}

/// A rayon pool of `threads` workers (all cores when `None`), with the
/// stack shaders need: the scene is built and shaded on these workers.
pub(super) fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool, ExitCode> {
    let builder = rayon::ThreadPoolBuilder::new().num_threads(threads.unwrap_or(0));
    builder.stack_size(luster::shader::STACK_SIZE).build().map_err(|e| {
        eprintln!("error: cannot start worker threads: {e}");
        ExitCode::from(2)
    })
}
