//! Calling a [`ThreadState`]'s entry points: the fast path of a call (a
//! clean return, the result in the output record), and what the others
//! amount to (an error, a caught timeout, `--debug-pixel` output, a missing
//! entry point).

use std::os::raw::c_int;

use luster_core::text::shown;

use super::call::Slot;
use super::compile::{Compiled, WRAPPERS};
use super::error::{ShaderError, ShaderErrorKind};
use super::ffi;
use super::shade::{describe, fill_point, fill_shade, object_random};
use super::state::ThreadState;
use super::threads::MISS;
use super::{Entry, MaterialOutputs, ShadeInput, ShadePoint};

impl ThreadState {
    /// Calls one entry point; the result's channels (a height in `[0]`).
    pub(crate) fn call(&self, id: usize, entry: Entry, input: &ShadeInput) -> Result<[f64; 3], ShaderError> {
        let mut rgb = [0.0; 3];
        match self.call_fast(id, entry, input, &mut rgb) {
            0 => Ok(rgb),
            code => self.finish(id, entry, input, code),
        }
    }

    /// The common case of a call (a defined entry, a clean return within
    /// the time limit, no `--debug-pixel`): 0, with the result's channels in
    /// `rgb`. Otherwise a code for [`ThreadState::finish`]: [`MISS`] when
    /// the call did not run (no such entry), or [`RAN`] with the call's
    /// status. A bare code, so the hot path moves no error-sized value.
    #[inline]
    pub(crate) fn call_fast(&self, id: usize, entry: Entry, input: &ShadeInput, rgb: &mut [f64; 3]) -> u32 {
        self.call_with(id, entry, input.instance_id, |s, random| fill_shade(self.avx, s, input, random), rgb)
    }

    /// [`ThreadState::call_fast`] of a renderer's point ([`fill_point`]).
    #[inline]
    pub fn call_fast_point<P: ShadePoint>(&self, id: usize, entry: Entry, p: &P, rgb: &mut [f64; 3]) -> u32 {
        self.call_with(id, entry, p.instance_id(), |s, random| fill_point(self.avx, s, p, random), rgb)
    }

    /// The body of both fast paths; `fill` writes the shading point (each
    /// caller has its own writer: see [`fill_point`]).
    #[inline(always)]
    fn call_with(
        &self,
        id: usize,
        entry: Entry,
        instance_id: u32,
        fill: impl Fn(&mut ffi::Shade, f64),
        rgb: &mut [f64; 3],
    ) -> u32 {
        let Some(f) = self.shaders.get(id).and_then(|s| s.entries[entry as usize]) else {
            return MISS;
        };
        let random = self.random(instance_id);
        self.io.begin(|s| fill(s, random));
        let status = self.caller.call(f);
        if status == mlua::ffi::LUA_OK
            && !self.io.timed_out()
            && !self.io.redo()
            && super::debug_pixel().is_none()
        {
            store_channels(rgb, self.io.channels());
            return 0;
        }
        let status = self.again(f, status, 1, |_, s| fill(s, random));
        if status == mlua::ffi::LUA_OK && !self.io.timed_out() && super::debug_pixel().is_none() {
            store_channels(rgb, self.io.channels());
            return 0;
        }
        ran(status)
    }

    /// Runs the wrapper at `f` again while the last run asked for it: an
    /// entry function took its first derivative, in a run that computed
    /// none (`prelude.lua`, "Derivatives"). `fill` writes the `points`
    /// shading points again; the time limit keeps its start. The status of
    /// the last run. Each run turns one more entry function to three runs
    /// a call, so a call runs at most once per function it calls, plus one.
    #[cold]
    #[inline(never)]
    fn again(
        &self,
        f: Slot,
        mut status: c_int,
        points: usize,
        fill: impl Fn(usize, &mut ffi::Shade),
    ) -> c_int {
        for _ in 0..=WRAPPERS {
            if !self.io.take_redo() {
                break;
            }
            if status != mlua::ffi::LUA_OK {
                self.caller.drop_error();
            }
            self.io.refill(points, &fill);
            status = self.caller.call(f);
        }
        status
    }

