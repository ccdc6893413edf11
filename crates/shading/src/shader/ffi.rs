//! The LuaJIT FFI boundary: the `#[repr(C)]` records Rust and Lua share, and
//! the table of built-in functions Lua calls through function pointers.
//!
//! # Why function pointers
//!
//! LuaJIT's `ffi.C.name` looks symbols up in the process's dynamic symbol
//! table, and an executable does not export its Rust functions. Instead Rust
//! fills one [`Builtins`] record with `extern "C"` function pointers, hands its
//! address to the trusted prelude as a light userdata, and the prelude
//! `ffi.cast`s it to the mirror C struct declared in `prelude.lua`. A call
//! through such a pointer is compiled by the JIT into a direct native call, with
//! no per-call marshalling.
//!
//! The C declarations in `prelude.lua` must match these records field for field;
//! every new state compares the sizes Lua reports with these (`state.rs`).
//!
//! # Soundness
//!
//! This and `call.rs` (raw calls into Lua) are the modules of the shader
//! runtime with `unsafe`:
//!
//! * [`IoBlock`] holds pointers to cdata that the prelude allocated with
//!   `ffi.new` and keeps referenced for the life of its Lua state (the prelude's
//!   entry wrappers close over them). LuaJIT never moves cdata, and the block is
//!   owned by the same `ThreadState` as the `Lua` it points into, which is dropped
//!   only with it. Rust touches the records only between Lua calls, on the thread
//!   that owns the state, so there is no concurrent access.
//! * `texture` receives the address of the state's image sampler, which the
//!   state owns for as long as its Lua lives (`state.rs`).
//! * The shader clock ([`epoch_now`]) is a static of atomics that the
//!   watchdog thread stores to; compiled Lua reads it with plain aligned
//!   8-byte loads, which are single-copy atomic on the targets LuaJIT's JIT
//!   supports, so a reader sees an old or a new value, never a torn one.
//! * `trace`, `occlusion` and `bevel` (`trace.rs`) receive the prelude's
//!   scratch records, and reach the scene through the tracer the renderer
//!   installed for the thread, which outlives the call.
//! * `find` receives two Lua strings with their lengths, as the prelude
//!   passes them.
//! * The built-ins are called by LuaJIT with arguments the trusted prelude
//!   passes; the only pointers they receive are scratch records the prelude
//!   allocated (user scripts never see the raw function pointers). Each built-in
//!   catches panics so none unwinds into C.

use std::ffi::c_void;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use super::closure::{Closure, Node, NodeKind, MAX_NODES};
use super::trace::{self, HitOut, RayIn};
use super::{Entry, ImageSampler, MaterialOutputs, SampleFilter};
use crate::noise::{course, fractal, perlin, simplex, voronoi};

/// A 3-vector as Lua sees it (`luster_vec3`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Vec3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// Texture coordinates as Lua sees them (`luster_vec2`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Vec2 {
    pub u: f64,
    pub v: f64,
}

/// The shading point, the `s` a script receives (`luster_shade`). Doubles,
/// because Lua numbers are doubles: reading a field then converts nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Shade {
    pub p: Vec3,
    pub pw: Vec3,
    pub pc: Vec3,
    pub n: Vec3,
    pub ng: Vec3,
    pub i: Vec3,
    pub v: Vec3,
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    pub dpdx: Vec3,
    pub dpdy: Vec3,
    pub uv: Vec2,
    pub time: f64,
    pub filterwidth: f64,
    pub random: f64,
    pub object_id: i32,
    pub instance_id: i32,
    pub depth: i32,
    pub pixel_x: i32,
    pub pixel_y: i32,
    pub pad: i32,
    pub dpwdx: Vec3,
    pub dpwdy: Vec3,
    pub dpcdx: Vec3,
    pub dpcdy: Vec3,
    pub duvdx: Vec2,
    pub duvdy: Vec2,
}

