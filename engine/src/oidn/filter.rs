//! [`Oidn`]: OIDN's `RT` filter over host images. The inputs go through OIDN's copies into device buffers (the
//! network and prefilters read them many times); the output is a host-storage buffer (pinned host memory a GPU
//! writes once, directly) read in place, where the device offers one, else a device buffer read back. Filters
//! and buffers are made once per image size and options and reused, as OIDN recommends: committing a filter is
//! its expensive step.
//!
//! Where OIDN's GPU device and wgpu's Vulkan device are the same GPU and both can share memory, the images
//! can instead live in Vulkan memory OIDN imports ([`Oidn::shared_images`]): a wgpu pass writes the inputs and
//! the output is read where OIDN wrote it, with no copy through the host (`super::shared`).

use super::device::{self, DeviceKind, DeviceRequest};
use super::library::{self, Library};
use super::{DenoiseOptions, Images, OidnError};
use crate::gpu::GpuContext;
use crate::render::passes::denoiser_planes::{MAX_RADIANCE, plane_bytes};
use std::ffi::CStr;
use std::time::Instant;

/// Milliseconds spent in each step of one [`Oidn::denoise`].
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// Creating and committing filters and buffers (only when the size or options changed).
    pub setup_ms: f64,
    /// Sanitising the images and copying them into OIDN's buffers (a host-to-device copy on a GPU); with
    /// shared GPU memory, the wgpu pass that writes them there.
    pub upload_ms: f64,
    /// Denoising the albedo and normal images (with [`super::AuxMode::Prefilter`]).
    pub prefilter_ms: f64,
    /// The main filter.
    pub filter_ms: f64,
    /// The output from OIDN's buffer into a host image.
    pub download_ms: f64,
}

impl Timings {
    pub fn total_ms(&self) -> f64 {
        self.setup_ms + self.upload_ms + self.prefilter_ms + self.filter_ms + self.download_ms
    }

    /// The denoise without the set-up and without bringing the output to the host: with shared GPU memory,
    /// what a denoised image costs where it stays on the GPU (the viewer's display).
    pub fn on_device_ms(&self) -> f64 {
        self.upload_ms + self.prefilter_ms + self.filter_ms
    }
}

/// Prefiltered albedo and normal images.
pub type AuxImages = (Vec<[f32; 3]>, Vec<[f32; 3]>);

/// A denoised image and what it cost.
#[derive(Clone, Debug)]
pub struct Denoised {
    pub color: Vec<[f32; 3]>,
    pub timings: Timings,
    /// Output pixels that came back non-finite and were replaced by their (sanitised) input.
    pub repaired: usize,
}

/// What a set of filters was made for.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FilterKey {
    width: u32,
    height: u32,
    options: DenoiseOptions,
    albedo: bool,
    normal: bool,
    /// The images live in GPU memory shared with wgpu.
    shared: bool,
}

/// The four FLOAT3 images (tightly packed, row-major from the top-left) as wgpu buffers whose memory OIDN's
/// GPU device imported: a wgpu pass writes `color`, `albedo` and `normal`; OIDN writes `output`.
#[derive(Clone, Debug)]
pub struct SharedImages {
    pub color: wgpu::Buffer,
    pub albedo: wgpu::Buffer,
    pub normal: wgpu::Buffer,
    pub output: wgpu::Buffer,
}

/// Filters and buffers for one image size and set of options.
struct Filters {
    key: FilterKey,
    beauty: library::Filter,
    /// In-place denoisers of the albedo and normal buffers (with [`super::AuxMode::Prefilter`]).
    prefilters: Vec<library::Filter>,
    color: library::Buffer,
    albedo: Option<library::Buffer>,
    normal: Option<library::Buffer>,
    output: library::Buffer,
    /// `output` is in host storage and its data pointer valid: read in place.
    output_in_host_memory: bool,
    /// The wgpu buffers whose memory the four buffers above imported; dropped after OIDN's imports are
    /// released.
    shared: Option<SharedImages>,
}

