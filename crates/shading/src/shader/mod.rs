//! The Lua shading language: user scripts that compute a surface's color,
//! bump height or reflectance at a point, run by LuaJIT in a sandbox.
//!
//! `docs/shaders.md` is the reference for shader authors; this is the Rust side.
//!
//! # Use
//!
//! ```
//! use std::time::Duration;
//! use luster_shading::shader::{ShadeInput, ShaderSet, ShaderSource};
//!
//! let marble = ShaderSource::new("marble", "marble.lua", r#"
//!     function color(s)
//!       local t = turbulence(s.P.x, s.P.y, s.P.z, 4)
//!       local v = 0.5 + 0.5 * math.sin(s.P.x * param.freq + 4 * t)
//!       return v, v, v * 0.9
//!     end
//! "#).with_number("freq", 3.0);
//! let set = ShaderSet::new(vec![marble], Duration::from_secs(10))?;
//! assert!(set.has_color(0) && !set.has_height(0));
//! let rgb = set.color(0, &ShadeInput { p: [0.1, 0.2, 0.3], ..ShadeInput::default() })?;
//! assert!(rgb.iter().all(|c| c.is_finite()));
//! # Ok::<(), luster_shading::shader::ShaderError>(())
//! ```
//!
//! [`ShaderSet`] is `Send + Sync`: the render scene owns one and every worker
//! calls it. Each thread gets its own Lua state per set, built on first use
//! with every script compiled once (`threads.rs` explains how they are kept and
//! freed). [`ShaderSet::new`] compiles everything once on the calling thread,
//! so syntax errors, missing entry points and errors in a script's top level
//! are reported before rendering starts.
//!
//! # How a call works
//!
//! Rust writes the shading point into a `#[repr(C)]` record that the state's
//! prelude allocated as FFI cdata (`ffi.rs`), then calls a no-argument Lua
//! wrapper that passes the record to the script as `s`, checks the results and
//! writes them into a second record. Nothing is converted through the Lua
//! stack, and the wrapper is called with a bare `lua_pcall` from a Lua thread
//! that keeps every wrapper on its stack (`call.rs`); `benches/shader.rs`
//! compares this with `Function::call` on scalars.
//! Built-in noise is Rust, reached through a table of function pointers.
//!
//! # Safety of user scripts
//!
//! Scripts run in a per-shader environment that has no `io`, `os`, `package`,
//! `require`, `debug`, `ffi`, `jit`, `load*`, `dofile`, `getfenv`/`setfenv`,
//! `newproxy` or `string.dump`; the string metatable is hidden. A call that
//! runs past its timeout is stopped by checks inserted into every loop and
//! function (`instrument.rs`), which also work inside JIT-compiled code and
//! read a clock that a watchdog thread keeps (`ffi.rs`); a call that returns
//! after its limit is a timeout too. Every library function a script reaches
//! has a bounded cost (pattern functions take literal patterns and search in
//! linear time, `table.sort` is O(n log n), `prelude.lua` has the rest), and
//! none calls back into Lua from C, so no recursion of a script grows the
//! native stack beyond what [`STACK_SIZE`] holds (`docs/robustness.md`).

pub mod attributes;
mod builtin_modules;
mod call;
pub mod closure;
mod compile;
mod declared;
mod entry;
mod error;
mod ffi;
mod input;
mod instrument;
mod invoke;
mod modules;
mod params;
mod shade;
/// The instrumenter, for the fuzz entry points.
pub use instrument::instrument as instrument_script;
mod state;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_author;
#[cfg(test)]
mod tests_closure;
#[cfg(test)]
mod tests_derivs;
#[cfg(test)]
mod tests_limits;
#[cfg(test)]
mod tests_modules;
#[cfg(test)]
mod tests_patterns;
#[cfg(test)]
mod tests_sandbox;
#[cfg(test)]
mod tests_trace;
mod threads;
mod trace;

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

pub use attributes::Attributes;
pub use declared::{DeclaredParam, ParamKind};
pub use entry::MaterialOutputs;
pub use entry::{Entry, ENTRIES};
pub use error::{ShaderError, ShaderErrorKind};
pub use input::ShadeInput;
pub use input::ShadePoint;
pub use modules::{search_path, set_library_dirs, MAX_MODULE_BYTES};
pub use trace::{with_tracer, TraceHit, TraceRay, Tracer, MAX_RAYS};