    /// What a code from [`ThreadState::call_fast`] amounts to.
    #[cold]
    #[inline(never)]
    pub(crate) fn finish(
        &self,
        id: usize,
        entry: Entry,
        input: &ShadeInput,
        code: u32,
    ) -> Result<[f64; 3], ShaderError> {
        match status_of(code) {
            Some(status) => self.finish_call(id, entry, input, status),
            None if entry == Entry::Material && self.shaders.get(id).is_some_and(|s| s.closure) => {
                Err(ShaderError::new(
                    ShaderErrorKind::Usage,
                    &self.shaders[id].name,
                    "material(s) returns a closure, which ShaderSet::material gives; it has no single result",
                ))
            }
            None => Err(self.no_entry(id, entry.name())),
        }
    }

    /// [`object_random`] of `id`, remembered for the next call: a pixel's
    /// points mostly lie on one object.
    #[inline]
    fn random(&self, id: u32) -> f64 {
        let (last, r) = self.last_random.get();
        if last == id {
            return r;
        }
        let r = object_random(id);
        self.last_random.set((id, r));
        r
    }

    /// [`ThreadState::call`] past its fast path: an error, a timeout the
    /// script caught, or a call to show for `--debug-pixel`.
    #[cold]
    #[inline(never)]
    fn finish_call(
        &self,
        id: usize,
        entry: Entry,
        input: &ShadeInput,
        status: c_int,
    ) -> Result<[f64; 3], ShaderError> {
        let shader = &self.shaders[id];
        let result = self.outcome(shader, status).map(|()| {
            let o = self.io.out();
            [o.r, o.g, o.b]
        });
        if super::debug_pixel() == Some(input.pixel) {
            let out = match &result {
                Ok(c)
                    if matches!(
                        entry,
                        Entry::Height | Entry::Density | Entry::Roughness | Entry::Metalness
                    ) =>
                {
                    format!("{}", c[0])
                }
                Ok(c) => format!("{} {} {}", c[0], c[1], c[2]),
                Err(e) => format!("error: {}", e.message),
            };
            eprintln!(
                "[shader {} at pixel {},{}] {}(s) -> {out}\n  s = {}",
                shown(&shader.name, false),
                input.pixel[0],
                input.pixel[1],
                entry.name(),
                describe(input)
            );
        }
        result
    }

    /// What a finished call amounts to: its error (popped off the call
    /// thread), a caught timeout, or success.
    fn outcome(&self, shader: &Compiled, status: c_int) -> Result<(), ShaderError> {
        if status != mlua::ffi::LUA_OK {
            let e = self.caller.pop_error(&self.lua, status);
            return Err(self.error(&shader.name, &shader.file, &e));
        }
        self.check_deadline(&shader.name)
    }

    /// The usage error for a missing shader or entry point.
    #[cold]
    #[inline(never)]
    fn no_entry(&self, id: usize, entry: &str) -> ShaderError {
        match self.shaders.get(id) {
            None => ShaderError::new(
                ShaderErrorKind::Usage,
                &format!("#{id}"),
                format!("no shader with id {id} (the set has {})", self.shaders.len()),
            ),
            Some(shader) if entry == "material" => ShaderError::new(
                ShaderErrorKind::Usage,
                &shader.name,
                "the script defines neither material(s) nor any of the material outputs (color, specular, \
                 roughness, metalness, emission, reflect)",
            ),
            Some(shader) => ShaderError::new(
                ShaderErrorKind::Usage,
                &shader.name,
                format!("the script defines no {entry}() function"),
            ),
        }
    }

    /// Calls every material output shader `id` defines, or its
    /// `material(s)`, in one Lua call, and writes what it says into `out`.
    pub(crate) fn call_material(
        &self,
        id: usize,
        input: &ShadeInput,
        out: &mut MaterialOutputs,
    ) -> Result<(), ShaderError> {
        let Some(f) = self.shaders.get(id).and_then(|s| s.material) else {
            return Err(self.no_entry(id, "material"));
        };
        let random = self.random(input.instance_id);
        self.io.begin_material(|s| fill_shade(self.avx, s, input, random));
        let mut status = self.caller.call(f);
        if self.io.redo() {
            status = self.again(f, status, 1, |_, s| fill_shade(self.avx, s, input, random));
        }
        let shader = &self.shaders[id];
        let defines = self.entries(id);
        let result = self.outcome(shader, status).and_then(|()| {
            if self.io.material_outputs(|e| defines[e as usize], out) {
                Ok(())
            } else {
                let msg = "shader runtime: material(s) wrote a malformed closure";
                Err(ShaderError::new(ShaderErrorKind::Internal, &shader.name, msg))
            }
        });
        if super::debug_pixel() == Some(input.pixel) {
            let said = match (&result, &out.closure) {
                (Ok(()), Some(c)) => format!("closure {c}"),
                (Ok(()), None) => describe_outputs(out),
                (Err(e), _) => format!("error: {}", e.message),
            };
            eprintln!(
                "[shader {} at pixel {},{}] material(s) -> {said}\n  s = {}",
                shown(&shader.name, false),
                input.pixel[0],
                input.pixel[1],
                describe(input)
            );
        }
        result
    }