/// An OIDN device and the filters made on it. Use it from one thread at a time (it is `Send`).
pub struct Oidn {
    lib: &'static Library,
    device: device::Device,
    filters: Option<Filters>,
    /// Notes from opening the device (a GPU that failed and the CPU used instead).
    pub notes: Vec<String>,
}

// SAFETY: OIDN's API is thread-safe; `Oidn` owns its handles and `&mut self` serialises their use.
unsafe impl Send for Oidn {}

impl Oidn {
    /// Loads the library ([`Library::shared`]) and opens the requested device.
    pub fn new(request: &DeviceRequest) -> Result<Self, OidnError> {
        Self::with_library(Library::shared()?, request)
    }

    pub fn with_library(lib: &'static Library, request: &DeviceRequest) -> Result<Self, OidnError> {
        let (device, notes) = device::open(lib, request)?;
        Ok(Self {
            lib,
            device,
            filters: None,
            notes,
        })
    }

    pub fn device_kind(&self) -> DeviceKind {
        self.device.kind
    }

    /// E.g. "CUDA NVIDIA H200" or "CPU Intel(R) Xeon(R) ...".
    pub fn device_description(&self) -> String {
        format!("{} {}", self.device.kind.name(), self.device.name)
    }

    /// The loaded library file.
    pub fn library_path(&self) -> &std::path::Path {
        &self.lib.path
    }

    /// Denoises `images.color`, guided by the albedo and normal images when given, shows `images.kept` pixels
    /// as their (sanitised) input colour, and adds `images.unscattered` (not denoised) to the result.
    pub fn denoise(
        &mut self,
        images: &Images,
        options: &DenoiseOptions,
    ) -> Result<Denoised, OidnError> {
        let (color, mut timings) = self.upload_and_prefilter(images, options)?;
        timings.filter_ms = self.run_main_filter()?;
        let output = self.filters.as_ref().expect("made by the upload").output;
        let start = Instant::now();
        let mut out = self.read(output, color.len())?;
        timings.download_ms = ms_since(start);
        let repaired = repair(&mut out, &color, images.kept);
        if let Some(unscattered) = images.unscattered {
            use rayon::prelude::*;
            out.par_iter_mut().zip(unscattered).for_each(|(o, u)| {
                *o = [0, 1, 2].map(|c| o[c] + sanitize(u[c], 0.0, MAX_RADIANCE))
            });
        }
        Ok(Denoised {
            color: out,
            timings,
            repaired,
        })
    }

    /// Whether this device can denoise images in `ctx`'s GPU memory ([`Self::shared_images`]): OIDN's device
    /// is a GPU that imports opaque file descriptors (OIDN's `externalMemoryTypes`) and wgpu's device exports
    /// them. The device was opened to match the adapter by its PCI address, so both are the same GPU.
    pub fn shares_memory_with(&self, ctx: &GpuContext) -> bool {
        if self.device.kind == DeviceKind::Cpu || !crate::gpu::external_memory::supported(ctx) {
            return false;
        }
        // SAFETY: a committed device; an integer parameter OIDN documents.
        let types = unsafe {
            (self.lib.get_device_int)(self.device.raw, library::name(c"externalMemoryTypes"))
        };
        self.lib.take_error(self.device.raw);
        types & library::EXTERNAL_MEMORY_OPAQUE_FD != 0
    }

    /// The filters for a `width` x `height` denoise with `options` over images in GPU memory shared with
    /// `ctx`'s device (made when the size or options change), and the milliseconds making them took. Write
    /// the inputs into the returned buffers, then [`Self::execute`], then read `output`.
    pub fn shared_images(
        &mut self,
        ctx: &GpuContext,
        width: u32,
        height: u32,
        options: &DenoiseOptions,
    ) -> Result<(SharedImages, f64), OidnError> {
        if width == 0 || height == 0 {
            return Err(OidnError::Input(format!("empty image ({width}x{height})")));
        }
        let start = Instant::now();
        let key = FilterKey {
            width,
            height,
            options: *options,
            albedo: true,
            normal: true,
            shared: true,
        };
        self.filters_for(key, Some(ctx))?;
        let images = self.filters.as_ref().and_then(|f| f.shared.clone());
        Ok((images.expect("made shared above"), ms_since(start)))
    }