/// The pixel `--debug-pixel` names, packed (`u64::MAX`: none).
static DEBUG_PIXEL: AtomicU64 = AtomicU64::new(u64::MAX);

/// Makes every shader call at pixel `p` print its inputs and result to
/// standard error, and `print` in scripts show only there (`None`: every
/// `print` shows, nothing else). Process-wide: it is a debugging aid for
/// the command line.
pub fn set_debug_pixel(p: Option<[u32; 2]>) {
    let packed = p.map_or(u64::MAX, |[x, y]| (u64::from(x) << 32) | u64::from(y));
    DEBUG_PIXEL.store(packed, Ordering::Relaxed);
}

/// The pixel of [`set_debug_pixel`].
pub fn debug_pixel() -> Option<[u32; 2]> {
    let p = DEBUG_PIXEL.load(Ordering::Relaxed);
    (p != u64::MAX).then_some([(p >> 32) as u32, p as u32])
}

/// The native stack a thread that runs shaders is started with (the render
/// and watch workers, the threads that build scenes). Lua code itself uses
/// none of it (LuaJIT runs Lua calls, metamethods and `pcall` on its own
/// stack, whose overflow is a Lua error), but the parser, the JIT and a
/// chain of coroutines resumed inside one another do, and so does the
/// renderer around them; `docs/robustness.md` gives the measured worst
/// cases, which this leaves a wide margin over.
pub const STACK_SIZE: usize = 16 * 1024 * 1024;

/// The default per-call time limit: generous, since a shader that needs it is
/// broken, and a false stop would lose a render.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(10);

/// One shader script and the parameters the scene gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct ShaderSource {
    /// The name errors use (the scene's shader name).
    pub name: String,
    /// The script's file, for messages (`file:line`).
    pub path: PathBuf,
    /// The Lua source text.
    pub code: String,
    /// Values the script reads as `param.NAME`.
    pub params: Vec<(String, ParamValue)>,
}

impl ShaderSource {
    /// A script with no parameters.
    pub fn new(name: impl Into<String>, path: impl Into<PathBuf>, code: impl Into<String>) -> ShaderSource {
        ShaderSource { name: name.into(), path: path.into(), code: code.into(), params: Vec::new() }
    }

    /// The same source with one more parameter.
    pub fn with_param(mut self, name: impl Into<String>, value: ParamValue) -> ShaderSource {
        self.params.push((name.into(), value));
        self
    }

    /// The same source with one more number parameter.
    pub fn with_number(self, name: impl Into<String>, value: f64) -> ShaderSource {
        self.with_param(name, ParamValue::Number(value))
    }
}

/// A shader parameter's value, as the scene file gives it.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// A number: a Lua number.
    Number(f64),
    /// Three numbers: a `vec3` in Lua.
    Vec3([f64; 3]),
    /// Text: a Lua string.
    Text(String),
}

/// How `texture(name, u, v, filter)` filters an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleFilter {
    /// The texel the point falls in.
    Nearest,
    /// The four texels around the point, weighted by distance.
    Bilinear,
}

/// The scene's images as shaders sample them. A trait, so the shader runtime
/// does not depend on how the renderer stores textures.
pub trait ImageSampler: Send + Sync {
    /// The colour of image `index` (an index [`ShaderImages::names`] gives)
    /// at texture coordinates `(u, v)`, with values in 0–1 for 8-bit images
    /// and as stored for floating-point ones. `None` when there is no such
    /// image.
    fn sample(&self, index: usize, u: f32, v: f32, filter: SampleFilter) -> Option<[f32; 3]>;
}

/// The images a set's scripts may sample: the names a script uses and the
/// images behind them.
#[derive(Clone)]
pub struct ShaderImages {
    /// Name to image index; an image may have several names (its scene id,
    /// its file name).
    pub names: Vec<(String, usize)>,
    /// The images.
    pub sampler: Arc<dyn ImageSampler>,
}

