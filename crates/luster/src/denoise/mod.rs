//! Denoising a finished render with Intel Open Image Denoise (OIDN), behind
//! the `oidn` cargo feature.
//!
//! OIDN's `RT` filter is a neural network trained on path-traced images from
//! 1 sample per pixel to nearly converged. It takes the noisy beauty image
//! and, optionally, first-hit albedo and normal images (feature buffers),
//! which let it keep texture and geometric edges that the noise hides.
//!
//! What luster passes it:
//!
//! | OIDN parameter | value | why |
//! |---|---|---|
//! | `hdr` | true | the film is linear and unbounded |
//! | `inputScale` | unset: OIDN's auto-exposure | the film's units are the scene's: 255 is white in a course image, radiance near 1 in a path-traced EXR |
//! | `cleanAux` | true with feature buffers | they are prefiltered first (below) |
//! | `quality` | high (the default) | final frames, not previews |
//!
//! With feature buffers, each is first denoised by an `RT` filter of its own
//! (OIDN's recommended final-frame path): feature buffers averaged over the
//! pixel's samples still carry noise from depth of field, motion and rough
//! reflections, and a network told they are clean (`cleanAux`) would keep
//! that noise. A normal buffer is only used together with an albedo buffer,
//! as OIDN's filter has no normal-only mode.
//!
//! OIDN runs on the CPU device with as many threads as the calling rayon
//! pool has, so `--threads` bounds it too. Values a network cannot take are
//! replaced before it sees them: a non-finite or negative beauty channel
//! becomes 0 (black), an albedo channel is clamped to [0, 1] and a normal
//! channel to [-1, 1] (non-finite: 0). Without the feature every call fails
//! with one sentence saying how to build it.

#[cfg(feature = "oidn")]
mod ffi;

use luster_core::math::Vec3;

/// Whether this build of luster can denoise (the `oidn` cargo feature).
pub const AVAILABLE: bool = cfg!(feature = "oidn");

/// How to get a luster that denoises, for a build without the feature.
pub const HOW_TO_BUILD: &str = "this luster was built without Open Image Denoise: build it with \
     `cargo build --release --features oidn` and OIDN 2 installed (see docs/denoising.md)";

/// An Open Image Denoise device, created once and used for every image.
pub struct Denoiser {
    #[cfg(feature = "oidn")]
    device: ffi::Device,
}

impl Denoiser {
    /// Starts OIDN's CPU device with `threads` worker threads (0: all
    /// cores). Fails, with one sentence, when the build lacks the `oidn`
    /// feature or OIDN cannot run on this machine (its CPU device module
    /// missing, a CPU without SSE4.1).
    pub fn new(threads: usize) -> Result<Denoiser, String> {
        #[cfg(feature = "oidn")]
        {
            Ok(Denoiser { device: ffi::Device::cpu(threads)? })
        }
        #[cfg(not(feature = "oidn"))]
        {
            let _ = threads;
            Err(HOW_TO_BUILD.to_string())
        }
    }

    /// The denoised `color` (`width` × `height` pixels, row by row, film
    /// units), guided by an `albedo` and a `normal` image of the same size
    /// when given (see the module's documentation for what is done with
    /// them). Errors: buffers of the wrong length, a normal buffer without an
    /// albedo buffer, or a failure inside OIDN (out of memory, say).
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[Vec3],
        albedo: Option<&[Vec3]>,
        normal: Option<&[Vec3]>,
    ) -> Result<Vec<Vec3>, String> {
        check_sizes(width, height, color, albedo, normal)?;
        #[cfg(feature = "oidn")]
        {
            let size = (width as usize, height as usize);
            let color = flatten(color, |c| if c.is_finite() && c > 0.0 { c } else { 0.0 });
            let albedo = albedo.map(|a| flatten(a, |c| if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.0 }));
            let normal = normal.map(|n| flatten(n, |c| if c.is_finite() { c.clamp(-1.0, 1.0) } else { 0.0 }));
            let out = self.device.denoise(size, &color, albedo.as_deref(), normal.as_deref())?;
            Ok(out
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]).max(Vec3::ZERO))
                .map(|p| if p.is_finite() { p } else { Vec3::ZERO })
                .collect())
        }
        #[cfg(not(feature = "oidn"))]
        {
            Err(HOW_TO_BUILD.to_string())
        }
    }
}

/// [`Denoiser::denoise`] with a denoiser made for this one image, using the
/// current rayon pool's thread count.
pub fn denoise(
    width: u32,
    height: u32,
    color: &[Vec3],
    albedo: Option<&[Vec3]>,
    normal: Option<&[Vec3]>,
) -> Result<Vec<Vec3>, String> {
    Denoiser::new(rayon::current_num_threads())?.denoise(width, height, color, albedo, normal)
}

/// Every buffer has `width` × `height` pixels, and a normal buffer comes
/// with an albedo buffer.
fn check_sizes(
    width: u32,
    height: u32,
    color: &[Vec3],
    albedo: Option<&[Vec3]>,
    normal: Option<&[Vec3]>,
) -> Result<(), String> {
    let n = width as usize * height as usize;
    if n == 0 {
        return Err(format!("cannot denoise a {width}x{height} image: it has no pixels"));
    }
    for (name, len) in [
        ("colour", Some(color.len())),
        ("albedo", albedo.map(<[_]>::len)),
        ("normal", normal.map(<[_]>::len)),
    ] {
        if let Some(len) = len.filter(|&len| len != n) {
            return Err(format!("cannot denoise: the {name} image has {len} pixels, not {width}x{height}"));
        }
    }
    if normal.is_some() && albedo.is_none() {
        return Err("cannot denoise with a normal image but no albedo image (OIDN uses normals only \
                    together with albedo)"
            .to_string());
    }
    Ok(())
}

/// Three floats per pixel, each mapped by `f`: the layout OIDN's `FLOAT3`
/// images have.
#[cfg(feature = "oidn")]
fn flatten(pixels: &[Vec3], f: impl Fn(f32) -> f32) -> Vec<f32> {
    pixels.iter().flat_map(|p| [f(p.x), f(p.y), f(p.z)]).collect()
}

#[cfg(test)]
mod tests;
