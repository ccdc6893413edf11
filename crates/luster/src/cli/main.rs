//! The `luster` command line: a thin layer over the library.

/// `println!` that ignores a closed stdout (`luster suite ... | head`), so a
/// reader that stops early cannot turn into a panic; what matters (files,
/// the exit code) still happens.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

/// Prints `kind: msg` on stderr (`error`, `warning`), with what a user or a
/// file controls made printable and capped (`luster::text::shown`): a name
/// or a shader's message cannot drive the terminal or forge lines.
fn report(kind: &str, msg: &dyn std::fmt::Display) {
    eprintln!("{kind}: {}", luster::text::shown(&msg.to_string(), false));
}

mod args;
mod compare;
mod merge;
mod part;
mod passes;
mod reframe;
mod render;
mod signal;
mod slurm;
mod suite;
mod tonemap;
mod watch;

use args::*;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// luster — a ray tracer for CENG795 scenes and procedural shaders.
#[derive(Parser)]
#[command(version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render scenes (CENG795 XML or JSON, glTF) or OBJ models; writes one image per camera.
    ///
    /// Each camera's image goes to OUTDIR/<ImageName>. An .obj file is
    /// rendered on its own, framed by a camera with a studio light setup, to
    /// OUTDIR/<stem>.png; the model flags below set that view. Errors in one
    /// scene are reported and the others still render; the exit code is 2 if
    /// any failed.
    Render {
        /// Scene files (.xml or .json), glTF scenes (.gltf, .glb) or OBJ models (.obj).
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Folder for the images (created if needed).
        #[arg(short, long, default_value = ".")]
        outdir: PathBuf,
        /// Worker threads (default: all cores; at most 1024).
        #[arg(short, long, value_parser = threads_parser())]
        threads: Option<usize>,
        /// Print no progress bar and no summary, only errors and warnings.
        #[arg(short, long)]
        quiet: bool,
        /// Samples per pixel, overriding each camera's NumSamples (for previews).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
        spp: Option<u32>,
        /// Seed of every random choice: another seed gives other noise, not another image.
        #[arg(long, default_value_t = 0)]
        seed: u32,
        /// Reconstruction filter: box (plain average) or gaussian (σ = 1/3 pixel).
        #[arg(long, value_enum, default_value_t = FilterArg::Box)]
        filter: FilterArg,
        /// Time limit of one shader call, in seconds; a call that runs past it
        /// stops the render with an error naming the shader.
        #[arg(long, value_name = "SECONDS", value_parser = parse_timeout,
              default_value_t = luster::shader::DEFAULT_TIMEOUT.as_secs_f64())]
        shader_timeout: f64,
        /// A folder shaders' `require "name"` searches, after the scene's
        /// folder and its <ShaderLibrary> folders (repeatable).
        #[arg(long = "shader-lib", value_name = "DIR", value_parser = parse_shader_lib)]
        shader_lib: Vec<PathBuf>,
        /// Render only part K of N of the images (for a cluster: see `luster
        /// slurm`), into OUTDIR/<ImageName>.part-K-of-N; `luster merge OUTDIR`
        /// then writes the images. Not with --size, --scale, --crop or --time (a part
        /// file records the scene's own cameras).
        #[arg(long, value_name = "K/N", conflicts_with_all = ["size", "scale", "crop", "time"])]
        part: Option<luster::cluster::Part>,
        /// With --part: keep this render's finished part files and continue
        /// from its checkpoints (a killed or requeued part loses little work).
        #[arg(long, requires = "part")]
        resume: bool,
        /// With --resume: least time between two checkpoints.
        #[arg(long, value_name = "SECONDS", default_value_t = 60, requires = "resume")]
        checkpoint: u64,
        /// Render each camera for about this many seconds: samples are taken
        /// in passes over the whole image, and the render stops before a pass
        /// that would end later (at least one sample per pixel; never more
        /// than the camera's or --spp's count). Prints the samples used.
        #[arg(long, value_name = "SECONDS", value_parser = parse_timeout)]
        time: Option<f64>,
        /// Which camera of a glTF file to render, numbered from 0 in the
        /// order of the scene's nodes (default: the first, or a framing
        /// camera when the file has none).
        #[arg(long, value_name = "N")]
        camera: Option<usize>,
        /// Denoise each image with Intel Open Image Denoise before writing it
        /// (a build with `--features oidn`; see docs/denoising.md). Not with
        /// --part: the denoiser needs the whole image.
        #[arg(long, conflicts_with = "part")]
        denoise: bool,
        #[command(flatten)]
        model: ModelArgs,
        #[command(flatten)]
        env: EnvArgs,
        #[command(flatten)]
        frame: reframe::FrameArgs,
        #[command(flatten)]
        passes: passes::PassArgs,
    },
    /// Preview a scene live in the browser, re-rendering whenever its files are saved.
    ///
    /// Serves a page on http://127.0.0.1:PORT/ that shows one camera's image
    /// as it refines (a 1-spp pass at a quarter of the resolution, then
    /// passes up to the camera's NumSamples or --spp), the pass and spp, and
    /// any error over the last good image. Saving the scene, a shader, a
    /// texture image or a PLY mesh it reads cancels the render and starts
    /// again. Runs until Ctrl-C; exit code 2 when the page cannot be served.
    Watch {
        /// The scene file (.xml or .json) or OBJ model (.obj).
        scene: PathBuf,
        /// Port of the page on 127.0.0.1 (0: any free port; the address is printed).
        #[arg(long, default_value_t = 8795)]
        port: u16,
        /// Which camera, numbered from 0 in the scene's order.
        #[arg(long, default_value_t = 0)]
        camera: usize,
        /// Worker threads (default: all cores; at most 1024).
        #[arg(short, long, value_parser = threads_parser())]
        threads: Option<usize>,
        /// Samples per pixel to refine to, overriding the camera's NumSamples.
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
        spp: Option<u32>,
        /// Seed of every random choice.
        #[arg(long, default_value_t = 0)]
        seed: u32,
        /// Time limit of one shader call, in seconds.
        #[arg(long, value_name = "SECONDS", value_parser = parse_timeout,
              default_value_t = luster::shader::DEFAULT_TIMEOUT.as_secs_f64())]
        shader_timeout: f64,
        /// A folder shaders' `require "name"` searches (repeatable).
        #[arg(long = "shader-lib", value_name = "DIR", value_parser = parse_shader_lib)]
        shader_lib: Vec<PathBuf>,
        #[command(flatten)]
        model: ModelArgs,
        #[command(flatten)]
        env: EnvArgs,
        #[command(flatten)]
        frame: reframe::FrameArgs,
        /// Also stream every pass to the tev image viewer listening at HOST:PORT (tev's default: 127.0.0.1:14158).
        #[arg(long, value_name = "HOST:PORT")]
        tev: Option<String>,
    },
    /// Join the part files of a split render (`render --part`) into its images.
    ///
    /// Writes every OUTDIR/<ImageName> (and the EXR/HDR's tone-mapped PNGs)
    /// byte for byte as a single `luster render` would. Every part file is
    /// checked first: a missing, duplicated, corrupt or truncated part, or
    /// parts of different renders (another scene, other options, another
    /// number of parts), is an error and no image is written. Exit code: 0
    /// merged, 2 an error.
    Merge {
        /// The folder holding the part files.
        outdir: PathBuf,
    },
    /// Write (and submit) Slurm batch scripts that render scenes as a job array.
    ///
    /// Writes OUTDIR/luster.sbatch (one array task per part, each running
    /// `luster render --part $SLURM_ARRAY_TASK_ID/N --resume`, requeued when
    /// preempted) and OUTDIR/luster-merge.sbatch (`luster merge OUTDIR`, to
    /// run after the array succeeds). `luster slurm status OUTDIR` reports
    /// progress from the part files.
    Slurm(slurm::Cli),
    /// Benchmark the BVH on PLY meshes (build time, memory, Mrays/s).
    ///
    /// Prints BVH build time, memory and closest-hit primary-ray throughput
    /// (Mrays/s) for each thread count, with the camera of
    /// shared/bench/embree_rays.py (1920x1080, 45° vertical field of view,
    /// looking along the bounding box's thinnest axis), so the figures line up
    /// with Intel Embree's on the same mesh and rays.
    Bench {
        /// PLY meshes.
        #[arg(required = true)]
        plys: Vec<PathBuf>,
        /// Thread counts to measure, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "1,2", value_parser = threads_parser())]
        threads: Vec<usize>,
        /// Timed repetitions per thread count (the median is reported).
        #[arg(long, default_value_t = 5)]
        reps: usize,
    },
    /// Compare a test image with a reference: PSNR, SSIM, LDR-FLIP, differing pixels.
    ///
    /// Reads PNG, JPEG, OpenEXR and Radiance HDR. FLIP is the mean LDR-FLIP
    /// error (Andersson et al., "FLIP: A Difference Evaluator for Alternating
    /// Images", HPG 2020) in [0, 1]; 0 means no visible difference; for two
    /// EXR/HDR images it is HDR-FLIP (Andersson et al., EG 2021). PSNR is on
    /// display values with peak 1 (8-bit PSNR), or on linear light when both
    /// images are EXR/HDR. Exit code: 0 compared (and bounds met), 1 a bound
    /// given by --max-error or --min-psnr was not met, 2 an image could not be
    /// read, the sizes differ, or the heatmap could not be written.
    Compare {
        /// The reference (expected) image.
        reference: PathBuf,
        /// The image to test against it.
        test: PathBuf,
        /// Write the per-pixel LDR-FLIP error as a magma-coloured PNG here.
        #[arg(long, value_name = "OUT.png")]
        heatmap: Option<PathBuf>,
        /// Exit 1 if the mean LDR-FLIP error is above this (0 to 1).
        #[arg(long, value_name = "F")]
        max_error: Option<f64>,
        /// Exit 1 if the PSNR is below this many dB.
        #[arg(long, value_name = "DB")]
        min_psnr: Option<f64>,
        /// Count a pixel as differing only if an 8-bit channel differs by more than N.
        #[arg(long, value_name = "N", default_value_t = 0)]
        tolerance: u8,
        /// Exposure in stops applied to EXR/HDR images before display-referred metrics.
        #[arg(long, value_name = "STOPS", default_value_t = 0.0, allow_negative_numbers = true)]
        exposure: f32,
    },
    /// Tone-map an HDR image (.exr or .hdr) to an 8-bit PNG or JPEG without rendering.
    ///
    /// The pipeline of hw5 (luminance, key scaling by the log-average, the
    /// operator's curve, saturation, clamp, gamma, rounding), as a camera's
    /// <Tonemap> does; docs/hdr.md has the exact curves. Exit code: 0 written,
    /// 2 the input could not be read or is not HDR, an option is out of range,
    /// or the output could not be written.
    Tonemap {
        /// The HDR image (.exr or .hdr).
        input: PathBuf,
        /// The image to write (.png, .jpg).
        #[arg(short, long, value_name = "OUT.png")]
        output: PathBuf,
        /// Operator: photographic (Reinhard 2002, hw5), aces or filmic.
        #[arg(long, default_value = "photographic")]
        tmo: String,
        /// Key value: the level the log-average luminance is scaled to.
        #[arg(long, default_value_t = 0.18)]
        key: f32,
        /// Burn-out percentage: this share of the brightest pixels becomes white (0: none).
        #[arg(long, value_name = "PERCENT", default_value_t = 0.0)]
        burn: f32,
        /// Saturation exponent (1 keeps colours, 0 is grey).
        #[arg(long, default_value_t = 1.0)]
        saturation: f32,
        /// Gamma: a positive number (C^(1/g)) or srgb.
        #[arg(long, default_value = "2.2")]
        gamma: String,
    },
    /// Render a course folder, compare with its expected images, write an HTML report.
    ///
    /// Finds every scene under DIR/hwN/{json,xml}/ that names one of the
    /// homework's expected images (DIR/hwN/expected/...), renders it, compares
    /// every camera's image with its expected image by the conformance
    /// thresholds, and writes OUTDIR/index.html and OUTDIR/results.json with
    /// the renders, copies of the expected images and LDR-FLIP heatmaps
    /// beside them. A scene that fails to load, render or even panics becomes
    /// an error row; the others still run. Exit code: 0 when the suite ran,
    /// whatever the verdicts (1 with --strict if any image failed); 2 when DIR
    /// is missing or the report cannot be written.
    Suite {
        /// The course folder (with hw1/, hw2/, ...).
        dir: PathBuf,
        /// Folder for the report (created if needed).
        #[arg(short, long, default_value = "report")]
        outdir: PathBuf,
        /// Scenes rendered at the same time.
        #[arg(short, long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..))]
        jobs: u16,
        /// Only scenes whose label (e.g. hw2/xml/ellipsoids.xml) contains this text.
        #[arg(long, value_name = "PATTERN")]
        only: Option<String>,
        /// Worker threads per scene (default: all cores, shared among the jobs).
        #[arg(short, long, value_parser = clap::value_parser!(u16).range(1..=MAX_THREADS as i64))]
        threads: Option<u16>,
        /// Exit 1 if any image failed or errored.
        #[arg(long)]
        strict: bool,
        /// Samples per pixel, overriding each camera's NumSamples (a quick
        /// look at hw3: noise-aware bars adapt to the noise).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
        spp: Option<u32>,
        /// At most this many samples per pixel: multi-sample cameras are
        /// capped, single-sample ones keep their one (the whole course in
        /// minutes, judged by the noise-aware bars at the count rendered).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
        max_spp: Option<u32>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(e) = signal::remove_temporaries_on_signal() {
        report("warning", &format_args!("Ctrl-C will not remove half-written images: {e}"));
    }
    match cli.command {
        Command::Render {
            scenes,
            outdir,
            threads,
            quiet,
            spp,
            seed,
            filter,
            shader_timeout,
            shader_lib,
            part,
            resume,
            checkpoint,
            time,
            camera,
            denoise,
            model,
            env,
            frame,
            passes,
        } => {
            let env = match env.hdri() {
                Ok(env) => env,
                Err(e) => {
                    report("error", &e);
                    return ExitCode::from(2);
                }
            };
            luster::shader::set_library_dirs(shader_lib);
            let view = luster::scene::obj::ModelView { camera, ..model.view() };
            let filter = filter.filter();
            let time_limit = time.map(std::time::Duration::from_secs_f64);
            let opts = luster::render::RenderOptions {
                spp,
                seed,
                filter,
                time_limit,
                passes: passes.passes(),
                adaptive: passes.adaptive(),
                ..Default::default()
            };
            let build = luster::render::BuildOptions {
                shader_timeout: std::time::Duration::from_secs_f64(shader_timeout),
            };
            match part {
                Some(part) => {
                    let split =
                        part::Split { part, resume, checkpoint: std::time::Duration::from_secs(checkpoint) };
                    part::run(&scenes, &outdir, threads, quiet, &opts, &build, &view, env.as_ref(), &split)
                }
                None => {
                    let frame = (model.size, frame);
                    render::run(
                        &scenes,
                        &outdir,
                        threads,
                        quiet,
                        denoise,
                        &opts,
                        &build,
                        &view,
                        env.as_ref(),
                        &frame,
                    )
                }
            }
        }
        Command::Watch {
            scene,
            port,
            camera,
            threads,
            spp,
            seed,
            shader_timeout,
            shader_lib,
            model,
            env,
            frame,
            tev,
        } => {
            let env = match env.hdri() {
                Ok(env) => env,
                Err(e) => {
                    report("error", &e);
                    return ExitCode::from(2);
                }
            };
            luster::shader::set_library_dirs(shader_lib);
            watch::run(watch::Args {
                scene,
                port,
                camera,
                threads,
                render: luster::render::RenderOptions { spp, seed, ..Default::default() },
                build: luster::render::BuildOptions {
                    shader_timeout: std::time::Duration::from_secs_f64(shader_timeout),
                },
                view: model.view(),
                env,
                frame: (model.size, frame),
                tev,
            })
        }
        Command::Merge { outdir } => merge::run(&outdir),
        Command::Slurm(cli) => slurm::run(cli),
        Command::Bench { plys, threads, reps } => match luster::bench::run(&plys, &threads, reps) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                report("error", &format_args!("{e:#}"));
                ExitCode::from(2)
            }
        },
        Command::Compare { reference, test, heatmap, max_error, min_psnr, tolerance, exposure } => {
            compare::run(&compare::Args {
                reference,
                test,
                heatmap,
                max_error,
                min_psnr,
                tolerance,
                exposure,
            })
        }
        Command::Tonemap { input, output, tmo, key, burn, saturation, gamma } => {
            tonemap::run(&tonemap::Args { input, output, tmo, key, burn, saturation, gamma })
        }
        Command::Suite { dir, outdir, jobs, only, threads, strict, spp, max_spp } => {
            suite::run(&suite::Args {
                dir,
                outdir,
                jobs: usize::from(jobs),
                only,
                threads: threads.map(usize::from),
                strict,
                spp,
                max_spp,
            })
        }
    }
}