/// Where an entry wrapper writes its result (`luster_out`); a height uses `r`.
/// `bad` is set when the wrapper rejected what the script returned, so Rust
/// can tell that error from one the script raised itself.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Out {
    pub r: f64,
    pub g: f64,
    pub b: f64,
    pub bad: i32,
}

/// One closure node as the constructors write it (`luster_node`); the
/// fields mean what [`Node`]'s do.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct NodeOut {
    pub kind: i32,
    pub a: i32,
    pub b: i32,
    pub thin: i32,
    pub c: [[f64; 3]; 3],
    pub x: [f64; 3],
}

/// Where the `DecalMode material` wrapper writes every material output the
/// script defines (`luster_material`); the others keep their defaults. A
/// script with `material(s)` writes the closure's nodes instead:
/// `nodes[..closure_len]`, rooted at `closure_root`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct MaterialOut {
    pub color: [f64; 3],
    pub specular: [f64; 3],
    pub emission: [f64; 3],
    pub reflect: [f64; 3],
    pub roughness: f64,
    pub metalness: f64,
    pub closure_len: i32,
    pub closure_root: i32,
    pub nodes: [NodeOut; MAX_NODES],
}

/// The closure in `m`, written into `c` (only the nodes in use: those past
/// its count are never read); `None` when the record is not one the
/// prelude's constructors write (an unknown kind, a child not below its
/// parent): the renderer relies on both.
fn closure_of(m: &MaterialOut, c: &mut Closure) -> Option<()> {
    let len = usize::try_from(m.closure_len).ok().filter(|n| (1..=MAX_NODES).contains(n))?;
    let root = usize::try_from(m.closure_root).ok().filter(|&r| r < len)?;
    (c.len, c.root) = (len as u8, root as u8);
    for (i, (dst, src)) in c.nodes.iter_mut().zip(&m.nodes[..len]).enumerate() {
        let kind = *usize::try_from(src.kind).ok().and_then(|k| NodeKind::ALL.get(k))?;
        let child = |k: i32| usize::try_from(k).ok().filter(|&k| k < i).map(|k| k as u8);
        let (a, b) = match kind {
            NodeKind::Add | NodeKind::Layer => (child(src.a)?, child(src.b)?),
            NodeKind::Scale => (child(src.a)?, 0),
            _ => (0, 0),
        };
        *dst = Node {
            kind,
            a,
            b,
            thin: src.thin != 0,
            c: src.c.map(|c| c.map(|v| v as f32)),
            x: src.x.map(|v| v as f32),
        };
    }
    Some(())
}

/// The per-call deadline (`luster_clock`), in periods of the watchdog's
/// clock ([`epoch`]): a call has run past its limit once the clock reads
/// more than `start + limit`. `depth` counts the coroutines the call has
/// resumed inside one another (the prelude's bound on native recursion),
/// `rays` the rays it has cast (`trace.rs`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Clock {
    pub start: f64,
    pub limit: f64,
    pub depth: i32,
    pub rays: i32,
}

/// The derivatives' flag (`luster_derivs`): `redo` is set when an entry
/// function asked for a derivative for the first time, in a call that
/// then ran it once only; Rust starts that call again (`invoke.rs`).
/// `offset` is set while an offset run is under way (Lua's own).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Derivs {
    pub redo: i32,
    pub offset: i32,
}

/// The Voronoi scratch record (`luster_cell`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CellOut {
    pub f1: f64,
    pub f2: f64,
    pub px: f64,
    pub py: f64,
    pub pz: f64,
    pub id: f64,
}

