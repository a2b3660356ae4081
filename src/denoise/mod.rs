//! Denoising a finished image with Intel Open Image Denoise (OIDN 2, loaded at run time:
//! `library.rs`): its `RT` filter on the film's HDR mean, guided by the albedo and normal
//! feature buffers (the `albedo` and `normal` integrators, `cpu/aov.rs` and `shaders/aov.wgsl`).
//! An output transform: films and film files stay exact and undenoised.
//!
//! The feature buffers go to the filter as they are (OIDN's default, `cleanAux` off, which
//! expects some noise in them), not prefiltered: prefiltering measured worse and slower
//! (docs/benchmarks.md, issue 65).

pub mod library;

use crate::film::Film;
use crate::options::{Integrator, RenderOptions};
use library::{DEVICE_TYPE_CPU, Device, ERROR_NONE, FORMAT_FLOAT3, Filter, Oidn, OidnError};
use std::ffi::{CStr, c_char, c_void};

/// The feature buffers of an image, as OIDN reads them: albedo in [0, 1], normals in [-1, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureBuffers {
    pub albedo: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
}

impl FeatureBuffers {
    /// From the films of the albedo and normal integrators (the same size): the albedo's mean
    /// clamped to [0, 1] (one BSDF sample's weight can exceed 1, its mean cannot), the normal's
    /// mapped back from (n + 1) / 2.
    pub fn from_films(albedo: &Film, normal: &Film) -> FeatureBuffers {
        FeatureBuffers {
            albedo: (albedo.mean_rgb().into_iter())
                .map(|c| c.map(|v| v.clamp(0.0, 1.0)))
                .collect(),
            normal: normal
                .mean_rgb()
                .into_iter()
                .map(normal_from_film)
                .collect(),
        }
    }
}

/// The most samples per pixel the feature buffers take: beyond this their noise is far below
/// the image's, and their time is better spent on the image.
pub const FEATURE_SPP: u32 = 64;

/// The feature buffers of an image of `spp` samples rendered with `opts` (from
/// `opts.first_sample`): the first of the same samples, at most [`FEATURE_SPP`], so that their
/// camera rays are the image's, each film made by `render` (given the albedo, then the normal
/// integrator's options). Returns them and their samples per pixel.
pub fn render_feature_buffers(
    opts: &RenderOptions,
    spp: u32,
    mut render: impl FnMut(&RenderOptions) -> anyhow::Result<Film>,
) -> anyhow::Result<(FeatureBuffers, u32)> {
    let feature_spp = spp.clamp(1, FEATURE_SPP);
    let mut buffer = |integrator| {
        render(&RenderOptions {
            spp: feature_spp,
            integrator,
            ..*opts
        })
    };
    let albedo = buffer(Integrator::Albedo)?;
    let normal = buffer(Integrator::Normal)?;
    Ok((FeatureBuffers::from_films(&albedo, &normal), feature_spp))
}

/// A normal film's mean, (n + 1) / 2 averaged, as the mean normal.
pub fn normal_from_film(mean: [f32; 3]) -> [f32; 3] {
    mean.map(|v| (2.0 * v - 1.0).clamp(-1.0, 1.0))
}

/// OIDN's CPU device, ready to denoise images one after another.
pub struct Denoiser {
    oidn: Oidn,
    device: Device,
}

// SAFETY: OIDN's API is thread-safe (its documentation: calls on one device are serialised),
// and the device handle is only used through it.
unsafe impl Send for Denoiser {}
unsafe impl Sync for Denoiser {}

impl Denoiser {
    /// Opens OIDN and its CPU device with `threads` threads (`None`: all cores).
    pub fn new(threads: Option<usize>) -> Result<Denoiser, OidnError> {
        let oidn = Oidn::open()?;
        // SAFETY: OIDN's functions called as oidn.h declares them; the device is released in
        // Drop.
        let device = unsafe { (oidn.functions.new_device)(DEVICE_TYPE_CPU) };
        if device.is_null() {
            return Err(OidnError::Failed("no CPU device".into()));
        }
        let denoiser = Denoiser { oidn, device };
        let f = &denoiser.oidn.functions;
        if let Some(threads) = threads {
            let threads = i32::try_from(threads).unwrap_or(i32::MAX);
            unsafe { (f.set_device_int)(device, c"numThreads".as_ptr(), threads) };
        }
        unsafe { (f.commit_device)(device) };
        denoiser.check()?;
        Ok(denoiser)
    }