impl std::fmt::Debug for ShaderImages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShaderImages").field("names", &self.names).finish_non_exhaustive()
    }
}

/// What a [`ShaderSet`] is built with besides its scripts.
#[derive(Debug, Clone)]
pub struct ShaderOptions {
    /// Bounds every call, and each script's top level.
    pub timeout: Duration,
    /// The images (if any) the scripts sample with `texture(name, u, v)`.
    pub images: Option<ShaderImages>,
    /// The folders `require` searches, in order ([`search_path`] makes them
    /// from the scene's).
    pub module_dirs: Vec<PathBuf>,
    /// The attributes `getattribute` reads ([`attributes`]).
    pub attributes: Arc<Attributes>,
}

impl Default for ShaderOptions {
    fn default() -> ShaderOptions {
        ShaderOptions {
            timeout: DEFAULT_TIMEOUT,
            images: None,
            module_dirs: Vec::new(),
            attributes: Arc::new(Attributes::default()),
        }
    }
}

/// What every thread's state is built from.
pub(crate) struct Shared {
    id: u64,
    sources: Vec<ShaderSource>,
    timeout: Duration,
    images: Option<ShaderImages>,
    modules: Arc<modules::Modules>,
    attributes: Arc<Attributes>,
}

/// A compiled set of shaders, addressed by their index in the list given to
/// [`ShaderSet::new`]. `Send + Sync`; see the module doc.
pub struct ShaderSet {
    shared: Arc<Shared>,
    entries: Vec<[bool; ENTRIES]>,
    /// What each script's `params{...}` declares.
    declared: Vec<Vec<DeclaredParam>>,
}

impl ShaderSet {
    /// Compiles every script once (syntax errors carry `file:line`), runs each
    /// one's top level, and checks that each defines at least one entry point.
    /// `timeout` bounds every later call (and each top level).
    pub fn new(sources: Vec<ShaderSource>, timeout: Duration) -> Result<ShaderSet, ShaderError> {
        ShaderSet::with_images(sources, timeout, None)
    }

    /// Like [`ShaderSet::new`], with the images (if any) the scripts sample
    /// with `texture(name, u, v)`.
    pub fn with_images(
        sources: Vec<ShaderSource>,
        timeout: Duration,
        images: Option<ShaderImages>,
    ) -> Result<ShaderSet, ShaderError> {
        ShaderSet::with_modules(sources, timeout, images, Vec::new())
    }

    /// Like [`ShaderSet::with_images`], with the folders `require` searches,
    /// in order ([`search_path`] makes them from the scene's).
    pub fn with_modules(
        sources: Vec<ShaderSource>,
        timeout: Duration,
        images: Option<ShaderImages>,
        module_dirs: Vec<PathBuf>,
    ) -> Result<ShaderSet, ShaderError> {
        ShaderSet::build(sources, ShaderOptions { timeout, images, module_dirs, ..ShaderOptions::default() })
    }

    /// Like [`ShaderSet::new`], with everything [`ShaderOptions`] holds.
    pub fn build(sources: Vec<ShaderSource>, options: ShaderOptions) -> Result<ShaderSet, ShaderError> {
        static NEXT_ID: AtomicU64 = AtomicU64::new(1);
        let ShaderOptions { timeout, images, module_dirs, attributes } = options;
        let shared = Arc::new(Shared {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            sources,
            timeout,
            images,
            modules: Arc::new(modules::Modules::new(module_dirs)),
            attributes,
        });
        let state = state::ThreadState::new(&shared)?;
        let entries = (0..shared.sources.len()).map(|id| state.entries(id)).collect();
        let declared = state.shaders.iter().map(|c| c.declared.clone()).collect();
        threads::adopt(&shared, state);
        Ok(ShaderSet { shared, entries, declared })
    }

    /// How many shaders the set holds.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the set holds no shader.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The module files the scripts have required so far (canonical paths):
    /// every top-level `require` once the set is built, and those a script
    /// makes inside its functions once a call has made them. A watcher
    /// watches these with the scripts.
    pub fn required_files(&self) -> Vec<PathBuf> {
        self.shared.modules.required()
    }

