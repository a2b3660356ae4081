//! Chi-square tests of a BSDF's `sample` against its `pdf` (as pbrt-v4's bsdfs_test and
//! Mitsuba 3's ChiSquareTest): a histogram over the sphere of directions, each cell's expected
//! count the pdf's integral over it.

use super::common::stats::chi_square;
use super::hit;
use glam::Vec3;
use rt_gpu::scene::Material;
use rt_gpu::shared::ray::Hit;
use rt_gpu::shared::sampler::Sampler;
use std::f64::consts::PI;

/// The histogram's cells: directions in polar coordinates about the mirror direction `r`
/// (theta' = pi u^3 for u in [0, 1], so that cells shrink toward `r` where glossy lobes are
/// narrow; phi' uniform).
const CELLS_U: usize = 24;
const CELLS_PHI: usize = 32;

pub struct Polar {
    r: Vec3,
    s: Vec3,
    t: Vec3,
}

impl Polar {
    pub fn new(r: Vec3) -> Self {
        let (s, t) = rt_gpu::shared::warp::basis(r);
        Polar { r, s, t }
    }
    pub fn cell(&self, d: Vec3) -> usize {
        // The angle from atan2 of the transverse and axial parts, in f64: the cells near `r`
        // are narrower than an f32 cosine resolves.
        let (x, y, z) = (
            d.dot(self.s) as f64,
            d.dot(self.t) as f64,
            d.dot(self.r) as f64,
        );
        let u = ((x * x + y * y).sqrt().atan2(z) / PI).cbrt();
        let phi = y.atan2(x) + PI;
        let a = ((u * CELLS_U as f64) as usize).min(CELLS_U - 1);
        let b = ((phi / (2.0 * PI) * CELLS_PHI as f64) as usize).min(CELLS_PHI - 1);
        a * CELLS_PHI + b
    }
    fn dir(&self, u: f64, phi: f64) -> Vec3 {
        let theta = PI * u * u * u;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = (phi - PI).sin_cos();
        (self.s * (st * cp) as f32 + self.t * (st * sp) as f32 + self.r * ct as f32).normalize()
    }
    /// The integral of `pdf` over each cell, in (u, phi) with the Jacobian sin(theta)
    /// dtheta/du: adaptive Simpson on 4 x 4 sub-cells per cell, each halved (to depth 6) until
    /// its estimate changes by under 1e-9, so that the horizon's cut and narrow lobes inside a
    /// cell are integrated too.
    pub fn expected(&self, pdf: impl Fn(Vec3) -> f32) -> Vec<f64> {
        let f = |u: f64, phi: f64| {
            let theta = PI * u * u * u;
            pdf(self.dir(u, phi)) as f64 * theta.sin() * 3.0 * PI * u * u
        };
        let du = 1.0 / CELLS_U as f64;
        let dphi = 2.0 * PI / CELLS_PHI as f64;
        let mut out = vec![0.0; CELLS_U * CELLS_PHI];
        for a in 0..CELLS_U {
            for b in 0..CELLS_PHI {
                let mut sum = 0.0;
                for i in 0..4 {
                    for j in 0..4 {
                        let u0 = (a as f64 + i as f64 / 4.0) * du;
                        let p0 = (b as f64 + j as f64 / 4.0) * dphi;
                        let (u1, p1) = (u0 + du / 4.0, p0 + dphi / 4.0);
                        let whole = simpson(&f, u0, u1, p0, p1);
                        sum += adaptive(&f, u0, u1, p0, p1, whole, 6, 1e-9);
                    }
                }
                out[a * CELLS_PHI + b] = sum;
            }
        }
        out
    }
}

/// Simpson's rule on one panel pair in each dimension.
fn simpson(f: &impl Fn(f64, f64) -> f64, u0: f64, u1: f64, p0: f64, p1: f64) -> f64 {
    let w = [1.0, 4.0, 1.0];
    let mut sum = 0.0;
    for (i, wu) in w.iter().enumerate() {
        for (j, wp) in w.iter().enumerate() {
            let u = u0 + (u1 - u0) * i as f64 / 2.0;
            let p = p0 + (p1 - p0) * j as f64 / 2.0;
            sum += wu * wp * f(u, p);
        }
    }
    sum * (u1 - u0) * (p1 - p0) / 36.0
}

#[allow(clippy::too_many_arguments)]
fn adaptive(
    f: &impl Fn(f64, f64) -> f64,
    u0: f64,
    u1: f64,
    p0: f64,
    p1: f64,
    whole: f64,
    depth: u32,
    tolerance: f64,
) -> f64 {
    let (um, pm) = ((u0 + u1) / 2.0, (p0 + p1) / 2.0);
    let quarters = [
        (u0, um, p0, pm),
        (um, u1, p0, pm),
        (u0, um, pm, p1),
        (um, u1, pm, p1),
    ];
    let parts = quarters.map(|(a, b, c, d)| simpson(f, a, b, c, d));
    let sum: f64 = parts.iter().sum();
    if depth == 0 || (sum - whole).abs() <= 15.0 * tolerance {
        return sum + (sum - whole) / 15.0;
    }
    quarters
        .iter()
        .zip(parts)
        .map(|(&(a, b, c, d), part)| adaptive(f, a, b, c, d, part, depth - 1, tolerance / 4.0))
        .sum()
}

