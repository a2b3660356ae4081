//! The film: every pixel's running mean and variance in f64, so each render knows its own noise.
//!
//! With independent samples the variance of a pixel's mean is its sample variance over n. With
//! a stratified sampler it is far lower, and the sample variance says nothing about it; there
//! the estimate comes from two independent randomisations, the replicas the sampler deals even
//! and odd sample indices into (`crate::sampler::REPLICAS`): the film keeps the odd samples'
//! mean beside the overall one.

use glam::{DVec3, Vec3};

/// Welford's running mean and sum of squared deviations of one pixel's samples, and the mean of
/// its odd-index samples (replica 1).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelStats {
    pub n: u64,
    pub mean: DVec3,
    pub m2: DVec3,
    pub odd_n: u64,
    pub odd_mean: DVec3,
}

impl PixelStats {
    /// Adds a sample whose index is unknown (replica statistics stay empty).
    #[inline]
    pub fn add(&mut self, sample: Vec3) {
        let x = sample.as_dvec3();
        self.n += 1;
        let delta = x - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// Adds sample number `index` of the pixel.
    #[inline]
    pub fn add_indexed(&mut self, sample: Vec3, index: u32) {
        self.add(sample);
        if index % 2 == 1 {
            self.odd_n += 1;
            self.odd_mean += (sample.as_dvec3() - self.odd_mean) / self.odd_n as f64;
        }
    }

    /// The mean of the even-index samples (replica 0), if there are any.
    pub fn even_mean(&self) -> Option<DVec3> {
        let even_n = self.n.checked_sub(self.odd_n).filter(|&n| n > 0)?;
        Some((self.mean * self.n as f64 - self.odd_mean * self.odd_n as f64) / even_n as f64)
    }

    /// Variance of the pixel's mean from the spread of its two replicas' means, independent
    /// randomised estimates: (m0 - m1)^2 / 4 for equal halves, n0 n1 (m0 - m1)^2 / n^2 in
    /// general (one degree of freedom per pixel: noisy alone, unbiased in sums over pixels).
    /// `None` while a replica has no samples.
    pub fn replica_variance_of_mean(&self) -> Option<DVec3> {
        let even = self.even_mean()?;
        (self.odd_n > 0).then(|| {
            let d = even - self.odd_mean;
            let (n0, n1, n) = (
                (self.n - self.odd_n) as f64,
                self.odd_n as f64,
                self.n as f64,
            );
            d * d * (n0 * n1 / (n * n))
        })
    }

    /// Combines two disjoint sets of samples (Chan et al.'s parallel update).
    pub fn merge(&mut self, other: &PixelStats) {
        if other.n == 0 {
            return;
        }
        let n = self.n + other.n;
        let delta = other.mean - self.mean;
        let weight = other.n as f64 / n as f64;
        self.mean += delta * weight;
        self.m2 += other.m2 + delta * delta * (self.n as f64 * weight);
        self.n = n;
        let odd_n = self.odd_n + other.odd_n;
        if odd_n > 0 {
            self.odd_mean += (other.odd_mean - self.odd_mean) * (other.odd_n as f64 / odd_n as f64);
        }
        self.odd_n = odd_n;
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

#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Row-major, row 0 at the top.
    pub pixels: Vec<PixelStats>,
    /// Samples that came out NaN or infinite and were counted as zero.
    pub invalid_samples: u64,
    /// Whether the samples were stratified (not independent): noise is then measured by the
    /// spread of the replicas.
    pub stratified: bool,
}

/// Longest image side.
pub const MAX_IMAGE_SIDE: u32 = 1 << 15;
/// Most pixels one image may have (the film keeps 88 bytes of statistics per pixel).
pub const MAX_PIXELS: u64 = 1 << 26;
/// Host memory a render needs per pixel: the film (88 bytes), its mean image (12), the encoded
/// output (up to 12) and slack for GPU readback and the CPU's rows.
pub const RENDER_BYTES_PER_PIXEL: u64 = 128;

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
    if let Some(available) = available_memory()
        && needed > available
    {
        return Err(format!(
            "a {width}x{height} render needs about {:.1} GB of memory, and {:.1} GB is available",
            needed as f64 / 1e9,
            available as f64 / 1e9
        ));
    }
    Ok(())
}

/// MemAvailable from /proc/meminfo, where there is one.
fn available_memory() -> Option<u64> {
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
            .map(|p| p.mean.as_vec3().to_array())
            .collect()
    }

    /// The mean linear radiance of the whole image, per channel.
    pub fn image_mean(&self) -> DVec3 {
        let sum: DVec3 = self.pixels.iter().map(|p| p.mean).sum();
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
    fn welford_matches_two_pass_and_merge_matches_sequential() {
        let samples: Vec<Vec3> = (0..101)
            .map(|i| Vec3::new(i as f32, (i * i % 17) as f32, 1e4 + (i % 3) as f32))
            .collect();
        let mut all = PixelStats::default();
        samples.iter().for_each(|&s| all.add(s));
        let n = samples.len() as f64;
        let mean: DVec3 = samples.iter().map(|s| s.as_dvec3()).sum::<DVec3>() / n;
        let var: DVec3 = samples
            .iter()
            .map(|s| (s.as_dvec3() - mean) * (s.as_dvec3() - mean))
            .sum::<DVec3>()
            / (n - 1.0);
        assert!((all.mean - mean).abs().max_element() < 1e-9);
        assert!((all.variance() - var).abs().max_element() < 1e-7);

        let (mut a, mut b) = (PixelStats::default(), PixelStats::default());
        samples[..40].iter().for_each(|&s| a.add(s));
        samples[40..].iter().for_each(|&s| b.add(s));
        a.merge(&b);
        assert_eq!(a.n, all.n);
        assert!((a.mean - all.mean).abs().max_element() < 1e-9);
        assert!((a.m2 - all.m2).abs().max_element() < 1e-6);
    }
}
