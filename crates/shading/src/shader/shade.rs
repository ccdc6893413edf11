//! Writing the shading point into the record the prelude reads (`s` in a
//! script), and the per-object `s.random`.

use super::ffi::{self, Shade};
use super::{ShadeInput, ShadePoint};

/// Writes one shading point into the record the prelude reads, with AVX
/// where the CPU has it (`avx`, from [`has_avx`]): the record's 59 doubles
/// are converted from floats four at a time, in half the stores of SSE2's
/// two at a time. Same values: a float converts to a double exactly either
/// way.
#[inline(always)]
pub(super) fn fill_shade(avx: bool, s: &mut Shade, i: &ShadeInput, random_value: f64) {
    #[cfg(target_arch = "x86_64")]
    if avx {
        // SAFETY: `avx` is true only where the CPU has AVX (`has_avx`).
        unsafe { write_shade_avx(s, i, random_value) };
        return;
    }
    let _ = avx;
    write_shade(s, i, random_value);
}

/// [`fill_shade`] of a renderer's point: built inside the writer
/// ([`ShadePoint::input`] inlines there), so it goes from the hit into the
/// record without being stored as a [`ShadeInput`] first, whose loads
/// would straddle its stores (no forwarding). (A [`ShadeInput`] that is
/// already in memory keeps [`fill_shade`], the cheaper path for it.)
#[inline(always)]
pub(super) fn fill_point<P: ShadePoint>(avx: bool, s: &mut Shade, p: &P, random_value: f64) {
    #[cfg(target_arch = "x86_64")]
    if avx {
        // SAFETY: `avx` is true only where the CPU has AVX (`has_avx`).
        unsafe { write_point_avx(s, p, random_value) };
        return;
    }
    let _ = avx;
    write_point_plain(s, p, random_value);
}

/// [`write_shade`] of `p`'s point without AVX: out of line, so that the
/// callers' fast path does not carry a second copy of the point's
/// arithmetic (and the registers it needs).
#[inline(never)]
fn write_point_plain<P: ShadePoint>(s: &mut Shade, p: &P, random_value: f64) {
    write_shade(s, &p.input(), random_value);
}

/// Whether [`fill_shade`] may use AVX on this CPU.
pub(super) fn has_avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::is_x86_feature_detected!("avx");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// [`write_shade`] compiled with AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn write_shade_avx(s: &mut Shade, i: &ShadeInput, random_value: f64) {
    write_shade(s, i, random_value);
}

/// [`write_shade`] of `p`'s point, compiled with AVX (the point's own
/// arithmetic too: the same operations, so the same values).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn write_point_avx<P: ShadePoint>(s: &mut Shade, p: &P, random_value: f64) {
    write_shade(s, &p.input(), random_value);
}

/// Writes one shading point into the record the prelude reads, in place.
/// The record is destructured whole so that a field added to it cannot be
/// left unwritten.
#[inline(always)]
fn write_shade(s: &mut Shade, i: &ShadeInput, random_value: f64) {
    let v = |a: [f32; 3]| ffi::Vec3 { x: a[0].into(), y: a[1].into(), z: a[2].into() };
    let int = |x: u32| i32::try_from(x).unwrap_or(i32::MAX);
    let Shade {
        p,
        pw,
        pc,
        n,
        ng,
        i: incident,
        v: view,
        dpdu,
        dpdv,
        dpdx,
        dpdy,
        uv,
        time,
        filterwidth,
        random,
        object_id,
        instance_id,
        depth,
        pixel_x,
        pixel_y,
        pad,
        dpwdx,
        dpwdy,
        dpcdx,
        dpcdy,
        duvdx,
        duvdy,
    } = s;
    *p = v(i.p);
    *pw = v(i.pw);
    *pc = v(i.pc);
    *n = v(i.n);
    *ng = v(i.ng);
    *incident = v(i.i);
    *view = v(i.i.map(|c| -c));
    *dpdu = v(i.dpdu);
    *dpdv = v(i.dpdv);
    *dpdx = v(i.dpdx);
    *dpdy = v(i.dpdy);
    *uv = ffi::Vec2 { u: i.uv[0].into(), v: i.uv[1].into() };
    *time = i.time.into();
    *filterwidth = i.filterwidth.into();
    *random = random_value;
    *object_id = int(i.object_id);
    *instance_id = int(i.instance_id);
    *depth = int(i.depth);
    *pixel_x = int(i.pixel[0]);
    *pixel_y = int(i.pixel[1]);
    *pad = 0;
    *dpwdx = v(i.dpwdx);
    *dpwdy = v(i.dpwdy);
    *dpcdx = v(i.dpcdx);
    *dpcdy = v(i.dpcdy);
    *duvdx = ffi::Vec2 { u: i.duvdx[0].into(), v: i.duvdx[1].into() };
    *duvdy = ffi::Vec2 { u: i.duvdy[0].into(), v: i.duvdy[1].into() };
}

/// The shading point as `--debug-pixel` prints it.
pub(super) fn describe(i: &ShadeInput) -> String {
    let v = |a: [f32; 3]| format!("({}, {}, {})", a[0], a[1], a[2]);
    format!(
        "{{ P = {}, Pw = {}, Pc = {}, N = {}, Ng = {}, I = {}, uv = ({}, {}), dPdu = {}, dPdv = {}, \
         dPdx = {}, dPdy = {}, dPwdx = {}, dPwdy = {}, dPcdx = {}, dPcdy = {}, duvdx = ({}, {}), \
         duvdy = ({}, {}), filterwidth = {}, object_id = {}, instance_id = {}, depth = {}, time = {} }}",
        v(i.p),
        v(i.pw),
        v(i.pc),
        v(i.n),
        v(i.ng),
        v(i.i),
        i.uv[0],
        i.uv[1],
        v(i.dpdu),
        v(i.dpdv),
        v(i.dpdx),
        v(i.dpdy),
        v(i.dpwdx),
        v(i.dpwdy),
        v(i.dpcdx),
        v(i.dpcdy),
        i.duvdx[0],
        i.duvdx[1],
        i.duvdy[0],
        i.duvdy[1],
        i.filterwidth,
        i.object_id,
        i.instance_id,
        i.depth,
        i.time
    )
}

/// A repeatable number in [0, 1) per object (SplitMix64's finaliser): the
/// same on every thread and run, different between neighbouring ids.
pub(crate) fn object_random(id: u32) -> f64 {
    let mut z = u64::from(id).wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}
