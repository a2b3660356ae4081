//! The film: every pixel's samples summed exactly, so each render knows its own noise and any
//! split of a render's samples (dispatches, passes, checkpoints, shards) adds up to the same bits.
//!
//! A sample is added exactly to a wide integer (`crate::shared::exact_sum`): integer addition is
//! associative, so the mean of samples 0..N is bit-identical however they were grouped, and no
//! finite sample is rounded away or dropped, whatever the scene's radiance scale. The
//! spread of the samples (Welford's M2, for the noise of independent samples) is kept in floating
//! point and merged with Chan's update: it agrees to about 1e-12 across splits, not bit for bit.
//!
//! With independent samples the variance of a pixel's mean is its sample variance over n. With
//! a stratified sampler it is far lower, and the sample variance says nothing about it; there
//! the estimate comes from two independent randomisations, the replicas the sampler deals even
//! and odd sample indices into (`crate::shared::sampler::REPLICAS`): the film keeps the odd samples'
//! sum beside the overall one.

pub mod file;
pub mod float_image;
pub mod levels;
pub mod output;

use crate::shared::exact_sum::ExactSum;
use glam::{DVec3, Vec3};

/// The f32 bits of +infinity: a channel whose bits (sign cleared) reach it is not finite.
/// Shared with `valid_sample` in shaders/film.wgsl.
pub const NOT_FINITE_BITS: u32 = 0x7f80_0000;

/// Whether a sample can enter the film: every channel finite and non-negative (or -0). Others
/// (NaN, infinite, negative) are counted as invalid and added as zero; any valid sample is
/// summed exactly, however dim or bright.
#[inline]
pub fn is_valid_sample(sample: Vec3) -> bool {
    sample
        .to_array()
        .iter()
        .all(|c| c.to_bits() < NOT_FINITE_BITS || c.to_bits() == 0x8000_0000)
}

fn sums_rgb(sum: &[ExactSum; 3]) -> DVec3 {
    DVec3::new(sum[0].to_f64(), sum[1].to_f64(), sum[2].to_f64())
}

/// One pixel's samples: their count and exact sum, Welford's sum of squared deviations, and the
/// count and exact sum of its odd-index samples (replica 1).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelStats {
    pub n: u64,
    /// Per channel, the samples' exact sum.
    pub sum: [ExactSum; 3],
    pub m2: DVec3,
    pub odd_n: u64,
    pub odd_sum: [ExactSum; 3],
}

impl PixelStats {
    /// Adds a sample whose index is unknown (replica statistics stay empty). The sample must be
    /// valid ([`is_valid_sample`]). A renderer adding many gathers them in a [`PixelRun`].
    pub fn add(&mut self, sample: Vec3) {
        let mut run = PixelRun::default();
        run.add(sample);
        self.merge(run.stats());
    }

    /// Adds sample number `index` of the pixel.
    pub fn add_indexed(&mut self, sample: Vec3, index: u32) {
        let mut run = PixelRun::default();
        run.add_indexed(sample, index);
        self.merge(run.stats());
    }

    /// The mean of the samples (zero without any).
    pub fn mean(&self) -> DVec3 {
        if self.n == 0 {
            DVec3::ZERO
        } else {
            sums_rgb(&self.sum) / self.n as f64
        }
    }

    /// The mean of the odd-index samples (zero without any).
    pub fn odd_mean(&self) -> DVec3 {
        if self.odd_n == 0 {
            DVec3::ZERO
        } else {
            sums_rgb(&self.odd_sum) / self.odd_n as f64
        }
    }

    /// The mean of the even-index samples (replica 0), if there are any.
    pub fn even_mean(&self) -> Option<DVec3> {
        let even_n = self.n.checked_sub(self.odd_n).filter(|&n| n > 0)?;
        let even: [ExactSum; 3] =
            std::array::from_fn(|c| self.sum[c].minus(&self.odd_sum[c]).unwrap_or_default());
        Some(sums_rgb(&even) / even_n as f64)
    }

    /// Variance of the pixel's mean from the spread of its two replicas' means, independent
    /// randomised estimates: (m0 - m1)^2 / 4 for equal halves, n0 n1 (m0 - m1)^2 / n^2 in
    /// general (one degree of freedom per pixel: noisy alone, unbiased in sums over pixels).
    /// `None` while a replica has no samples.
    pub fn replica_variance_of_mean(&self) -> Option<DVec3> {
        let even = self.even_mean()?;
        (self.odd_n > 0).then(|| {
            let d = even - self.odd_mean();
            let (n0, n1, n) = (
                (self.n - self.odd_n) as f64,
                self.odd_n as f64,
                self.n as f64,
            );
            d * d * (n0 * n1 / (n * n))
        })
    }