/// The cells of a test: polar cells about the mirror direction, and for a BSDF that transmits,
/// a second set below the surface about the refracted direction, so that each lobe has narrow
/// cells where it peaks.
pub struct Histogram {
    normal: Vec3,
    above: Polar,
    below: Option<Polar>,
}

impl Histogram {
    /// For a reflecting BSDF at `wo` on a surface with this normal.
    pub fn reflecting(normal: Vec3, wo: Vec3) -> Self {
        Histogram {
            normal,
            above: Polar::new(rt_gpu::material::reflect(-wo, normal)),
            below: None,
        }
    }

    /// For a BSDF that also refracts, with `eta` = the index on wo's side over the other's: the
    /// cells below are about the refracted direction (straight down under total internal
    /// reflection).
    pub fn transmitting(normal: Vec3, wo: Vec3, eta: f32) -> Self {
        let cos_i = wo.dot(normal);
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        let refracted = if sin2_t < 1.0 {
            (-eta * wo + (eta * cos_i - (1.0 - sin2_t).sqrt()) * normal).normalize()
        } else {
            -normal
        };
        Histogram {
            below: Some(Polar::new(refracted)),
            ..Histogram::reflecting(normal, wo)
        }
    }

    pub fn cells(&self) -> usize {
        CELLS_U * CELLS_PHI * if self.below.is_some() { 2 } else { 1 }
    }

    pub fn cell(&self, d: Vec3) -> usize {
        match &self.below {
            Some(below) if d.dot(self.normal) <= 0.0 => CELLS_U * CELLS_PHI + below.cell(d),
            _ => self.above.cell(d),
        }
    }

    pub fn expected(&self, pdf: impl Fn(Vec3) -> f32) -> Vec<f64> {
        let Some(below) = &self.below else {
            return self.above.expected(pdf);
        };
        let n = self.normal;
        let mut out = self
            .above
            .expected(|w| if w.dot(n) > 0.0 { pdf(w) } else { 0.0 });
        out.extend(below.expected(|w| if w.dot(n) <= 0.0 { pdf(w) } else { 0.0 }));
        out
    }
}

/// Chi-square p-value of `samples` draws of `material.sample` at `wo` against the density
/// `pdf_of.pdf` (the same material, or a wrong one for the control), over the polar cells
/// about the mirror direction plus one cell for the draws that end the path or come from a delta
/// lobe (expected: 1 - the integral of the pdf).
pub fn sample_vs_pdf(
    material: &Material,
    pdf_of: &Material,
    wo: Vec3,
    samples: u32,
) -> (f64, usize, f64) {
    sample_vs_pdf_at(material, pdf_of, Vec3::Z, wo, samples)
}

/// [`sample_vs_pdf`] at a surface whose normal is `normal`.
pub fn sample_vs_pdf_at(
    material: &Material,
    pdf_of: &Material,
    normal: Vec3,
    wo: Vec3,
    samples: u32,
) -> (f64, usize, f64) {
    let cells = Histogram::reflecting(normal, wo);
    sample_vs_pdf_in(material, pdf_of, &hit(normal), wo, &cells, samples)
}

/// [`sample_vs_pdf`] at hit `h`, over `cells`.
pub fn sample_vs_pdf_in(
    material: &Material,
    pdf_of: &Material,
    h: &Hit,
    wo: Vec3,
    cells: &Histogram,
    samples: u32,
) -> (f64, usize, f64) {
    let mut observed = vec![0.0; cells.cells() + 1];
    for i in 0..samples {
        let mut sampler = Sampler::independent(i, 0, 17);
        match material.sample(wo, h, &mut sampler) {
            // A delta lobe's draws have no density: with the path's end, they are what the
            // pdf leaves out.
            Some(s) if s.lobe.is_delta() => observed[cells.cells()] += 1.0,
            Some(s) => {
                // Pooling cells hides draws where the density is zero: each is checked.
                assert!(
                    material.pdf(wo, s.wi, h) > 0.0,
                    "{material:?} sampled {} at wo {wo}, where its pdf is 0",
                    s.wi
                );
                observed[cells.cell(s.wi)] += 1.0
            }
            None => observed[cells.cells()] += 1.0,
        }
    }
    let mut expected = cells.expected(|wi| pdf_of.pdf(wo, wi, h));
    let covered: f64 = expected.iter().sum();
    expected.push((1.0 - covered).max(0.0));
    chi_square(&expected, &observed, samples as f64)
}
