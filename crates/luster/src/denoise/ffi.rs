//! The calls into Open Image Denoise's C API that the `oidn` crate's safe
//! wrapper does not offer: a CPU device with a thread count, feature-buffer
//! prefiltering (an `RT` filter whose only input is `albedo` or `normal`)
//! and the `cleanAux` parameter (the wrapper's `clean_aux` sets a parameter
//! name OIDN does not know, which it ignores). Devices and buffers are the
//! crate's safe types; only the filter is driven through `oidn::sys`.
//!
//! Soundness: every handle passed to OIDN is live for the call. `Device`
//! owns its handle (released on drop by `oidn::Device`); a `Filter` is
//! released on drop and borrows the device, and the buffers it reads and
//! writes are borrowed for the whole of `run`, so none can be released while
//! OIDN holds them. Parameter names are NUL-terminated literals. Buffers are
//! sized from the image (3 floats a pixel) and the images set on a filter
//! are `FLOAT3` of exactly that size, so OIDN never reads or writes past
//! them. OIDN's API is thread-safe; a `Device` is used from one thread.

use oidn::sys;
use std::ffi::CStr;

/// An OIDN CPU device.
pub(super) struct Device(oidn::Device);

impl Device {
    /// A committed CPU device with `threads` threads (0: OIDN's default, all
    /// cores), or OIDN's reason why not.
    pub(super) fn cpu(threads: usize) -> Result<Device, String> {
        // SAFETY: oidnNewDevice takes an enum value and returns an owned
        // handle or null; null is checked before any other use.
        let handle = unsafe { sys::oidnNewDevice(sys::OIDNDeviceType_OIDN_DEVICE_TYPE_CPU) };
        if handle.is_null() {
            return Err(format!("Open Image Denoise cannot start its CPU device: {}", null_device_error()));
        }
        let threads = i32::try_from(threads).unwrap_or(0);
        // SAFETY: `handle` is a live device; from_raw takes over its one
        // reference, so oidn::Device's drop releases it on every path below.
        let device = unsafe {
            sys::oidnSetDeviceInt(handle, c"numThreads".as_ptr(), threads);
            sys::oidnSetDeviceInt(handle, c"verbose".as_ptr(), 0);
            sys::oidnCommitDevice(handle);
            oidn::Device::from_raw(handle)
        };
        device.get_error().map_err(|e| format!("Open Image Denoise cannot start its CPU device: {e}"))?;
        Ok(Device(device))
    }

    /// The denoised `color` (`FLOAT3`, `size` pixels), with prefiltered
    /// `albedo` and `normal` when given.
    pub(super) fn denoise(
        &self,
        size: (usize, usize),
        color: &[f32],
        albedo: Option<&[f32]>,
        normal: Option<&[f32]>,
    ) -> Result<Vec<f32>, String> {
        let failed = |e: oidn::Error| format!("Open Image Denoise failed: {e}");
        let buffer = |v: &[f32]| self.0.create_buffer(v).map_err(failed);
        let color = buffer(color)?;
        let output = buffer(&vec![0.0; color.size()])?;
        let albedo = albedo.map(buffer).transpose()?;
        let normal = normal.map(buffer).transpose()?;
        // Prefiltered in place, then marked clean for the beauty's filter.
        if let Some(a) = &albedo {
            Filter::new(self)?.run(self, size, &[(c"albedo", a), (c"output", a)], false)?;
        }
        if let (Some(_), Some(n)) = (&albedo, &normal) {
            Filter::new(self)?.run(self, size, &[(c"normal", n), (c"output", n)], false)?;
        }
        let mut images = vec![(c"color", &color), (c"output", &output)];
        if let Some(a) = &albedo {
            images.push((c"albedo", a));
            if let Some(n) = &normal {
                images.push((c"normal", n));
            }
        }
        Filter::new(self)?.run(self, size, &images, true)?;
        output.read().map_err(failed)
    }

    fn error(&self, what: &str) -> Result<(), String> {
        self.0.get_error().map_err(|e| format!("Open Image Denoise failed {what}: {e}"))
    }
}

/// OIDN's message for an error not tied to a device (one that could not be
/// created is reported on the null device).
fn null_device_error() -> String {
    let mut message: *const std::ffi::c_char = std::ptr::null();
    // SAFETY: the null device is valid here by OIDN's API; `message` is
    // either left null or set to a NUL-terminated string OIDN keeps alive
    // until the next call on this thread, and is copied at once.
    unsafe {
        sys::oidnGetDeviceError(std::ptr::null_mut(), &mut message);
        if message.is_null() {
            "no reason given".to_string()
        } else {
            CStr::from_ptr(message).to_string_lossy().into_owned()
        }
    }
}

/// An `RT` filter, released on drop.
struct Filter<'d> {
    handle: sys::OIDNFilter,
    _device: &'d Device,
}

impl<'d> Filter<'d> {
    fn new(device: &'d Device) -> Result<Filter<'d>, String> {
        // SAFETY: the device handle is live (borrowed for 'd); the type name
        // is a NUL-terminated literal; a null result is checked.
        let handle = unsafe { sys::oidnNewFilter(device.0.raw(), c"RT".as_ptr()) };
        device.error("creating its filter")?;
        if handle.is_null() {
            return Err("Open Image Denoise failed creating its filter".to_string());
        }
        Ok(Filter { handle, _device: device })
    }

    /// Sets `images` (each `FLOAT3`, `size` pixels), then the beauty's
    /// parameters when `beauty` (HDR, clean feature buffers),
    /// commits and runs the filter synchronously.
    fn run(
        &self,
        device: &Device,
        size: (usize, usize),
        images: &[(&CStr, &oidn::Buffer)],
        beauty: bool,
    ) -> Result<(), String> {
        // SAFETY: see the module's documentation: live handles, literal names,
        // buffers of exactly width × height × 3 floats, borrowed until the
        // synchronous execution has returned.
        unsafe {
            for (name, buffer) in images {
                sys::oidnSetFilterImage(
                    self.handle,
                    name.as_ptr(),
                    buffer.raw(),
                    sys::OIDNFormat_OIDN_FORMAT_FLOAT3,
                    size.0,
                    size.1,
                    0,
                    0,
                    0,
                );
            }
            if beauty {
                sys::oidnSetFilterBool(self.handle, c"hdr".as_ptr(), true);
                let clean = images.iter().any(|(name, _)| *name == c"albedo");
                sys::oidnSetFilterBool(self.handle, c"cleanAux".as_ptr(), clean);
            }
            sys::oidnCommitFilter(self.handle);
        }
        device.error("setting up its filter")?;
        // SAFETY: as above; oidnExecuteFilter returns when the output is written.
        unsafe { sys::oidnExecuteFilter(self.handle) };
        device.error("filtering")
    }
}

impl Drop for Filter<'_> {
    fn drop(&mut self) {
        // SAFETY: the handle came from oidnNewFilter and is released once.
        unsafe { sys::oidnReleaseFilter(self.handle) };
    }
}