    /// Combines two disjoint sets of samples: the sums exactly, M2 by Chan et al.'s update.
    pub fn merge(&mut self, other: &PixelStats) {
        if other.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *other;
            return;
        }
        let n = self.n + other.n;
        let delta = other.mean() - self.mean();
        self.m2 += other.m2 + delta * delta * (self.n as f64 * other.n as f64 / n as f64);
        self.n = n;
        for c in 0..3 {
            self.sum[c] = self.sum[c].plus(&other.sum[c]);
            self.odd_sum[c] = self.odd_sum[c].plus(&other.odd_sum[c]);
        }
        self.odd_n += other.odd_n;
    }

    /// Unbiased sample variance of one sample (of independent samples).
    pub fn variance(&self) -> DVec3 {
        if self.n < 2 {
            DVec3::ZERO
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// Variance of the pixel's mean, the square of its standard error, for independent
    /// samples (see [`Film::variance_of_mean`] for any sampler).
    pub fn variance_of_mean(&self) -> DVec3 {
        if self.n == 0 {
            DVec3::ZERO
        } else {
            self.variance() / self.n as f64
        }
    }
}

/// A pixel's samples as one render adds them, one at a time: the sums exact as in
/// [`PixelStats`], and Welford's update on a running f64 mean rather than on the mean of the
/// exact sums, which converting twice per sample made a tenth of the render of a scene with short
/// paths (docs/benchmarks.md).
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelRun {
    stats: PixelStats,
    mean: DVec3,
}

impl PixelRun {
    /// Adds a sample whose index is unknown (replica statistics stay empty). The sample must be
    /// valid ([`is_valid_sample`]).
    #[inline]
    pub fn add(&mut self, sample: Vec3) {
        let x = sample.as_dvec3();
        let stats = &mut self.stats;
        stats.n += 1;
        for (s, c) in stats.sum.iter_mut().zip(sample.to_array()) {
            s.add_f32(c);
        }
        let delta = x - self.mean;
        self.mean += delta / stats.n as f64;
        stats.m2 += delta * (x - self.mean);
    }

    /// Adds sample number `index` of the pixel.
    #[inline]
    pub fn add_indexed(&mut self, sample: Vec3, index: u32) {
        self.add(sample);
        if index % 2 == 1 {
            let stats = &mut self.stats;
            stats.odd_n += 1;
            for (s, c) in stats.odd_sum.iter_mut().zip(sample.to_array()) {
                s.add_f32(c);
            }
        }
    }

    /// The statistics of the samples added so far.
    pub fn stats(&self) -> &PixelStats {
        &self.stats
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Row-major, row 0 at the top.
    pub pixels: Vec<PixelStats>,
    /// Samples that came out invalid (NaN, infinite or negative) and were counted as zero.
    pub invalid_samples: u64,
    /// Whether the samples were stratified (not independent): noise is then measured by the
    /// spread of the replicas.
    pub stratified: bool,
}

/// Longest image side.
pub const MAX_IMAGE_SIDE: u32 = 1 << 15;
/// Most pixels one image may have (the film keeps 280 bytes of statistics per pixel).
pub const MAX_PIXELS: u64 = 1 << 26;
/// Host memory a render needs per pixel: the film, a pass's film merged into it, GPU readback
/// (the kernel's accumulator), its mean image (12 bytes) and the encoded output (up to 12).
pub const RENDER_BYTES_PER_PIXEL: u64 = 2 * std::mem::size_of::<PixelStats>() as u64 + 276 + 24;

/// The one check of an image size, wherever it comes from (`--size`, a scene file, a test).
pub fn check_image_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(format!(
            "image sides must be in 1..={MAX_IMAGE_SIDE}, got {width}x{height}"
        ));
    }
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(format!(
            "a {width}x{height} image has more than {MAX_PIXELS} pixels"
        ));
    }
    Ok(())
}

/// Whether this machine has the memory a `width` x `height` render needs, checked before
/// anything is allocated (an allocation that fails aborts the process).
pub fn check_memory(width: u32, height: u32) -> Result<(), String> {
    let needed = width as u64 * height as u64 * RENDER_BYTES_PER_PIXEL;
    check_available(needed, || format!("a {width}x{height} render"))
}

/// Refuses `needed` bytes where this machine has fewer available: "`what` needs about X GB of
/// memory, and Y GB is available".
pub fn check_available(needed: u64, what: impl FnOnce() -> String) -> Result<(), String> {
    if let Some(available) = available_memory()
        && needed > available
    {
        return Err(format!(
            "{} needs about {:.1} GB of memory, and {:.1} GB is available",
            what(),
            needed as f64 / 1e9,
            available as f64 / 1e9
        ));
    }
    Ok(())
}

