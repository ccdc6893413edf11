//! `luster watch`: serve a live preview of a scene (see `luster::watch`)
//! until Ctrl-C.

use luster::render::{BuildOptions, RenderOptions};
use luster::scene::obj::ModelView;
use std::path::PathBuf;
use std::process::ExitCode;

/// The command's options.
pub struct Args {
    pub scene: PathBuf,
    pub port: u16,
    pub camera: usize,
    pub threads: Option<usize>,
    pub render: RenderOptions,
    pub build: BuildOptions,
    pub view: ModelView,
    /// `--env`: applied to every load, so it survives reloads.
    pub env: Option<luster::scene::hdri::Hdri>,
    pub frame: (Option<(u32, u32)>, super::reframe::FrameArgs),
    pub tev: Option<String>,
}

pub fn run(mut args: Args) -> ExitCode {
    let obj = luster::scene::is_model(&args.scene);
    // A glTF scene's description holds the one camera `--camera` picks.
    if luster::scene::gltf::is_gltf(&args.scene) {
        args.view.camera = Some(args.camera);
        args.camera = 0;
    }
    let (size, frame) = args.frame;
    // A model's --size already made its camera; --scale and --crop apply to both.
    let size = if obj { None } else { size };
    let env = args.env;
    let reframe: luster::watch::Reframe = Box::new(move |desc| {
        if let Some(env) = &env {
            env.apply(desc);
        }
        super::reframe::apply(desc, size, &frame).map_err(|e| e.to_string())
    });
    let opts = luster::watch::Options {
        scene: args.scene,
        camera: args.camera,
        render: args.render,
        build: args.build,
        view: args.view,
        reframe,
        threads: args.threads,
        tev: args.tev,
    };
    match luster::watch::Session::start(opts, args.port) {
        Ok(session) => {
            say!("luster watch: {} (Ctrl-C to stop)", session.url());
            session.wait();
            ExitCode::SUCCESS
        }
        Err(e) => {
            super::report("error", &e);
            ExitCode::from(2)
        }
    }
}
