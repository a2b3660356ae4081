//! Chi-square tests of a BSDF's `sample` against its `pdf` (as pbrt-v4's bsdfs_test and
//! Mitsuba 3's ChiSquareTest), through the one harness (`common::chi_square`): polar cells over
//! the sphere of directions about the mirror (and refracted) direction, each cell's expected
//! count the pdf's integral over it, and one cell for the draws the pdf leaves out.

pub use super::common::chi_square::Histogram;
use super::common::chi_square::{self, Draw};
use super::hit;
use glam::Vec3;
use rt_gpu::scene::Material;
use rt_gpu::shared::ray::Hit;
use rt_gpu::shared::sampler::Sampler;

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
    sample_vs_pdf_between(material, h, (pdf_of, h), wo, cells, samples)
}

/// [`sample_vs_pdf_in`], the pdf taken of `pdf_of` at another hit (a negative control's).
pub fn sample_vs_pdf_between(
    material: &Material,
    h: &Hit,
    (pdf_of, pdf_hit): (&Material, &Hit),
    wo: Vec3,
    cells: &Histogram,
    samples: u32,
) -> (f64, usize, f64) {
    let tally = chi_square::tally(cells, samples, |i| {
        let mut sampler = Sampler::independent(i, 0, 17);
        match material.sample(wo, h, &mut sampler) {
            // A delta lobe's draws have no density: with the path's end, they are what the
            // pdf leaves out.
            Some(s) if s.lobe.is_delta() => Draw::Lost,
            Some(s) => {
                // Pooling cells hides draws where the density is zero: each is checked.
                assert!(
                    material.pdf(wo, s.wi, h) > 0.0,
                    "{material:?} sampled {} at wo {wo}, where its pdf is 0",
                    s.wi
                );
                Draw::Direction(s.wi)
            }
            None => Draw::Lost,
        }
    });
    let expected = chi_square::expected_with_lost(cells, &|wi| pdf_of.pdf(wo, wi, pdf_hit) as f64);
    chi_square::test(&tally, &expected, samples)
}