/// The built-ins, in the order of `luster_builtins` in `prelude.lua`.
#[repr(C)]
pub(crate) struct Builtins {
    perlin1: extern "C" fn(f64) -> f64,
    perlin2: extern "C" fn(f64, f64) -> f64,
    perlin3: extern "C" fn(f64, f64, f64) -> f64,
    perlin4: extern "C" fn(f64, f64, f64, f64) -> f64,
    perlin3_grad: extern "C" fn(f64, f64, f64, *mut Vec3) -> f64,
    pperlin3: extern "C" fn(f64, f64, f64, i32, i32, i32) -> f64,
    simplex2: extern "C" fn(f64, f64) -> f64,
    simplex3: extern "C" fn(f64, f64, f64) -> f64,
    simplex4: extern "C" fn(f64, f64, f64, f64) -> f64,
    simplex3_grad: extern "C" fn(f64, f64, f64, *mut Vec3) -> f64,
    fbm: extern "C" fn(f64, f64, f64, i32, f64, f64) -> f64,
    fbm_grad: extern "C" fn(f64, f64, f64, i32, f64, f64, *mut Vec3) -> f64,
    turbulence: extern "C" fn(f64, f64, f64, i32, f64, f64) -> f64,
    ridged: extern "C" fn(f64, f64, f64, i32, f64, f64, f64) -> f64,
    voronoi3: extern "C" fn(f64, f64, f64, u32, f64, *mut CellOut),
    voronoi2: extern "C" fn(f64, f64, u32, f64, *mut CellOut),
    find: extern "C" fn(*const u8, i32, i32, *const u8, i32) -> i32,
    magic: extern "C" fn(*const u8, i32) -> i32,
    epoch: *const AtomicU64,
    course_noise: extern "C" fn(f64, f64, f64) -> f64,
    texture: extern "C" fn(*const c_void, i32, f64, f64, i32, *mut Vec3) -> i32,
    course_perlin: extern "C" fn(f64, f64, f64, f64, i32, i32) -> f64,
    trace: extern "C" fn(*const RayIn, *mut HitOut) -> i32,
    occlusion: extern "C" fn(*const RayIn, i32) -> f64,
    bevel: extern "C" fn(*const RayIn, u32, i32, i32, *mut Vec3) -> i32,
    max_rays: i32,
}

// SAFETY: the record is immutable after construction and holds function
// pointers and the address of a static of atomics, all fine to share
// between threads.
unsafe impl Sync for Builtins {}

/// The one process-wide built-in table; its address is handed to every state.
pub(crate) static BUILTINS: Builtins = Builtins {
    perlin1,
    perlin2,
    perlin3,
    perlin4,
    perlin3_grad,
    pperlin3,
    simplex2,
    simplex3,
    simplex4,
    simplex3_grad,
    fbm,
    fbm_grad,
    turbulence,
    ridged,
    voronoi3,
    voronoi2,
    find,
    magic,
    epoch: EPOCH_CLOCK.as_ptr(),
    course_noise,
    texture,
    course_perlin,
    trace: trace::trace_ffi,
    occlusion: trace::occlusion_ffi,
    bevel: trace::bevel_ffi,
    max_rays: trace::MAX_RAYS,
};

/// The address of [`BUILTINS`], as the prelude's light userdata wants it.
pub(crate) fn builtins_address() -> *mut std::ffi::c_void {
    std::ptr::addr_of!(BUILTINS) as *mut std::ffi::c_void
}

/// Octaves beyond this add nothing visible in f32 and would let one call run
/// unboundedly long inside Rust, where the timeout cannot reach.
const MAX_OCTAVES: i32 = 32;

/// Runs `f`, turning a panic into NaN, which the entry wrapper then reports as
/// a bad result: a panic must not unwind into LuaJIT's C frames.
#[inline]
fn guard(f: impl FnOnce() -> f32) -> f64 {
    catch_unwind(AssertUnwindSafe(f)).map_or(f64::NAN, f64::from)
}

fn octaves(n: i32) -> u32 {
    n.clamp(0, MAX_OCTAVES) as u32
}