    /// Runs the prefilters (with [`super::AuxMode::Prefilter`]) and the main filter over the images already in
    /// OIDN's buffers; returns their milliseconds.
    pub fn execute(&mut self) -> Result<(f64, f64), OidnError> {
        let prefilter_ms = self.run_prefilters()?;
        Ok((prefilter_ms, self.run_main_filter()?))
    }

    fn run_prefilters(&self) -> Result<f64, OidnError> {
        let filters = self
            .filters
            .as_ref()
            .expect("filters made before running them");
        self.run(&filters.prefilters, "prefiltering the albedo and normal")
    }

    fn run_main_filter(&self) -> Result<f64, OidnError> {
        let filters = self
            .filters
            .as_ref()
            .expect("filters made before running them");
        self.run(&[filters.beauty], "denoising")
    }

    /// Executes `filters` in order (each blocks until done); their milliseconds, or the error naming `what`.
    fn run(&self, filters: &[library::Filter], what: &str) -> Result<f64, OidnError> {
        let start = Instant::now();
        for &f in filters {
            // SAFETY: a committed filter over live buffers.
            unsafe { (self.lib.execute_filter)(f) };
        }
        self.check(what)?;
        Ok(ms_since(start))
    }

    /// The albedo and normal images after OIDN's prefilters (what [`Self::denoise`] guides the main filter
    /// with in [`super::AuxMode::Prefilter`]), for inspection and tests.
    pub fn prefiltered_aovs(
        &mut self,
        images: &Images,
        quality: super::Quality,
    ) -> Result<AuxImages, OidnError> {
        let (Some(_), Some(_)) = (images.albedo, images.normal) else {
            return Err(OidnError::Input(
                "prefiltering needs both the albedo and the normal image".into(),
            ));
        };
        let options = DenoiseOptions::at(quality);
        let (color, _) = self.upload_and_prefilter(images, &options)?;
        let filters = self.filters.as_ref().expect("made by the upload");
        let (albedo, normal) = (
            filters.albedo.expect("an albedo image"),
            filters.normal.expect("a normal image"),
        );
        Ok((
            self.read(albedo, color.len())?,
            self.read(normal, color.len())?,
        ))
    }

