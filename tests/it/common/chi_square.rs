//! The chi-square test of a sampling routine against its pdf: one harness for every sampling
//! test, in the shape of Mitsuba 3's `ChiSquareTest` (a domain, a sample function, a pdf
//! function). A [`Domain`] divides the directions the routine draws into cells and integrates
//! the pdf over each (the expected counts); [`tally`] bins the draws; [`test`] pools the cells
//! expected below 5 and gives Pearson's statistic and its p-value (`stats::chi_square`).
//!
//! The domains: [`Polar`] and [`Histogram`] here (cells about a direction, narrowing toward
//! it, for BSDFs: `bsdfs/`); the others live beside the one test that needs them (a cone about
//! a light, `nee.rs`; an environment's texels, `environment.rs`; cosine and azimuth cells about
//! an axis, `media.rs` and `materials.rs`).

use glam::Vec3;
use std::f64::consts::PI;

/// Cells over the directions a sampling routine draws.
pub trait Domain {
    /// How many cells.
    fn cells(&self) -> usize;
    /// The cell direction `d` falls in; `None` outside the domain.
    fn cell(&self, d: Vec3) -> Option<usize>;
    /// Each cell's probability under `pdf` (a density over the domain): its integral over the
    /// cell.
    fn expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64>;
}

/// What one draw of a sampling routine gave.
pub enum Draw {
    /// A direction the pdf has a density for.
    Direction(Vec3),
    /// What the pdf's integral leaves out: no direction (the path ends), or one from a delta
    /// lobe. Counted in the extra cell [`expected_with_lost`] adds.
    Lost,
    /// Not counted at all (a routine that may decline, whose pdf is normalised over what it
    /// gives).
    Skipped,
}

/// The draws binned: one count per cell and one more for [`Draw::Lost`], and the directions
/// that fell outside every cell.
pub struct Tally {
    pub observed: Vec<f64>,
    pub outside: Vec<Vec3>,
}

/// Bins `draw(i)` for i in 0..`samples` into `domain`'s cells.
pub fn tally(domain: &dyn Domain, samples: u32, draw: impl Fn(u32) -> Draw) -> Tally {
    let mut observed = vec![0.0f64; domain.cells() + 1];
    let mut outside = Vec::new();
    for i in 0..samples {
        match draw(i) {
            Draw::Direction(d) => match domain.cell(d) {
                Some(cell) => observed[cell] += 1.0,
                None => outside.push(d),
            },
            Draw::Lost => observed[domain.cells()] += 1.0,
            Draw::Skipped => {}
        }
    }
    Tally { observed, outside }
}

/// `domain`'s expected probabilities under `pdf`, and the lost draws' cell: 1 - their sum.
pub fn expected_with_lost(domain: &dyn Domain, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
    let mut expected = domain.expected(pdf);
    let covered: f64 = expected.iter().sum();
    expected.push((1.0 - covered).max(0.0));
    expected
}

/// Pearson's chi-square of the tally against `expected` (one probability per cell, the lost
/// draws' last or absent: then the tally's lost cell must be empty), over `samples` draws:
/// (chi2, cells after pooling, p-value).
pub fn test(tally: &Tally, expected: &[f64], samples: u32) -> (f64, usize, f64) {
    let observed = if expected.len() + 1 == tally.observed.len() {
        let (cells, lost) = tally.observed.split_at(expected.len());
        assert_eq!(lost, [0.0], "lost draws where the pdf leaves nothing out");
        cells
    } else {
        &tally.observed[..]
    };
    super::stats::chi_square(expected, observed, samples as f64)
}

/// The histogram's cells: directions in polar coordinates about the mirror direction `r`
/// (theta' = pi u^3 for u in [0, 1], so that cells shrink toward `r` where glossy lobes are
/// narrow; phi' uniform).
const CELLS_U: usize = 24;
const CELLS_PHI: usize = 32;

/// Cells over the whole sphere about a direction (a BSDF's mirror or refracted direction).
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
    fn polar_cell(&self, d: Vec3) -> usize {
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
    fn polar_expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let f = |u: f64, phi: f64| {
            let theta = PI * u * u * u;
            pdf(self.dir(u, phi)) * theta.sin() * 3.0 * PI * u * u
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
}

impl Domain for Polar {
    fn cells(&self) -> usize {
        CELLS_U * CELLS_PHI
    }
    fn cell(&self, d: Vec3) -> Option<usize> {
        Some(self.polar_cell(d))
    }
    fn expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        self.polar_expected(pdf)
    }
}