/// Writes a gradient into the prelude's scratch vector.
fn put_grad(out: *mut Vec3, g: [f32; 3]) {
    if out.is_null() {
        return;
    }
    // SAFETY: `out` is the prelude's `ffi.new("luster_vec3")` scratch record
    // (see the module doc), alive and not aliased during this call.
    unsafe { *out = Vec3 { x: g[0].into(), y: g[1].into(), z: g[2].into() } }
}

fn grad_call(out: *mut Vec3, f: impl FnOnce() -> (f32, [f32; 3])) -> f64 {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok((v, g)) => {
            put_grad(out, g);
            v.into()
        }
        Err(_) => f64::NAN,
    }
}

extern "C" fn perlin1(x: f64) -> f64 {
    guard(|| perlin::noise1(x as f32))
}
extern "C" fn perlin2(x: f64, y: f64) -> f64 {
    guard(|| perlin::noise2(x as f32, y as f32))
}
extern "C" fn perlin3(x: f64, y: f64, z: f64) -> f64 {
    guard(|| perlin::noise3(x as f32, y as f32, z as f32))
}
/// The CENG795 lecture's noise, so a script can reproduce the `perlin` texture.
extern "C" fn course_noise(x: f64, y: f64, z: f64) -> f64 {
    guard(|| course::noise(x as f32, y as f32, z as f32))
}
/// The course's `perlin` texture map, octaves and conversion included
/// (`absval` non-zero: turbulence), computed as the built-in map does.
extern "C" fn course_perlin(x: f64, y: f64, z: f64, scale: f64, oct: i32, absval: i32) -> f64 {
    guard(|| course::texture_value([x as f32, y as f32, z as f32], scale as f32, octaves(oct), absval != 0))
}
extern "C" fn perlin4(x: f64, y: f64, z: f64, w: f64) -> f64 {
    guard(|| perlin::noise4(x as f32, y as f32, z as f32, w as f32))
}
extern "C" fn perlin3_grad(x: f64, y: f64, z: f64, g: *mut Vec3) -> f64 {
    grad_call(g, || perlin::noise3_grad(x as f32, y as f32, z as f32))
}
extern "C" fn pperlin3(x: f64, y: f64, z: f64, px: i32, py: i32, pz: i32) -> f64 {
    // A period below 1 would divide by zero inside the noise.
    guard(|| perlin::pnoise3(x as f32, y as f32, z as f32, px.max(1), py.max(1), pz.max(1)))
}
extern "C" fn simplex2(x: f64, y: f64) -> f64 {
    guard(|| simplex::noise2(x as f32, y as f32))
}
extern "C" fn simplex3(x: f64, y: f64, z: f64) -> f64 {
    guard(|| simplex::noise3(x as f32, y as f32, z as f32))
}
extern "C" fn simplex4(x: f64, y: f64, z: f64, w: f64) -> f64 {
    guard(|| simplex::noise4(x as f32, y as f32, z as f32, w as f32))
}
extern "C" fn simplex3_grad(x: f64, y: f64, z: f64, g: *mut Vec3) -> f64 {
    grad_call(g, || simplex::noise3_grad(x as f32, y as f32, z as f32))
}
extern "C" fn fbm(x: f64, y: f64, z: f64, oct: i32, lac: f64, gain: f64) -> f64 {
    guard(|| fractal::fbm3(x as f32, y as f32, z as f32, octaves(oct), lac as f32, gain as f32))
}
extern "C" fn fbm_grad(x: f64, y: f64, z: f64, oct: i32, lac: f64, gain: f64, g: *mut Vec3) -> f64 {
    grad_call(g, || fractal::fbm3_grad(x as f32, y as f32, z as f32, octaves(oct), lac as f32, gain as f32))
}
extern "C" fn turbulence(x: f64, y: f64, z: f64, oct: i32, lac: f64, gain: f64) -> f64 {
    guard(|| fractal::turbulence3(x as f32, y as f32, z as f32, octaves(oct), lac as f32, gain as f32))
}
extern "C" fn ridged(x: f64, y: f64, z: f64, oct: i32, lac: f64, gain: f64, offset: f64) -> f64 {
    guard(|| {
        fractal::ridged3(x as f32, y as f32, z as f32, octaves(oct), lac as f32, gain as f32, offset as f32)
    })
}