    /// The parameters shader `id` declares with `params{...}`, in name
    /// order (empty for a script without `params{}`), with their defaults
    /// and the ranges `range(default, min, max)` gives.
    pub fn declared(&self, id: usize) -> &[DeclaredParam] {
        self.declared.get(id).map_or(&[], Vec::as_slice)
    }

    /// The name of shader `id`.
    pub fn name(&self, id: usize) -> Option<&str> {
        self.shared.sources.get(id).map(|s| s.name.as_str())
    }

    fn has(&self, id: usize, entry: Entry) -> bool {
        self.entries.get(id).is_some_and(|e| e[entry as usize])
    }

    /// Whether shader `id` defines `color(s)`.
    pub fn has_color(&self, id: usize) -> bool {
        self.has(id, Entry::Color)
    }

    /// Whether shader `id` defines `height(s)`.
    pub fn has_height(&self, id: usize) -> bool {
        self.has(id, Entry::Height)
    }

    /// Whether shader `id` defines `reflect(s)`.
    pub fn has_reflect(&self, id: usize) -> bool {
        self.has(id, Entry::Reflect)
    }

    /// Whether shader `id` defines `density(s)`.
    pub fn has_density(&self, id: usize) -> bool {
        self.has(id, Entry::Density)
    }

    /// Whether shader `id` defines `emission(s)`.
    pub fn has_emission(&self, id: usize) -> bool {
        self.has(id, Entry::Emission)
    }

    /// Whether shader `id` defines `normal(s)`.
    pub fn has_normal(&self, id: usize) -> bool {
        self.has(id, Entry::Normal)
    }

    /// Whether shader `id` defines `material(s)` or any material output
    /// (`color`, `specular`, `roughness`, `metalness`, `emission` or
    /// `reflect`), one of which `DecalMode material` needs.
    pub fn has_material(&self, id: usize) -> bool {
        [
            Entry::Material,
            Entry::Color,
            Entry::Specular,
            Entry::Roughness,
            Entry::Metalness,
            Entry::Emission,
            Entry::Reflect,
        ]
        .into_iter()
        .any(|e| self.has(id, e))
    }

    /// Whether shader `id` defines `material(s)`: its
    /// [`ShaderSet::material`] then gives a closure and no other output.
    pub fn has_closure(&self, id: usize) -> bool {
        self.has(id, Entry::Material)
    }

    /// What shader `id` says about the surface at `input`, in one call into
    /// Lua: the closure its `material(s)` returns (`docs/closures.md`),
    /// converted to [`closure::Closure`]; or, for a script without
    /// `material`, every material output it defines, each checked against
    /// its range (reflectances and `roughness`, `metalness` in 0–1,
    /// `emission` finite and not negative).
    pub fn material(&self, id: usize, input: &ShadeInput) -> Result<MaterialOutputs, ShaderError> {
        self.material_with(id, input, |o| *o)
    }

    /// [`material`](Self::material), with the outputs lent to `f` rather
    /// than returned: they are written in place into the thread's own
    /// record, so a closure (a few kilobytes, mostly unused nodes) is not
    /// copied on its way to the renderer.
    pub fn material_with<R>(
        &self,
        id: usize,
        input: &ShadeInput,
        f: impl FnOnce(&MaterialOutputs) -> R,
    ) -> Result<R, ShaderError> {
        threads::with_state(&self.shared, |state| {
            let mut out = state.outputs.borrow_mut();
            state.call_material(id, input, &mut out)?;
            Ok(f(&out))
        })
    }

    /// The density of volume shader `id` at `input` (a number; the caller
    /// treats negative values as empty space).
    #[inline]
    pub fn density(&self, id: usize, input: &ShadeInput) -> Result<f32, ShaderError> {
        self.call(id, Entry::Density, input).map(|c| c[0] as f32)
    }

    /// The emitted radiance per unit length of volume shader `id` at `input`.
    #[inline]
    pub fn emission(&self, id: usize, input: &ShadeInput) -> Result<[f32; 3], ShaderError> {
        self.call(id, Entry::Emission, input).map(|c| c.map(|x| x as f32))
    }