    /// Calls `height` at three points in one Lua call (bump mapping).
    pub(crate) fn call_height3(&self, id: usize, inputs: &[ShadeInput; 3]) -> Result<[f64; 3], ShaderError> {
        let mut h = [0.0; 3];
        match self.call_height3_fast(id, inputs, &mut h) {
            0 => Ok(h),
            code => self.finish_height3(id, code),
        }
    }

    /// [`ThreadState::call_fast`] for [`ThreadState::call_height3`].
    #[inline]
    pub(crate) fn call_height3_fast(&self, id: usize, inputs: &[ShadeInput; 3], h: &mut [f64; 3]) -> u32 {
        let Some(f) = self.shaders.get(id).and_then(|s| s.height3) else {
            return MISS;
        };
        let random = inputs.map(|i| self.random(i.instance_id));
        self.io.begin3(|k, s| fill_shade(self.avx, s, &inputs[k], random[k]));
        let mut status = self.caller.call(f);
        if self.io.redo() {
            status = self.again(f, status, 3, |k, s| fill_shade(self.avx, s, &inputs[k], random[k]));
        }
        if status == mlua::ffi::LUA_OK && !self.io.timed_out() {
            store_channels(h, self.io.channels());
            return 0;
        }
        ran(status)
    }

    /// What a code from [`ThreadState::call_height3_fast`] amounts to.
    #[cold]
    #[inline(never)]
    pub(crate) fn finish_height3(&self, id: usize, code: u32) -> Result<[f64; 3], ShaderError> {
        let Some(status) = status_of(code) else {
            return Err(self.no_entry(id, "height"));
        };
        self.outcome(&self.shaders[id], status).map(|()| {
            let o = self.io.out();
            [o.r, o.g, o.b]
        })
    }
}

/// Stores a call's channels where its caller reads them: the first two in
/// one 16-byte store, because the callers convert them to `f32` two at a
/// time (`cvtpd2ps` of a 16-byte load), which two 8-byte stores could not
/// forward to (a store-forwarding stall on every call).
#[inline(always)]
fn store_channels(out: &mut [f64; 3], c: [f64; 3]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_set_pd, _mm_storeu_pd};
        // SAFETY: `out` has room for two doubles at its start (SSE2 is part
        // of x86_64).
        unsafe { _mm_storeu_pd(out.as_mut_ptr(), _mm_set_pd(c[1], c[0])) };
        out[2] = c[2];
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        *out = c;
    }
}

/// A code from a fast call (`call_fast`) that ran and needs finishing: the
/// call's status, marked so that it differs from 0 and from [`MISS`].
pub(crate) const RAN: u32 = 1 << 31;

fn ran(status: c_int) -> u32 {
    RAN | (status as u32 & 0xffff)
}

/// The Lua status in a [`RAN`] code; `None` for [`MISS`].
fn status_of(code: u32) -> Option<c_int> {
    (code != MISS && code & RAN != 0).then_some((code & 0xffff) as c_int)
}

/// The outputs a script without `material(s)` defined, for `--debug-pixel`:
/// `color=(r, g, b) roughness=x ...`.
fn describe_outputs(m: &MaterialOutputs) -> String {
    let rgb = |k: &str, c: Option<[f32; 3]>| c.map(|c| format!("{k}=({}, {}, {})", c[0], c[1], c[2]));
    let num = |k: &str, x: Option<f32>| x.map(|x| format!("{k}={x}"));
    [
        rgb("color", m.color),
        rgb("specular", m.specular),
        num("roughness", m.roughness),
        num("metalness", m.metalness),
        rgb("emission", m.emission),
        rgb("reflect", m.reflect),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>()
    .join(" ")
}