    /// Copies `pixels` FLOAT3 pixels of an OIDN buffer to the host.
    fn read(&self, buffer: library::Buffer, pixels: usize) -> Result<Vec<[f32; 3]>, OidnError> {
        if self
            .filters
            .as_ref()
            .is_some_and(|f| f.output_in_host_memory && f.output == buffer)
        {
            use rayon::prelude::*;
            // SAFETY: the host-storage output of `pixels` FLOAT3 pixels; the filter that writes it has returned
            // (oidnExecuteFilter is synchronous) and nothing else touches it.
            let source = unsafe { host_pixels(self.lib, buffer, pixels) };
            return Ok(source.par_iter().copied().collect());
        }
        let mut out = vec![[0.0f32; 3]; pixels];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut out);
        // SAFETY: the buffer holds exactly `bytes.len()` bytes; the call blocks until copied.
        unsafe { (self.lib.read_buffer)(buffer, 0, bytes.len(), bytes.as_mut_ptr().cast()) };
        self.check("reading a result")?;
        Ok(out)
    }

    /// Makes the filters for this size and options if needed, uploads the (sanitised) images and runs the
    /// prefilters; returns the sanitised colour and the timings so far.
    fn upload_and_prefilter(
        &mut self,
        images: &Images,
        options: &DenoiseOptions,
    ) -> Result<(Vec<[f32; 3]>, Timings), OidnError> {
        images.validate()?;
        let mut timings = Timings::default();
        let start = Instant::now();
        let key = FilterKey {
            width: images.width,
            height: images.height,
            options: *options,
            albedo: images.albedo.is_some(),
            normal: images.normal.is_some(),
            shared: false,
        };
        self.filters_for(key, None)?;
        timings.setup_ms = ms_since(start);

        let lib = self.lib;
        let filters = self.filters.as_ref().expect("made above");
        let start = Instant::now();
        let color = sanitized(images.color, 0.0, MAX_RADIANCE);
        let albedo = images.albedo.map(|a| sanitized(a, 0.0, 1.0));
        let normal = images.normal.map(|n| sanitized(n, -1.0, 1.0));
        for (buffer, data) in [
            (Some(filters.color), Some(&color)),
            (filters.albedo, albedo.as_ref()),
            (filters.normal, normal.as_ref()),
        ] {
            if let (Some(buffer), Some(data)) = (buffer, data) {
                let bytes: &[u8] = bytemuck::cast_slice(data);
                // SAFETY: the buffer was made with exactly width x height x 12 bytes, as `data` holds.
                unsafe { (lib.write_buffer)(buffer, 0, bytes.len(), bytes.as_ptr().cast()) };
            }
        }
        self.check("uploading the images")?;
        timings.upload_ms = ms_since(start);
        timings.prefilter_ms = self.run_prefilters()?;
        Ok((color, timings))
    }

    /// Four buffers of `bytes` whose memory is Vulkan memory of `ctx`'s device (colour, albedo, normal,
    /// output), imported by OIDN's device, and the wgpu buffers over the same memory.
    #[cfg(unix)]
    fn import_shared(
        &self,
        ctx: &GpuContext,
        bytes: usize,
    ) -> Result<([library::Buffer; 4], SharedImages), OidnError> {
        use std::os::fd::{FromRawFd, IntoRawFd};
        let (lib, dev) = (self.lib, self.device.raw);
        let mut imported: Vec<library::Buffer> = Vec::new();
        let mut exported = Vec::new();
        let fail = |imported: &[library::Buffer], message: String| {
            for &b in imported {
                // SAFETY: imported below and not used by any filter yet.
                unsafe { (lib.release_buffer)(b) };
            }
            OidnError::Device {
                device: self.device_description(),
                message: format!("sharing GPU memory with wgpu: {message}"),
            }
        };
        for label in ["oidn colour", "oidn albedo", "oidn normal", "oidn output"] {
            let e = crate::gpu::external_memory::exported_buffer(ctx, label, bytes as u64)
                .map_err(|m| fail(&imported, m))?;
            let fd = e.fd.into_raw_fd();
            // SAFETY: a descriptor of `allocation_size` bytes of exported Vulkan memory; on success OIDN's
            // device (CUDA) owns the descriptor.
            let buffer = unsafe {
                (lib.new_shared_buffer_from_fd)(
                    dev,
                    library::EXTERNAL_MEMORY_OPAQUE_FD,
                    fd,
                    e.allocation_size as usize,
                )
            };
            if let Some(error) = lib.take_error(dev).or(buffer.is_null().then(String::new)) {
                if buffer.is_null() {
                    // SAFETY: the import failed, so the descriptor is still ours.
                    drop(unsafe { std::os::fd::OwnedFd::from_raw_fd(fd) });
                } else {
                    imported.push(buffer);
                }
                return Err(fail(&imported, format!("importing {label}: {error}")));
            }
            imported.push(buffer);
            exported.push(e.buffer);
        }
        let [color, albedo, normal, output] =
            <[wgpu::Buffer; 4]>::try_from(exported).expect("four made above");
        let buffers = <[library::Buffer; 4]>::try_from(imported).expect("four made above");
        Ok((
            buffers,
            SharedImages {
                color,
                albedo,
                normal,
                output,
            },
        ))
    }

    #[cfg(not(unix))]
    fn import_shared(
        &self,
        _ctx: &GpuContext,
        _bytes: usize,
    ) -> Result<([library::Buffer; 4], SharedImages), OidnError> {
        Err(OidnError::Device {
            device: self.device_description(),
            message: "sharing GPU memory needs POSIX file descriptors".into(),
        })
    }

    /// Makes the filters for `key` unless the current ones were made for it (committing filters is OIDN's
    /// expensive step; they are kept across denoises).
    fn filters_for(&mut self, key: FilterKey, ctx: Option<&GpuContext>) -> Result<(), OidnError> {
        if self.filters.as_ref().is_none_or(|f| f.key != key) {
            self.release_filters();
            self.filters = Some(self.make_filters(key, ctx)?);
        }
        Ok(())
    }

    /// The filters for `key`, over new OIDN buffers or, for shared images, over Vulkan memory of `ctx`'s
    /// device.
    fn make_filters(&self, key: FilterKey, ctx: Option<&GpuContext>) -> Result<Filters, OidnError> {
        let FilterKey {
            width,
            height,
            options,
            albedo: has_albedo,
            normal: has_normal,
            shared,
        } = key;
        let lib = self.lib;
        let dev = self.device.raw;
        let bytes = plane_bytes(width as u64 * height as u64) as usize;
        // SAFETY: `dev` is a committed device; every handle made here is released in `release_filters`.
        let new_buffer = || unsafe { (lib.new_buffer)(dev, bytes) };
        let mut filters = match (shared, ctx) {
            (true, Some(ctx)) => {
                let ([color, albedo, normal, output], images) = self.import_shared(ctx, bytes)?;
                Filters {
                    key,
                    beauty: std::ptr::null_mut(),
                    prefilters: Vec::new(),
                    color,
                    albedo: Some(albedo),
                    normal: Some(normal),
                    output,
                    output_in_host_memory: false,
                    shared: Some(images),
                }
            }
            _ => {
                // SAFETY: as above; a null buffer or data pointer means no host storage here (the error is
                // cleared).
                let mut output =
                    unsafe { (lib.new_buffer_with_storage)(dev, bytes, library::STORAGE_HOST) };
                let output_in_host_memory = lib.take_error(dev).is_none()
                    && !output.is_null()
                    && !unsafe { (lib.get_buffer_data)(output) }.is_null();
                if !output_in_host_memory {
                    if !output.is_null() {
                        // SAFETY: made above, never used.
                        unsafe { (lib.release_buffer)(output) };
                    }
                    output = new_buffer();
                }
                Filters {
                    key,
                    beauty: std::ptr::null_mut(),
                    prefilters: Vec::new(),
                    color: new_buffer(),
                    albedo: has_albedo.then(new_buffer),
                    normal: has_normal.then(new_buffer),
                    output,
                    output_in_host_memory,
                    shared: None,
                }
            }
        };
        let image = |filter, name: &'static CStr, buffer| {
            // SAFETY: a live filter and a buffer of width x height FLOAT3 pixels, tightly packed.
            unsafe {
                (lib.set_filter_image)(
                    filter,
                    library::name(name),
                    buffer,
                    library::FORMAT_FLOAT3,
                    width as usize,
                    height as usize,
                    0,
                    0,
                    0,
                )
            }
        };
        // SAFETY: a committed device; "RT" is a built-in filter type.
        let new_filter = || unsafe { (lib.new_filter)(dev, library::name(c"RT")) };
        let set_quality = |f| unsafe {
            (lib.set_filter_int)(f, library::name(c"quality"), options.quality.raw())
        };
        let prefilter = options.aux == super::AuxMode::Prefilter;
        // Each prefilter denoises its AOV in place (OIDN's documented prefiltering setup).
        for (aov, name) in [(filters.albedo, c"albedo"), (filters.normal, c"normal")] {
            if let (true, Some(buffer)) = (prefilter, aov) {
                let f = new_filter();
                image(f, name, buffer);
                image(f, c"output", buffer);
                set_quality(f);
                // SAFETY: a live filter with its images set.
                unsafe { (lib.commit_filter)(f) };
                filters.prefilters.push(f);
            }
        }
        let beauty = new_filter();
        image(beauty, c"color", filters.color);
        if let Some(albedo) = filters.albedo {
            image(beauty, c"albedo", albedo);
        }
        if let Some(normal) = filters.normal {
            image(beauty, c"normal", normal);
        }
        image(beauty, c"output", filters.output);
        // SAFETY: a live filter; parameter names from OIDN's RT filter documentation.
        unsafe {
            (lib.set_filter_bool)(beauty, library::name(c"hdr"), options.hdr);
            (lib.set_filter_bool)(
                beauty,
                library::name(c"cleanAux"),
                options.aux != super::AuxMode::Noisy && (has_albedo || has_normal),
            );
            (lib.set_filter_float)(beauty, library::name(c"inputScale"), f32::NAN);
        }
        set_quality(beauty);
        // SAFETY: as above.
        unsafe { (lib.commit_filter)(beauty) };
        filters.beauty = beauty;
        let made = filters;
        if let Err(e) = self.check(&format!("setting up a {width}x{height} filter")) {
            release(lib, &made);
            return Err(e);
        }
        Ok(made)
    }

    /// The device's pending error, as an [`OidnError`] naming `what` was being done.
    fn check(&self, what: &str) -> Result<(), OidnError> {
        match self.lib.take_error(self.device.raw) {
            None => Ok(()),
            Some(message) => Err(OidnError::Device {
                device: self.device_description(),
                message: format!("{what}: {message}"),
            }),
        }
    }

    fn release_filters(&mut self) {
        if let Some(f) = self.filters.take() {
            release(self.lib, &f);
        }
    }
}