fn metric(m: u32) -> voronoi::Metric {
    voronoi::Metric::from_u32(m).unwrap_or(voronoi::Metric::Euclidean)
}

fn put_cell(out: *mut CellOut, c: Option<voronoi::Cell>) {
    if out.is_null() {
        return;
    }
    let rec = match c {
        Some(c) => CellOut {
            f1: c.f1.into(),
            f2: c.f2.into(),
            px: c.p1[0].into(),
            py: c.p1[1].into(),
            pz: c.p1[2].into(),
            id: c.id.into(),
        },
        None => CellOut { f1: f64::NAN, ..CellOut::default() },
    };
    // SAFETY: `out` is the prelude's `ffi.new("luster_cell")` scratch record.
    unsafe { *out = rec }
}

extern "C" fn voronoi3(x: f64, y: f64, z: f64, m: u32, jitter: f64, out: *mut CellOut) {
    let c = catch_unwind(|| voronoi::voronoi3(x as f32, y as f32, z as f32, metric(m), jitter as f32));
    put_cell(out, c.ok());
}
extern "C" fn voronoi2(x: f64, y: f64, m: u32, jitter: f64, out: *mut CellOut) {
    let c = catch_unwind(|| voronoi::voronoi2(x as f32, y as f32, metric(m), jitter as f32));
    put_cell(out, c.ok());
}

/// `texture(name, u, v, filter)`: samples image `index` of the state's images
/// into `out`. 0 on success; 1 when the state has no images or no such image
/// (the prelude resolved the name, so that means a stale index), 2 on a panic.
extern "C" fn texture(ctx: *const c_void, index: i32, u: f64, v: f64, filter: i32, out: *mut Vec3) -> i32 {
    if ctx.is_null() || out.is_null() {
        return 1;
    }
    // SAFETY: `ctx` is the address of the `Box<Arc<dyn ImageSampler>>` the
    // state owns (`state.rs`), which lives as long as the Lua state that calls
    // this; the prelude passes it unchanged and user code cannot reach it.
    let sampler = unsafe { &*ctx.cast::<Arc<dyn ImageSampler>>() };
    let filter = if filter == 0 { SampleFilter::Nearest } else { SampleFilter::Bilinear };
    let Ok(index) = usize::try_from(index) else { return 1 };
    match catch_unwind(AssertUnwindSafe(|| sampler.sample(index, u as f32, v as f32, filter))) {
        Ok(Some(c)) => {
            // SAFETY: `out` is the prelude's scratch `luster_vec3`.
            unsafe { *out = Vec3 { x: c[0].into(), y: c[1].into(), z: c[2].into() } };
            0
        }
        Ok(None) => 1,
        Err(_) => 2,
    }
}

/// `string.find` of literal text: where `p[..m]` first occurs in
/// `s[from..n]`, as a byte index into `s`, or -1. Linear in `n` and `m`
/// (`memchr`'s two-way search), where LuaJIT's own search compares the
/// whole pattern at every occurrence of its first byte (quadratic on
/// `"aaaa…"`), out of the time limit's reach.
extern "C" fn find(s: *const u8, from: i32, n: i32, p: *const u8, m: i32) -> i32 {
    let (Ok(from), Ok(n), Ok(m)) = (usize::try_from(from), usize::try_from(n), usize::try_from(m)) else {
        return -1;
    };
    if s.is_null() || p.is_null() || from > n {
        return -1;
    }
    // SAFETY: the prelude passes two Lua strings with their lengths (`#s`,
    // `#p`); LuaJIT hands a string to a `const char *` parameter as a
    // pointer to its bytes, which live for the call.
    let (s, p) = unsafe { (std::slice::from_raw_parts(s, n), std::slice::from_raw_parts(p, m)) };
    memchr::memmem::find(&s[from..], p).map_or(-1, |i| i32::try_from(from + i).unwrap_or(-1))
}