    #[inline]
    fn call(&self, id: usize, entry: Entry, input: &ShadeInput) -> Result<[f64; 3], ShaderError> {
        let mut rgb = [0.0; 3];
        match threads::with_state_fast(&self.shared, |state| state.call_fast(id, entry, input, &mut rgb)) {
            0 => Ok(rgb),
            code => self.call_slow(id, entry, input, code),
        }
    }

    /// The fast path of a call of `entry` at `p`: 0 with the result's
    /// channels in `rgb`, or a code for [`ShaderSet::call_slow`]. The
    /// renderer's maps call this with their hit, so that neither the point
    /// nor the result passes through memory on the way (an 80-byte
    /// `Result` returned through the stack would be read back in pieces
    /// that its stores cannot forward to).
    #[inline]
    pub fn call_point<P: ShadePoint>(&self, id: usize, entry: Entry, p: &P, rgb: &mut [f64; 3]) -> u32 {
        threads::with_state_fast(&self.shared, |state| state.call_fast_point(id, entry, p, rgb))
    }

    /// A call past its fast path: an error, a caught timeout, `--debug-pixel`
    /// output, or a thread whose state is not built yet (`threads::MISS`:
    /// the call did not run, so it runs here).
    #[cold]
    #[inline(never)]
    pub fn call_slow<P: ShadePoint>(
        &self,
        id: usize,
        entry: Entry,
        p: &P,
        code: u32,
    ) -> Result<[f64; 3], ShaderError> {
        let input = p.input();
        threads::with_state(&self.shared, |state| match code {
            threads::MISS => state.call(id, entry, &input),
            code => state.finish(id, entry, &input, code),
        })
    }

    /// The diffuse color of shader `id` at `input`.
    #[inline]
    pub fn color(&self, id: usize, input: &ShadeInput) -> Result<[f32; 3], ShaderError> {
        self.call(id, Entry::Color, input).map(|c| c.map(|x| x as f32))
    }

    /// The bump height of shader `id` at `input` (the renderer differentiates it).
    #[inline]
    pub fn height(&self, id: usize, input: &ShadeInput) -> Result<f32, ShaderError> {
        self.call(id, Entry::Height, input).map(|c| c[0] as f32)
    }

    /// The bump heights of shader `id` at three points, in one call into Lua
    /// (the overhead of one call, not of three [`ShaderSet::height`] calls).
    /// The time limit covers the three together.
    #[inline]
    pub fn heights3(&self, id: usize, inputs: &[ShadeInput; 3]) -> Result<[f32; 3], ShaderError> {
        let mut h = [0.0; 3];
        match threads::with_state_fast(&self.shared, |state| state.call_height3_fast(id, inputs, &mut h)) {
            0 => Ok(h.map(|x| x as f32)),
            code => self.heights3_slow(id, inputs, code),
        }
    }

    /// [`ShaderSet::heights3`] past its fast path (see `call_slow`).
    #[cold]
    #[inline(never)]
    fn heights3_slow(&self, id: usize, inputs: &[ShadeInput; 3], code: u32) -> Result<[f32; 3], ShaderError> {
        threads::with_state(&self.shared, |state| match code {
            threads::MISS => state.call_height3(id, inputs),
            code => state.finish_height3(id, code),
        })
        .map(|h| h.map(|x| x as f32))
    }

    /// The world-space shading normal shader `id`'s `normal(s)` gives at
    /// `input`, as returned (the caller normalizes it).
    #[inline]
    pub fn normal(&self, id: usize, input: &ShadeInput) -> Result<[f32; 3], ShaderError> {
        self.call(id, Entry::Normal, input).map(|c| c.map(|x| x as f32))
    }

    /// The reflective color of shader `id` at `input`.
    #[inline]
    pub fn reflect(&self, id: usize, input: &ShadeInput) -> Result<[f32; 3], ShaderError> {
        self.call(id, Entry::Reflect, input).map(|c| c.map(|x| x as f32))
    }
}

impl Drop for ShaderSet {
    fn drop(&mut self) {
        threads::release(self.shared.id);
    }
}

impl std::fmt::Debug for ShaderSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.shared.sources.iter().map(|s| s.name.as_str()).collect();
        f.debug_struct("ShaderSet").field("shaders", &names).field("timeout", &self.shared.timeout).finish()
    }
}