    /// The library's version, as "2.5.1", and where it was loaded from.
    pub fn describe(&self) -> String {
        let f = &self.oidn.functions;
        let version = unsafe { (f.get_device_int)(self.device, c"version".as_ptr()) };
        format!(
            "Open Image Denoise {}.{}.{} ({})",
            version / 10000,
            version / 100 % 100,
            version % 100,
            self.oidn.path.display()
        )
    }

    /// `color` (linear HDR radiance, `width` x `height`, row-major from the top) denoised,
    /// guided by `features` where given.
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[[f32; 3]],
        features: Option<&FeatureBuffers>,
    ) -> Result<Vec<[f32; 3]>, OidnError> {
        let pixels = width as usize * height as usize;
        let sizes_match = color.len() == pixels
            && features.is_none_or(|f| f.albedo.len() == pixels && f.normal.len() == pixels);
        if !sizes_match {
            return Err(OidnError::Failed(
                "the image and its feature buffers differ in size".into(),
            ));
        }
        let mut output = vec![[0.0f32; 3]; pixels];
        let mut color = color.to_vec();
        let (mut albedo, mut normal);
        let mut images = vec![(c"color", &mut color)];
        if let Some(features) = features {
            (albedo, normal) = (features.albedo.clone(), features.normal.clone());
            images.push((c"albedo", &mut albedo));
            images.push((c"normal", &mut normal));
        }
        images.push((c"output", &mut output));
        self.run(width, height, &mut images)?;
        Ok(output)
    }

    /// One `RT` filter over `images` (each `width` x `height` RGB floats, named as OIDN names
    /// its inputs and output).
    fn run(
        &self,
        width: u32,
        height: u32,
        images: &mut [(&CStr, &mut Vec<[f32; 3]>)],
    ) -> Result<(), OidnError> {
        let f = &self.oidn.functions;
        // SAFETY: the filter reads and writes the images' buffers, which outlive it (released
        // below before they can be dropped), each width x height x 3 floats.
        let filter: Filter = unsafe { (f.new_filter)(self.device, c"RT".as_ptr()) };
        if filter.is_null() {
            self.check()?;
            return Err(OidnError::Failed("no RT filter".into()));
        }
        unsafe {
            for (name, image) in images.iter_mut() {
                (f.set_shared_filter_image)(
                    filter,
                    name.as_ptr(),
                    image.as_mut_ptr() as *mut c_void,
                    FORMAT_FLOAT3,
                    width as usize,
                    height as usize,
                    0,
                    0,
                    0,
                );
            }
            (f.set_filter_bool)(filter, c"hdr".as_ptr(), true);
            (f.commit_filter)(filter);
            (f.execute_filter)(filter);
            (f.release_filter)(filter);
        }
        self.check()
    }

    /// The device's first error since the last check, if any.
    fn check(&self) -> Result<(), OidnError> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: OIDN sets `message` to a string it owns, valid until the next call on this
        // device, or leaves it null.
        let code = unsafe { (self.oidn.functions.get_device_error)(self.device, &mut message) };
        if code == ERROR_NONE {
            return Ok(());
        }
        let text = if message.is_null() {
            format!("error {code}")
        } else {
            unsafe { CStr::from_ptr(message) }
                .to_string_lossy()
                .into_owned()
        };
        Err(OidnError::Failed(text))
    }
}

impl Drop for Denoiser {
    fn drop(&mut self) {
        // SAFETY: the device was made by new_device and nothing uses it after this.
        unsafe { (self.oidn.functions.release_device)(self.device) };
    }
}