/// Whether `p[..m]` holds a character that is magic in Lua patterns
/// (`^$*+?.()[]%-`): 1 or 0. A scan of a byte table, where a Lua pattern
/// class would take a hundred times longer on a long pattern, in C.
extern "C" fn magic(p: *const u8, m: i32) -> i32 {
    const MAGIC: [bool; 256] = {
        let mut t = [false; 256];
        let chars = b"^$*+?.()[]%-";
        let mut i = 0;
        while i < chars.len() {
            t[chars[i] as usize] = true;
            i += 1;
        }
        t
    };
    let Ok(m) = usize::try_from(m) else { return 0 };
    if p.is_null() {
        return 0;
    }
    // SAFETY: the prelude passes a Lua string and its length (`find`'s).
    let p = unsafe { std::slice::from_raw_parts(p, m) };
    i32::from(p.iter().any(|&b| MAGIC[usize::from(b)]))
}

/// How often the watchdog advances the shader clock. A call is stopped
/// between one and two periods after its limit (plus scheduling delay).
pub(crate) const EPOCH_PERIOD: Duration = Duration::from_millis(5);

/// The shader clock: whole [`EPOCH_PERIOD`] periods since the watchdog started,
/// as the bits of an `f64` (Lua reads a double without boxing it). Four
/// copies, which the prelude's tick reads in turn: a load whose address
/// changes every tick is one the JIT cannot hoist out of a loop (LuaJIT
/// ignores `volatile` on FFI loads).
static EPOCH_CLOCK: [AtomicU64; 4] = [const { AtomicU64::new(0) }; 4];

/// The shader clock now, in [`EPOCH_PERIOD`] periods.
#[inline(always)]
pub(crate) fn epoch_now() -> f64 {
    f64::from_bits(EPOCH_CLOCK[0].load(Ordering::Relaxed))
}

/// Starts the watchdog thread that advances the shader clock, once per
/// process; false when it cannot run (no thread could be started), and then
/// no shader may run, since nothing would stop it.
///
/// The watchdog makes the time limit independent of what the shader does:
/// the tick that instrumented code runs in every loop and function reads
/// the clock directly (no count of ticks between reads), and after every
/// call Rust compares it with the call's start, so a single slow library
/// call that overran is reported as a timeout too.
pub(crate) fn start_watchdog() -> bool {
    static STARTED: OnceLock<bool> = OnceLock::new();
    *STARTED.get_or_init(|| {
        std::thread::Builder::new()
            .name("shader-clock".into())
            .stack_size(64 * 1024)
            .spawn(|| {
                let t0 = Instant::now();
                loop {
                    std::thread::sleep(EPOCH_PERIOD);
                    // From the elapsed time, not a count of wake-ups, so a
                    // late wake-up never slows the clock.
                    let periods = (t0.elapsed().as_nanos() / EPOCH_PERIOD.as_nanos()) as f64;
                    for copy in &EPOCH_CLOCK {
                        copy.store(periods.to_bits(), Ordering::Relaxed);
                    }
                }
            })
            .is_ok()
    })
}

/// A time limit in [`EPOCH_PERIOD`] periods, rounded up, plus one: the clock
/// a call starts from may be one period behind (the watchdog wakes late), and
/// a call is never stopped before its limit.
pub(crate) fn limit_periods(timeout: Duration) -> f64 {
    (timeout.as_nanos() as f64 / EPOCH_PERIOD.as_nanos() as f64).ceil() + 1.0
}

/// Rust's handle on one state's shared records (see the module doc for why the
/// pointers stay valid).
pub(crate) struct IoBlock {
    shade: *mut Shade,
    /// The three points of a bump evaluation: `shade`, `shade_b`, `shade_c`.
    shade3: [*mut Shade; 3],
    out: *mut Out,
    material: *mut MaterialOut,
    clock: *mut Clock,
    derivs: *mut Derivs,
}