impl Drop for Oidn {
    fn drop(&mut self) {
        self.release_filters();
        // SAFETY: every filter and buffer on the device is released; the device is not used again.
        unsafe {
            (self.lib.sync_device)(self.device.raw);
            (self.lib.release_device)(self.device.raw);
        }
    }
}

fn release(lib: &Library, f: &Filters) {
    // SAFETY: handles made by `make_filters` and not used after this (null ones are skipped).
    unsafe {
        for &p in f.prefilters.iter().chain([&f.beauty]) {
            if !p.is_null() {
                (lib.release_filter)(p);
            }
        }
        for b in [Some(f.color), f.albedo, f.normal, Some(f.output)]
            .into_iter()
            .flatten()
        {
            if !b.is_null() {
                (lib.release_buffer)(b);
            }
        }
    }
}

/// A host-storage buffer's pixels.
///
/// # Safety
/// `buffer` is a live host-storage buffer of at least `pixels` FLOAT3 pixels that nothing writes while
/// the slice lives.
unsafe fn host_pixels<'a>(lib: &Library, buffer: library::Buffer, pixels: usize) -> &'a [[f32; 3]] {
    // SAFETY: per the contract; OIDN's host allocations are aligned far beyond f32's 4 bytes.
    unsafe { std::slice::from_raw_parts((lib.get_buffer_data)(buffer).cast(), pixels) }
}