impl Domain for Histogram {
    fn cells(&self) -> usize {
        CELLS_U * CELLS_PHI * if self.below.is_some() { 2 } else { 1 }
    }

    fn cell(&self, d: Vec3) -> Option<usize> {
        Some(match &self.below {
            Some(below) if d.dot(self.normal) <= 0.0 => CELLS_U * CELLS_PHI + below.polar_cell(d),
            _ => self.above.polar_cell(d),
        })
    }

    fn expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let Some(below) = &self.below else {
            return self.above.polar_expected(pdf);
        };
        let n = self.normal;
        let mut out = (self.above).polar_expected(&|w| if w.dot(n) > 0.0 { pdf(w) } else { 0.0 });
        out.extend(below.polar_expected(&|w| if w.dot(n) <= 0.0 { pdf(w) } else { 0.0 }));
        out
    }
}

/// Cells of the whole sphere, or a cap of it, about an axis: `rings` rings evenly spaced in
/// s = ((cos theta - `lowest_cos`) / (1 - `lowest_cos`))^`power`, by `sectors` sectors of phi;
/// a cell's integral is a midpoint rule of `sub` x `sub_phi` points in (s, phi) (16 x 16 unless
/// set: a density symmetric about the axis needs one in phi, a peaked one many in s). With `power` 2
/// over the hemisphere (`lowest_cos` 0), each cell holds the same share of a cosine-weighted
/// density; with `power` 1 over the sphere (`lowest_cos` -1), of a uniform one.
pub struct Rings {
    axis: Vec3,
    t: Vec3,
    b: Vec3,
    pub lowest_cos: f64,
    pub power: i32,
    pub rings: usize,
    pub sectors: usize,
    pub sub: usize,
    pub sub_phi: usize,
}

impl Rings {
    pub fn new(axis: Vec3, lowest_cos: f64, power: i32, rings: usize, sectors: usize) -> Self {
        let (t, b) = rt_gpu::shared::warp::basis(axis);
        Rings {
            axis,
            t,
            b,
            lowest_cos,
            power,
            rings,
            sectors,
            sub: 16,
            sub_phi: 16,
        }
    }

    /// cos theta at s, and d(cos theta)/ds.
    fn cos_at(&self, s: f64) -> (f64, f64) {
        let span = 1.0 - self.lowest_cos;
        let k = 1.0 / self.power as f64;
        (
            self.lowest_cos + span * s.powf(k),
            span * k * s.powf(k - 1.0),
        )
    }
}

impl Domain for Rings {
    fn cells(&self) -> usize {
        self.rings * self.sectors
    }

    fn cell(&self, d: Vec3) -> Option<usize> {
        let c = (d.dot(self.axis) as f64).clamp(-1.0, 1.0);
        if c < self.lowest_cos {
            return None;
        }
        let s = ((c - self.lowest_cos) / (1.0 - self.lowest_cos)).powi(self.power);
        let phi = (d.dot(self.b) as f64).atan2(d.dot(self.t) as f64) + PI;
        let i = ((s * self.rings as f64) as usize).min(self.rings - 1);
        let j = ((phi / (2.0 * PI) * self.sectors as f64) as usize).min(self.sectors - 1);
        Some(i * self.sectors + j)
    }

    fn expected(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let (ds, dphi) = (1.0 / self.rings as f64, 2.0 * PI / self.sectors as f64);
        let mut out = Vec::with_capacity(self.cells());
        for i in 0..self.rings {
            for j in 0..self.sectors {
                let mut sum = 0.0;
                for si in 0..self.sub {
                    for sj in 0..self.sub_phi {
                        let s = (i as f64 + (si as f64 + 0.5) / self.sub as f64) * ds;
                        let phi = (j as f64 + (sj as f64 + 0.5) / self.sub_phi as f64) * dphi - PI;
                        let (c, dc_ds) = self.cos_at(s);
                        let sin = (1.0 - c * c).max(0.0).sqrt();
                        let d = (c * self.axis.as_dvec3()
                            + sin * phi.cos() * self.t.as_dvec3()
                            + sin * phi.sin() * self.b.as_dvec3())
                        .as_vec3();
                        sum += pdf(d) * dc_ds;
                    }
                }
                out.push(sum / (self.sub * self.sub_phi) as f64 * ds * dphi);
            }
        }
        out
    }
}