/// The addresses of the records the prelude allocated, as it reports them.
pub(crate) struct Addresses {
    pub shade: usize,
    pub shade_b: usize,
    pub shade_c: usize,
    pub out: usize,
    pub material: usize,
    pub clock: usize,
    pub derivs: usize,
}

impl IoBlock {
    /// Takes the addresses the prelude reported. They are checked for null
    /// and alignment; the prelude allocated them with `ffi.new` of the
    /// matching C types.
    pub(crate) fn new(a: Addresses, limit: f64) -> Option<IoBlock> {
        let Addresses { shade, shade_b, shade_c, out, material, clock, derivs } = a;
        fn ok<T>(a: usize) -> bool {
            a != 0 && a % std::mem::align_of::<T>() == 0
        }
        if !(ok::<Shade>(shade)
            && ok::<Shade>(shade_b)
            && ok::<Shade>(shade_c)
            && ok::<Out>(out)
            && ok::<MaterialOut>(material)
            && ok::<Clock>(clock)
            && ok::<Derivs>(derivs))
        {
            return None;
        }
        let block = IoBlock {
            shade: shade as *mut Shade,
            shade3: [shade as *mut Shade, shade_b as *mut Shade, shade_c as *mut Shade],
            out: out as *mut Out,
            material: material as *mut MaterialOut,
            clock: clock as *mut Clock,
            derivs: derivs as *mut Derivs,
        };
        // SAFETY: see the module doc; no Lua code runs during this write.
        unsafe { (*block.clock).limit = limit }
        Some(block)
    }

    /// Writes the shading point (`fill` writes it in place, so the record
    /// is never copied) and arms the clock for one call.
    #[inline]
    pub(crate) fn begin(&self, fill: impl FnOnce(&mut Shade)) {
        // SAFETY: see the module doc; no Lua code runs during these writes,
        // and no other reference to the record exists while `fill` runs.
        unsafe {
            fill(&mut *self.shade);
            self.arm();
        }
    }

    /// Clears the rejection flag and arms the clock for one call. The
    /// channels need no clearing: a wrapper that returns normally has
    /// written every one its entry point's caller reads.
    ///
    /// # Safety
    ///
    /// No Lua code runs (see the module doc).
    #[inline]
    unsafe fn arm(&self) {
        (*self.out).bad = 0;
        (*self.clock).start = epoch_now();
        (*self.clock).depth = 0;
        (*self.clock).rays = 0;
    }

    /// Whether the last call asked to be run again (see [`Derivs`]).
    #[inline(always)]
    pub(crate) fn redo(&self) -> bool {
        // SAFETY: see the module doc; the Lua call has returned.
        unsafe { (*self.derivs).redo != 0 }
    }

    /// [`IoBlock::redo`], clearing the flag.
    pub(crate) fn take_redo(&self) -> bool {
        // SAFETY: see the module doc; no Lua code runs.
        unsafe {
            let r = (*self.derivs).redo != 0;
            (*self.derivs).redo = 0;
            r
        }
    }

    /// Writes the shading points again for a call that runs again
    /// ([`IoBlock::redo`]): the first `points` of them (1, or 3 for a
    /// bump), since the script may have changed them. The clock keeps its
    /// start, so the time limit covers both runs.
    pub(crate) fn refill(&self, points: usize, mut fill: impl FnMut(usize, &mut Shade)) {
        // SAFETY: as in `begin3`.
        unsafe {
            for (k, &s) in self.shade3.iter().enumerate().take(points) {
                fill(k, &mut *s);
            }
            (*self.out).bad = 0;
            (*self.clock).depth = 0;
        }
    }