/// Replaces each non-finite output pixel, and each pixel `kept` marks, by its input and clamps negative
/// channels to 0 (unpack.wgsl's rule on the GPU path); returns how many non-finite pixels there were.
fn repair(out: &mut [[f32; 3]], input: &[[f32; 3]], kept: Option<&[bool]>) -> usize {
    use rayon::prelude::*;
    out.par_iter_mut()
        .zip(input)
        .enumerate()
        .map(|(p, (o, i))| {
            let finite = o.iter().all(|v| v.is_finite());
            let keep = kept.is_some_and(|k| k[p]);
            *o = if finite && !keep {
                o.map(|v| v.max(0.0))
            } else {
                *i
            };
            usize::from(!finite)
        })
        .sum()
}

/// `v` clamped to [lo, hi]; NaN becomes 0.
fn sanitize(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_nan() { 0.0 } else { v.clamp(lo, hi) }
}

/// Each channel clamped to [lo, hi]; NaN becomes 0.
fn sanitized(image: &[[f32; 3]], lo: f32, hi: f32) -> Vec<[f32; 3]> {
    use rayon::prelude::*;
    image
        .par_iter()
        .map(|p| p.map(|v| sanitize(v, lo, hi)))
        .collect()
}

pub(crate) fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sanitizing_clamps_and_drops_nan() {
        let img = [[f32::NAN, -1.0, f32::INFINITY], [0.5, 2.0, -0.0]];
        assert_eq!(
            sanitized(&img, 0.0, 1.0),
            vec![[0.0, 0.0, 1.0], [0.5, 1.0, 0.0]]
        );
    }
}
