//! Running many cases: `jobs` scenes at a time, each on its own rayon pool.
//!
//! Every case goes through [`super::run_case_guarded`], so a
//! scene that fails to load, or even panics, becomes a failed result and the
//! others still run. The per-pixel maps of each comparison are dropped once
//! its heatmap is on disk, so a long suite keeps only the numbers in memory.
//! Results come back in the order of the input, whatever
//! order they finish in; `on_done` sees each one as it finishes (for progress
//! lines).
//!
//! With `jobs` > 1, scene-level parallelism hides the serial parts of a case
//! (parsing, building the BVH, PNG encoding, comparing) that a single rayon
//! pool cannot fill. The pools are built once per job and reused.

use super::{run_case_guarded, Case, CaseResult};
use luster_render::render::RenderOptions;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// How to run a batch of cases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunOptions {
    /// Scenes rendered at the same time (at least 1).
    pub jobs: usize,
    /// Worker threads of each scene's rayon pool (at least 1).
    pub threads: usize,
    /// Sample count, seed and filter of every render.
    pub render: RenderOptions,
    /// Cap on each camera's samples per pixel (see [`run_case_guarded`]).
    pub max_spp: Option<u32>,
}

impl RunOptions {
    /// `jobs` scenes at a time; `threads` per scene, or when `None` the
    /// machine's cores shared evenly among the jobs (at least one each).
    pub fn new(jobs: usize, threads: Option<usize>) -> Self {
        let jobs = jobs.max(1);
        let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        let threads = threads.unwrap_or(cores / jobs).max(1);
        RunOptions { jobs, threads, render: RenderOptions::default(), max_spp: None }
    }
}

/// Runs every case, writing renders and heatmaps under `outdir`.
///
/// `on_done(result, finished, total)` is called once per case as it
/// finishes, from the job's thread. Fails only if a thread pool cannot be
/// started.
pub fn run_cases(
    cases: &[Case],
    outdir: &Path,
    opts: RunOptions,
    on_done: &(dyn Fn(&CaseResult, usize, usize) + Sync),
) -> Result<Vec<CaseResult>, rayon::ThreadPoolBuildError> {
    let jobs = opts.jobs.max(1).min(cases.len().max(1));
    let pools = (0..jobs)
        .map(|_| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(opts.threads.max(1));
            pool.stack_size(luster_shading::shader::STACK_SIZE).build()
        })
        .collect::<Result<Vec<_>, _>>()?;
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<CaseResult>>> = Mutex::new(vec![None; cases.len()]);
    std::thread::scope(|s| {
        for pool in &pools {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(case) = cases.get(i) else { break };
                let mut result = pool.install(|| run_case_guarded(case, outdir, &opts.render, opts.max_spp));
                result.drop_pixel_maps();
                let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
                // A failing progress callback must not lose the result.
                let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    on_done(&result, n, cases.len())
                }));
                // A poisoned lock only means another job panicked after
                // catching; the slots themselves are still sound.
                let mut slots = slots.lock().unwrap_or_else(|e| e.into_inner());
                slots[i] = Some(result);
            });
        }
    });
    let slots = slots.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok(slots
        .into_iter()
        .zip(cases)
        .map(|(r, c)| r.unwrap_or_else(|| CaseResult::failed(c, Some("the scene was never run".to_string()))))
        .collect())
}
