//! The image-equivalence test shared by the GPU and integrator tests.
//!
//! Two films of the same scene with independent seeds are compared cell by cell with Welch's
//! z-test, z = (m1 - m2) / sqrt(v1/n1 + v2/n2), where each pixel's v/n is its film's measured
//! variance of the mean. Cells are single pixels and, to give the test power against small
//! global changes (a 2% albedo change is invisible in one noisy pixel), also 4x4 blocks, 16x16
//! blocks and the whole image; a block's mean is the mean of its pixel means and its variance
//! the sum of their variances over the block size squared. Every cell and channel is one
//! comparison; the family-wise significance is ALPHA = 0.01, Sidak-corrected over all m
//! comparisons: each is tested at 1 - (1 - ALPHA)^(1/m).
//!
//! Stated up front: up to 0.5% of single-pixel comparisons may fail (a pixel whose rare bright
//! paths one film happened not to sample has an underestimated variance), and no block or
//! whole-image comparison may fail.

use rt_gpu::film::Film;
use statrs::distribution::{ContinuousCDF, Normal};

pub const ALPHA: f64 = 0.01;
pub const ALLOWED_PIXEL_FAILURE_FRACTION: f64 = 0.005;
const BLOCK_SIZES: [u32; 3] = [4, 16, 0]; // 0: the whole image

#[derive(Debug)]
pub struct Verdict {
    pub comparisons: usize,
    pub z_threshold: f64,
    pub pixel_failures: usize,
    pub pixel_comparisons: usize,
    pub block_failures: usize,
    pub worst_block_z: f64,
}

impl Verdict {
    pub fn passed(&self) -> bool {
        self.block_failures == 0
            && (self.pixel_failures as f64)
                <= ALLOWED_PIXEL_FAILURE_FRACTION * self.pixel_comparisons as f64
    }
}

/// (mean, variance of the mean) of each channel over the cell [x0, x1) x [y0, y1), of `film`'s
/// radiance times `scale`.
fn cell(film: &Film, scale: f64, x0: u32, y0: u32, x1: u32, y1: u32) -> [(f64, f64); 3] {
    let mut out = [(0.0, 0.0); 3];
    let k = ((x1 - x0) * (y1 - y0)) as f64;
    for y in y0..y1 {
        for x in x0..x1 {
            let p = film.pixel(x, y);
            let v = film.variance_of_mean(p);
            for c in 0..3 {
                out[c].0 += scale * p.mean()[c] / k;
                out[c].1 += scale * scale * v[c] / (k * k);
            }
        }
    }
    out
}

fn z(a: (f64, f64), b: (f64, f64)) -> f64 {
    let diff = (a.0 - b.0).abs();
    let var = a.1 + b.1;
    if var > 0.0 {
        diff / var.sqrt()
    } else if diff <= 1e-6 * a.0.abs().max(b.0.abs()).max(1e-6) {
        // Both noise-free (e.g. background): equal up to f32 rounding passes.
        0.0
    } else {
        f64::INFINITY
    }
}

pub fn compare(a: &Film, b: &Film) -> Verdict {
    compare_scaled(a, 1.0, b)
}

/// [`compare`] of `a`'s radiance times `scale` with `b`'s.
pub fn compare_scaled(a: &Film, scale: f64, b: &Film) -> Verdict {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let (w, h) = (a.width, a.height);
    let mut cells: Vec<(bool, u32, u32, u32, u32)> = Vec::new();
    for y in 0..h {
        for x in 0..w {
            cells.push((true, x, y, x + 1, y + 1));
        }
    }
    for size in BLOCK_SIZES {
        let (bw, bh) = if size == 0 {
            (w, h)
        } else {
            (size.min(w), size.min(h))
        };
        for y in (0..h).step_by(bh as usize) {
            for x in (0..w).step_by(bw as usize) {
                cells.push((false, x, y, (x + bw).min(w), (y + bh).min(h)));
            }
        }
    }
    let comparisons = cells.len() * 3;
    let per_test_alpha = 1.0 - (1.0 - ALPHA).powf(1.0 / comparisons as f64);
    let z_threshold = Normal::standard().inverse_cdf(1.0 - per_test_alpha / 2.0);
    let mut verdict = Verdict {
        comparisons,
        z_threshold,
        pixel_failures: 0,
        pixel_comparisons: (w * h * 3) as usize,
        block_failures: 0,
        worst_block_z: 0.0,
    };
    for (is_pixel, x0, y0, x1, y1) in cells {
        let (ca, cb) = (cell(a, scale, x0, y0, x1, y1), cell(b, 1.0, x0, y0, x1, y1));
        for c in 0..3 {
            let zc = z(ca[c], cb[c]);
            if is_pixel {
                verdict.pixel_failures += (zc > z_threshold) as usize;
            } else {
                verdict.worst_block_z = verdict.worst_block_z.max(zc);
                verdict.block_failures += (zc > z_threshold) as usize;
            }
        }
    }
    verdict
}

/// Pearson's chi-square of `observed` counts against `expected` probabilities over
/// `samples` draws, cells expected below 5 pooled into one: (chi2, cells, p-value).
pub fn chi_square(expected: &[f64], observed: &[f64], samples: f64) -> (f64, usize, f64) {
    use statrs::distribution::ChiSquared;
    let (mut chi2, mut cells, mut pooled_e, mut pooled_o) = (0.0, 0usize, 0.0, 0.0);
    for (e, o) in expected.iter().zip(observed) {
        let e = e * samples;
        if e < 5.0 {
            pooled_e += e;
            pooled_o += o;
        } else {
            chi2 += (o - e).powi(2) / e;
            cells += 1;
        }
    }
    if pooled_e > 0.0 {
        chi2 += (pooled_o - pooled_e).powi(2) / pooled_e.max(5.0);
        cells += 1;
    }
    let p = ChiSquared::new((cells - 1) as f64).expect("dof").sf(chi2);
    (chi2, cells, p)
}