/// MemAvailable from /proc/meminfo, where there is one.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![PixelStats::default(); width as usize * height as usize],
            invalid_samples: 0,
            stratified: false,
        }
    }

    /// The render's own estimate of its RMSE: the root of the mean variance of its pixel means
    /// (from independent randomisations under a stratified sampler; see
    /// [`Film::variance_of_mean`]).
    pub fn estimated_rmse(&self) -> f64 {
        let sum: f64 = (self.pixels.iter())
            .map(|p| self.variance_of_mean(p).element_sum())
            .sum();
        (sum / (self.pixels.len() * 3).max(1) as f64).sqrt()
    }

    /// The variance of `pixel`'s mean: from its replicas when the samples were stratified
    /// (falling back to the sample variance, an overestimate, while a replica is empty), else
    /// from its samples.
    pub fn variance_of_mean(&self, pixel: &PixelStats) -> DVec3 {
        if self.stratified {
            pixel
                .replica_variance_of_mean()
                .unwrap_or_else(|| pixel.variance_of_mean())
        } else {
            pixel.variance_of_mean()
        }
    }

    pub fn pixel(&self, x: u32, y: u32) -> &PixelStats {
        &self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Linear radiance per pixel, row-major from the top.
    pub fn mean_rgb(&self) -> Vec<[f32; 3]> {
        self.pixels
            .iter()
            .map(|p| p.mean().as_vec3().to_array())
            .collect()
    }

    /// The mean linear radiance of the whole image, per channel.
    pub fn image_mean(&self) -> DVec3 {
        let sum: DVec3 = self.pixels.iter().map(|p| p.mean()).sum();
        sum / self.pixels.len().max(1) as f64
    }

    /// Standard error of [`Film::image_mean`], from the per-pixel variances.
    pub fn image_mean_std_error(&self) -> DVec3 {
        let sum: DVec3 = self.pixels.iter().map(|p| self.variance_of_mean(p)).sum();
        let n = self.pixels.len().max(1) as f64;
        (sum / (n * n)).map(f64::sqrt)
    }

    /// Adds another film's samples of the same pixels.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        self.stratified |= other.stratified;
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            a.merge(b);
        }
        self.invalid_samples += other.invalid_samples;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass_and_merges_add_up_to_the_same_sums() {
        let samples: Vec<Vec3> = (0..101)
            .map(|i| Vec3::new(i as f32 * 0.37, (i * i % 17) as f32, 1e4 + (i % 3) as f32))
            .collect();
        let mut all = PixelStats::default();
        samples
            .iter()
            .enumerate()
            .for_each(|(i, &s)| all.add_indexed(s, i as u32));
        let n = samples.len() as f64;
        let mean: DVec3 = samples.iter().map(|s| s.as_dvec3()).sum::<DVec3>() / n;
        let var: DVec3 = samples
            .iter()
            .map(|s| (s.as_dvec3() - mean) * (s.as_dvec3() - mean))
            .sum::<DVec3>()
            / (n - 1.0);
        assert!((all.mean() - mean).abs().max_element() < 1e-9);
        assert!((all.variance() - var).abs().max_element() < 1e-7);

        // Any split, merged in any order: the same sums, bit for bit.
        for cut in [1, 40, 100] {
            let (mut a, mut b) = (PixelStats::default(), PixelStats::default());
            for (i, &s) in samples.iter().enumerate() {
                let part = if i < cut { &mut a } else { &mut b };
                part.add_indexed(s, i as u32);
            }
            let mut ab = a;
            ab.merge(&b);
            b.merge(&a);
            for merged in [ab, b] {
                assert_eq!((merged.n, merged.sum), (all.n, all.sum));
                assert_eq!((merged.odd_n, merged.odd_sum), (all.odd_n, all.odd_sum));
                assert_eq!(merged.mean(), all.mean());
                assert!((merged.m2 - all.m2).abs().max_element() < 1e-6);
            }
        }
    }

    #[test]
    fn every_finite_non_negative_sample_is_valid_and_kept() {
        for good in [
            0.0,
            -0.0,
            f32::from_bits(1),
            1e-30,
            2f32.powi(32),
            1e30,
            f32::MAX,
        ] {
            assert!(is_valid_sample(Vec3::new(1.0, good, 1.0)), "{good}");
        }
        for bad in [-1e-30, -1.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
            assert!(!is_valid_sample(Vec3::new(1.0, bad, 1.0)), "{bad}");
        }
        // A sample of 1e30 among ordinary ones is kept, and so are the ordinary ones.
        let mut p = PixelStats::default();
        for (i, v) in [0.25f32, 1e30, 1e-20, 0.5].into_iter().enumerate() {
            p.add_indexed(Vec3::splat(v), i as u32);
        }
        let expected = (0.25 + 1e30f32 as f64 + 1e-20f32 as f64 + 0.5) / 4.0;
        assert!((p.mean().x / expected - 1.0).abs() < 1e-15);
        let odd = p.odd_mean().x;
        assert!((odd / ((1e30f32 as f64 + 0.5) / 2.0) - 1.0).abs() < 1e-15);
        assert!(p.variance().is_finite());
    }
}