    /// Writes the shading point and arms the clock for one `DecalMode
    /// material` call. The record needs no clearing: the wrapper writes
    /// every output the script defines, and a closure's count (the nodes
    /// past it are never read).
    #[inline]
    pub(crate) fn begin_material(&self, fill: impl FnOnce(&mut Shade)) {
        self.begin(fill);
    }

    /// What the material wrapper wrote, as [`MaterialOutputs`], into `out`:
    /// the outputs for which `defines` is true, or the closure alone when it
    /// defines `material`. Reads only the nodes in use, not the whole
    /// record, and writes the closure in place (it is large, and most
    /// closures use a few of its nodes). `false` when the closure is
    /// malformed (see [`closure_of`]).
    pub(crate) fn material_outputs(
        &self,
        defines: impl Fn(Entry) -> bool,
        out: &mut MaterialOutputs,
    ) -> bool {
        // SAFETY: see the module doc; the Lua call has returned, and nothing
        // writes the record while this reference lives.
        let m = unsafe { &*self.material };
        if defines(Entry::Material) {
            let closure = out.closure.get_or_insert_with(Closure::default);
            let ok = closure_of(m, closure).is_some();
            (out.color, out.specular, out.roughness, out.metalness, out.emission, out.reflect) =
                (None, None, None, None, None, None);
            return ok;
        }
        let rgb = |e: Entry, c: [f64; 3]| defines(e).then(|| c.map(|x| x as f32));
        let num = |e: Entry, x: f64| defines(e).then_some(x as f32);
        out.color = rgb(Entry::Color, m.color);
        out.specular = rgb(Entry::Specular, m.specular);
        out.roughness = num(Entry::Roughness, m.roughness);
        out.metalness = num(Entry::Metalness, m.metalness);
        out.emission = rgb(Entry::Emission, m.emission);
        out.reflect = rgb(Entry::Reflect, m.reflect);
        out.closure = None;
        true
    }

    /// Writes the three points of a bump evaluation and arms the clock: the
    /// time limit covers the three `height` calls together.
    #[inline]
    pub(crate) fn begin3(&self, mut fill: impl FnMut(usize, &mut Shade)) {
        // SAFETY: see the module doc; no Lua code runs during these writes,
        // and no other reference to the records exists while `fill` runs
        // (the three are distinct allocations).
        unsafe {
            for (k, &s) in self.shade3.iter().enumerate() {
                fill(k, &mut *s);
            }
            self.arm();
        }
    }

    /// The three channels the entry wrapper wrote, each read on its own:
    /// LuaJIT stores them one double at a time, and a copy of the record
    /// would read two of them in one 16-byte load, which no store can forward
    /// to (the load would wait for both stores to reach the cache).
    #[inline(always)]
    pub(crate) fn channels(&self) -> [f64; 3] {
        // SAFETY: see the module doc; the Lua call has returned. Volatile
        // only so that the three loads are not merged into wider ones.
        unsafe {
            let o = self.out;
            [
                std::ptr::addr_of!((*o).r).read_volatile(),
                std::ptr::addr_of!((*o).g).read_volatile(),
                std::ptr::addr_of!((*o).b).read_volatile(),
            ]
        }
    }

    /// The result the entry wrapper wrote.
    pub(crate) fn out(&self) -> Out {
        // SAFETY: see the module doc; the Lua call has returned.
        unsafe { *self.out }
    }

    /// Whether the last call failed because the wrapper rejected its result.
    pub(crate) fn bad_result(&self) -> bool {
        self.out().bad != 0
    }

    /// Whether the last call ran past its deadline: whether it was
    /// stopped, or finished late (a slow library call can overrun between
    /// two ticks), which counts as a timeout too.
    #[inline(always)]
    pub(crate) fn timed_out(&self) -> bool {
        // SAFETY: see the module doc; the Lua call has returned.
        let (start, limit) = unsafe { ((*self.clock).start, (*self.clock).limit) };
        epoch_now() - start > limit
    }
}
