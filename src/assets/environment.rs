//! An environment light: an equirectangular HDR image around the scene (looked up and sampled
//! by `src/cpu/environment.rs`, twin `shaders/environment.wgsl`), and the tables both
//! backends sample it with.
//!
//! Mapping: a direction's longitude and latitude as `sphere_uv` gives them (u from -x round
//! through +z..., v from the south pole), after turning the direction by -`rotate_y`: image
//! column u, image row 1 - v (row 0 is the sky straight up).

use super::image::Image;
use std::sync::Arc;

/// `background = { image = "sky.hdr", strength = 1, rotate_y = 0 }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub image: Arc<Image>,
    /// Multiplies the image's radiance.
    pub strength: f32,
    /// Turns the sky about +y (degrees, as objects turn).
    pub rotate_y_degrees: f32,
    /// cos and sin of `rotate_y_degrees`, worked out once in f64 (both backends use these).
    pub rotation: [f32; 2],
}

/// Largest strength accepted.
pub const MAX_STRENGTH: f32 = 1e6;

impl Environment {
    pub fn new(image: Arc<Image>, strength: f32, rotate_y_degrees: f32) -> Result<Self, String> {
        if !(0.0..=MAX_STRENGTH).contains(&strength) {
            return Err(format!(
                "background strength must be in [0, {MAX_STRENGTH:e}], got {strength}"
            ));
        }
        if !(rotate_y_degrees.abs() <= 360.0) {
            return Err(format!(
                "background rotate_y must be in [-360, 360] degrees, got {rotate_y_degrees}"
            ));
        }
        let (sin, cos) = (rotate_y_degrees as f64).to_radians().sin_cos();
        Ok(Environment {
            image,
            strength,
            rotate_y_degrees,
            rotation: [cos as f32, sin as f32],
        })
    }

    /// The tables that sample it (built once per image).
    pub fn distribution(&self) -> &Distribution {
        self.image
            .sampling
            .get_or_init(|| Distribution::new(&self.image))
    }

    /// Its power on a disc of radius `radius` facing any way: pi r^2 times the integral of its
    /// luminance over the sphere of directions (how light picking weighs it against the rest).
    pub fn power(&self, radius: f64) -> f64 {
        std::f64::consts::PI * radius * radius * self.distribution().integral * self.strength as f64
    }
}

/// Luminance of linear Rec. 709 RGB (the weights light picking uses too).
pub fn luminance(r: f32, g: f32, b: f32) -> f64 {
    0.2126 * r as f64 + 0.7152 * g as f64 + 0.0722 * b as f64
}

/// A piecewise-constant density over the image, each texel split into [`cells_per_texel`]
/// x [`cells_per_texel`] cells, in proportion to the mean over the cell of the luminance as looked up (bilinearly
/// filtered), less the sky's mean where it is above it ([`compensated_weights`]), times
/// sin(theta) (the solid angle a cell spans), sampled by inverting cumulative
/// distributions: the first number picks a row of cells from the rows' CDF, the second a cell
/// from that row's, and their remainders place the direction across the cell. Cells finer than
/// texels follow the filtered radiance more closely, so a sample's radiance over its pdf varies
/// less across a bright sun (measured in docs/benchmarks.md); images of more than
/// `SUBDIVIDED_MAX_TEXELS` texels keep one cell a texel, for the tables' memory. Inversion is monotone, so stratified numbers (Sobol
/// points) give stratified directions; an alias table would scatter neighbouring numbers over
/// distant cells and lose that (pbrt-v4 and Mitsuba invert too). (One table over all cells
/// would ask one f32 number to tell apart more cells than its 24 bits can in a large image,
/// and leave no bits to place the direction.) Built in f64, stored in f32; each cell's density
/// is the product of its row's and column's steps of the stored CDFs, so that it is the chance
/// with which the picks land on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    /// Cells across and down: the image's width and height times [`cells_per_texel`].
    pub width: usize,
    pub height: usize,
    /// The rows' CDF (height + 1 values).
    pub rows: Cdfs,
    /// Per row, its cells' CDF (width + 1 values each), row by row.
    pub columns: Cdfs,
    /// Per cell, row by row: its density in image coordinates (s, t) in [0, 1]^2, its share
    /// of the whole times the number of cells.
    pub density: Vec<f32>,
    /// The integral of luminance over directions (steradians), strength 1.
    pub integral: f64,
}

/// Most texels an image may have for its distribution to split each into 2 x 2 cells (the
/// kernel's tables then take 64 bytes a texel).
pub const SUBDIVIDED_MAX_TEXELS: u32 = 1 << 19;

/// Cells across a texel (and down) in the distribution of an image of `width` x `height`
/// texels (twin: `environment_cells` in shaders/environment.wgsl).
pub fn cells_per_texel(width: u32, height: u32) -> usize {
    if width * height <= SUBDIVIDED_MAX_TEXELS {
        2
    } else {
        1
    }
}

/// The shares of the previous texel, the texel itself and the next one in the mean, over cell
/// `i` of `n` across a texel, of a bilinear filter along one axis (tents between texels'
/// centres): over the whole texel 1/8, 3/4, 1/8; over its halves 1/4, 3/4, 0 and 0, 3/4, 1/4.
fn filter_shares(n: usize, i: usize) -> [f64; 3] {
    match (n, i) {
        (1, _) => [0.125, 0.75, 0.125],
        (2, 0) => [0.25, 0.75, 0.0],
        (2, _) => [0.0, 0.75, 0.25],
        _ => unreachable!("one or two cells a texel"),
    }
}

/// Each cell's weight for sampling, its filtered radiance `filtered` above the sky's mean `mean`
/// (over solid angle) times its solid angle (in proportion to sin(theta) of row `cy`): MIS
/// compensation (Karlik et al. 2019, pbrt-v4's `compensatedDistribution`). Light sampling is
/// only ever combined with BSDF sampling here, which finds the dim, even parts of a sky well,
/// so its samples go where the sky is brighter than its mean, where BSDF sampling does badly;
/// a direction light sampling never picks is weighed 1 on the BSDF's side. A sky with nothing
/// above its mean (an even one) keeps the plain weights; a black one is sampled uniformly.
fn compensated_weights(
    filtered: &[f64],
    cw: usize,
    mean: f64,
    sin_theta: impl Fn(usize) -> f64,
) -> Vec<f64> {
    let weighed = |above: &dyn Fn(f64) -> f64| -> Vec<f64> {
        filtered
            .chunks_exact(cw)
            .enumerate()
            .flat_map(|(cy, row)| {
                let sin = sin_theta(cy);
                row.iter().map(move |&f| above(f) * sin)
            })
            .collect()
    };
    let compensated = weighed(&|f| (f - mean).max(0.0));
    if compensated.iter().sum::<f64>() > 0.0 {
        return compensated;
    }
    let plain = weighed(&|f| f);
    if plain.iter().sum::<f64>() > 0.0 {
        plain
    } else {
        vec![1.0; filtered.len()] // nothing to favour: uniform over the image
    }
}

/// Cumulative distribution functions of piecewise-constant densities on [0, 1), one or several
/// side by side: a table of `n` slots is `n + 1` entries whose values rise from 0 to 1, each
/// entry k < n also holding a guide (Chen and Asau 1974): the slot where `u` = k / n falls,
/// from which a pick walks a step or two instead of searching (a binary search's steps are
/// branches no predictor can learn). A value and its guide share an entry,
/// as the kernel's vec4f does, so a pick's loads share cache lines.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Cdfs {
    pub entries: Vec<CdfEntry>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CdfEntry {
    pub value: f32,
    /// The last slot whose value is at most k / n, for this entry's k (0 past the last slot).
    pub guide: u32,
}

impl Cdfs {
    /// The slot of table `table` (of those of `n` slots side by side) that `u` in [0, 1)
    /// picks: the last whose CDF value is at most `u`, never a slot of weight 0; and `u`'s
    /// remainder across it, uniform in [0, 1) again. The kernel's `cdf_pick` does the same f32
    /// arithmetic; the slot found does not depend on the guide, only the walk's length does.
    #[inline]
    pub fn pick(&self, table: usize, n: usize, u: f32) -> (usize, f32) {
        let cdf = &self.entries[table * (n + 1)..][..n + 1];
        let mut i = cdf[((u * n as f32) as u32 as usize).min(n - 1)].guide as usize;
        while i + 1 < n && cdf[i + 1].value <= u {
            i += 1;
        }
        while i > 0 && cdf[i].value > u {
            i -= 1;
        }
        let (low, high) = (cdf[i].value, cdf[i + 1].value);
        let rest = if high > low {
            ((u - low) / (high - low)).clamp(0.0, ONE_BELOW)
        } else {
            0.0
        };
        (i, rest)
    }

    /// The values of table `table` of `n` slots.
    pub fn values(&self, table: usize, n: usize) -> impl Iterator<Item = f32> + '_ {
        self.entries[table * (n + 1)..][..n + 1]
            .iter()
            .map(|e| e.value)
    }

    /// The step of slot `i` of table `table` of `n` slots: its chance.
    fn step(&self, table: usize, n: usize, i: usize) -> f64 {
        let at = table * (n + 1) + i;
        self.entries[at + 1].value as f64 - self.entries[at].value as f64
    }

    /// Appends the table of `weights` (uniform if they are all 0).
    fn push(&mut self, weights: &[f64]) {
        let n = weights.len();
        let total: f64 = weights.iter().sum();
        let mut running = 0.0;
        let mut values = vec![0.0f32];
        for (i, w) in weights.iter().enumerate() {
            running += if total > 0.0 {
                w / total
            } else {
                1.0 / n as f64
            };
            // Rounding to f32 keeps the values in order; the last is 1 exactly.
            values.push(if i + 1 == n {
                1.0
            } else {
                running.min(1.0) as f32
            });
        }
        let mut slot = 0;
        for (k, &value) in values.iter().enumerate() {
            let at = k as f64 / n as f64;
            while slot + 1 < n && values[slot + 1] as f64 <= at {
                slot += 1;
            }
            let guide = if k < n { slot as u32 } else { 0 };
            self.entries.push(CdfEntry { value, guide });
        }
    }
}

impl Distribution {
    pub fn new(image: &Image) -> Self {
        let (w, h) = (image.width as usize, image.height as usize);
        let n = cells_per_texel(image.width, image.height);
        let (cw, ch) = (n * w, n * h);
        let lum: Vec<f64> = (0..w * h)
            .map(|i| {
                let t = image.texel((i % w) as u32, (i / w) as u32);
                luminance(t.x, t.y, t.z)
            })
            .collect();
        // Over each cell, the mean of the radiance as it is looked up, filtered bilinearly
        // (wrapping across, clamped at the poles): on each axis, shares of the texel and its
        // neighbours. A cell beside a small bright sun receives some of the sun's light through
        // the filter; weighed by its own texel's value alone it would be picked too rarely for
        // that light, and each pick would be a firefly. First across: per texel row, per cell.
        let across: Vec<f64> = (0..h * cw)
            .map(|i| {
                let (y, cx) = (i / cw, i % cw);
                let (x, part) = (cx / n, cx % n);
                let (left, right) = ((x + w - 1) % w, (x + 1) % w);
                let [l, c, r] = filter_shares(n, part);
                l * lum[y * w + left] + c * lum[y * w + x] + r * lum[y * w + right]
            })
            .collect();
        let mut filtered = Vec::with_capacity(cw * ch);
        let sin_theta = |cy: usize| (std::f64::consts::PI * (cy as f64 + 0.5) / ch as f64).sin();
        for cy in 0..ch {
            let (y, part) = (cy / n, cy % n);
            let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
            let [u, c, d] = filter_shares(n, part);
            filtered.extend((0..cw).map(|cx| {
                u * across[up * cw + cx] + c * across[y * cw + cx] + d * across[down * cw + cx]
            }));
        }
        let solid_angles: f64 = (0..ch).map(sin_theta).sum::<f64>() * cw as f64;
        let total: f64 = filtered
            .chunks_exact(cw)
            .enumerate()
            .map(|(cy, row)| row.iter().sum::<f64>() * sin_theta(cy))
            .sum();
        let cell_solid_angle =
            2.0 * std::f64::consts::PI / cw as f64 * std::f64::consts::PI / ch as f64;
        let integral = total * cell_solid_angle;
        let weights = compensated_weights(&filtered, cw, total / solid_angles, sin_theta);
        let row_sums: Vec<f64> = weights.chunks_exact(cw).map(|r| r.iter().sum()).collect();
        let mut rows = Cdfs::default();
        rows.push(&row_sums);
        let mut columns = Cdfs::default();
        for row in weights.chunks_exact(cw) {
            columns.push(row);
        }
        let cells = (cw * ch) as f64;
        let density = (0..cw * ch)
            .map(|i| {
                let (x, y) = (i % cw, i / cw);
                (rows.step(0, ch, y) * columns.step(y, cw, x) * cells) as f32
            })
            .collect();
        Distribution {
            width: cw,
            height: ch,
            rows,
            columns,
            density,
            integral,
        }
    }

    /// The cell (x, y) that (u1, u2) in [0, 1)^2 pick, and where across it (in [0, 1)^2).
    #[inline]
    pub fn pick(&self, u1: f32, u2: f32) -> ((usize, usize), (f32, f32)) {
        let (y, down) = self.rows.pick(0, self.height, u1);
        let (x, across) = self.columns.pick(y, self.width, u2);
        ((x, y), (across, down))
    }
}

pub use crate::shared::constants::ONE_BELOW;

#[cfg(test)]
mod tests {
    use super::*;

    /// Each cell's density is in proportion to the mean over it of the luminance as looked
    /// up (bilinearly, rows clamped to their centres as `cpu::environment` clamps them), less
    /// the sky's mean over solid angle where that leaves something (else 0), times sin(theta)
    /// at its centre: by a midpoint rule on 4 x 4 points a cell, exact for the bilinear lookup
    /// since cells split texels at their centres.
    fn assert_cells_follow_the_filtered_image(image: &Image) {
        let d = Distribution::new(image);
        let n = cells_per_texel(image.width, image.height);
        let (w, h) = (d.width, d.height);
        assert_eq!(
            (w, h),
            (n * image.width as usize, n * image.height as usize)
        );
        let rows = image.height as f32;
        let sin = |y: usize| (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
        let cell_means: Vec<f64> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let mut sum = 0.0;
                for (a, b) in (0..16).map(|k| (k % 4, k / 4)) {
                    let s = (x as f32 + (a as f32 + 0.5) / 4.0) / w as f32;
                    let t = (y as f32 + (b as f32 + 0.5) / 4.0) / h as f32;
                    let t = t.clamp(0.5 / rows, 1.0 - 0.5 / rows);
                    let v = crate::assets::image_lookup::bilinear(image, s, t);
                    sum += luminance(v.x, v.y, v.z) / 16.0;
                }
                sum
            })
            .collect();
        let solid_angles: f64 = (0..w * h).map(|i| sin(i / w)).sum();
        let sky_mean = (0..w * h).map(|i| cell_means[i] * sin(i / w)).sum::<f64>() / solid_angles;
        let expected: Vec<f64> = (0..w * h)
            .map(|i| (cell_means[i] - sky_mean).max(0.0) * sin(i / w))
            .collect();
        let total: f64 = expected.iter().sum();
        assert!(total > 0.0, "an image with something above its mean");
        for (i, (&density, e)) in d.density.iter().zip(&expected).enumerate() {
            // A cell within rounding of the mean may go either way.
            if (cell_means[i] - sky_mean).abs() <= 1e-9 * sky_mean {
                continue;
            }
            let want = e / total * (w * h) as f64;
            // A density is the product of the stored f32 CDFs' steps, each off by up to two
            // ulps of 1 (much of a small step near the end of a table).
            let (x, y) = (i % w, i / w);
            let rounding = 2.4e-7 * (1.0 / d.rows.step(0, h, y) + 1.0 / d.columns.step(y, w, x));
            let close = if want == 0.0 {
                density == 0.0
            } else {
                (density as f64 - want).abs() <= want * (1e-4 + rounding)
            };
            assert!(
                close,
                "{}x{}: cell {i}: {density} against {want}",
                image.width, image.height
            );
        }
        let mean = d.density.iter().map(|&x| x as f64).sum::<f64>() / (w * h) as f64;
        assert!((mean - 1.0).abs() < 1e-5, "{mean}");
    }

    #[test]
    fn cells_follow_the_filtered_image_and_the_cdfs_rise() {
        // A ramp of texels 1..=12, and single bright texels (a sun) amid black, in the middle,
        // at the left edge (the filter wraps across) and in the top row (clamped at the pole).
        let texels: Vec<f32> = (0..12).flat_map(|i| [1.0 + i as f32; 3]).collect();
        let ramp = Image::from_linear("ramp", 4, 3, texels).unwrap();
        assert_cells_follow_the_filtered_image(&ramp);
        let (w, h) = (8usize, 5usize);
        for bright in [(3, 2), (0, 2), (5, 0)] {
            let texels: Vec<f32> = (0..w * h)
                .flat_map(|i| [if (i % w, i / w) == bright { 1.0 } else { 0.0 }; 3])
                .collect();
            let sun = Image::from_linear("sun", w as u32, h as u32, texels).unwrap();
            assert_cells_follow_the_filtered_image(&sun);
        }
        // Each table rises from 0 to 1 in order (flat over cells below the mean).
        let d = Distribution::new(&ramp);
        let tables = std::iter::once(d.rows.values(0, d.height).collect::<Vec<_>>())
            .chain((0..d.height).map(|row| d.columns.values(row, d.width).collect()));
        for table in tables {
            let n = table.len() - 1;
            assert_eq!((table[0], table[n]), (0.0, 1.0));
            assert!(table.windows(2).all(|w| w[0] <= w[1]), "{table:?}");
        }
        // The integral of a white image is 4 pi, up to the midpoint rule's error; nothing in it
        // is above its mean, so it is sampled in proportion to solid angle (sin(theta)).
        let white = Image::from_linear("white", 8, 4, vec![1.0; 96]).unwrap();
        let d = Distribution::new(&white);
        assert!((d.integral / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.05);
        let sin = |y: usize| (std::f64::consts::PI * (y as f64 + 0.5) / d.height as f64).sin();
        let mean_sin = (0..d.height).map(sin).sum::<f64>() / d.height as f64;
        for (i, &density) in d.density.iter().enumerate() {
            let want = sin(i / d.width) / mean_sin;
            assert!(
                (density as f64 / want - 1.0).abs() < 1e-5,
                "cell {i}: {density}"
            );
        }
        // A sky lit half as brightly as the rest: light sampling never picks its dim half.
        let halves: Vec<f32> = (0..32)
            .flat_map(|i| [if i % 8 < 4 { 1.0 } else { 2.0 }; 3])
            .collect();
        let d = Distribution::new(&Image::from_linear("halves", 8, 4, halves).unwrap());
        for (i, &density) in d.density.iter().enumerate() {
            // Cells of texel columns 1-2 see only the dim texels through the filter.
            let texel_column = (i % d.width) / 2;
            if (1..3).contains(&texel_column) {
                assert_eq!(density, 0.0, "cell {i}");
            }
            if (5..7).contains(&texel_column) {
                assert!(density > 0.0, "cell {i}");
            }
        }
        // A black image is sampled uniformly and has no power.
        let black = Image::from_linear("black", 2, 2, vec![0.0; 12]).unwrap();
        let d = Distribution::new(&black);
        assert_eq!(d.density, vec![1.0; 16]);
        assert_eq!(d.integral, 0.0);
    }

    /// Images up to `SUBDIVIDED_MAX_TEXELS` texels get 2 x 2 cells a texel; larger ones one,
    /// and their cells (texels) still follow the filtered image.
    #[test]
    fn large_images_keep_one_cell_a_texel() {
        assert_eq!(cells_per_texel(1024, 512), 2);
        assert_eq!(cells_per_texel(1024, 513), 1);
        let (w, h) = (1024u32, 513u32);
        let texels: Vec<f32> = (0..w * h)
            .flat_map(|i| [((i * 7919) % 13) as f32; 3])
            .collect();
        let image = Image::from_linear("large", w, h, texels).unwrap();
        assert_cells_follow_the_filtered_image(&image);
    }

    #[test]
    fn picks_land_in_proportion_and_leave_a_uniform_remainder() {
        let texels: Vec<f32> = (0..6).flat_map(|i| [(i * i) as f32; 3]).collect();
        let image = Image::from_linear("squares", 3, 2, texels).unwrap();
        let d = Distribution::new(&image);
        let cells = d.width * d.height;
        let m = 400;
        let mut counts = vec![0usize; cells];
        let mut remainder = (0.0, 0.0);
        for k in 0..m {
            for j in 0..m {
                let (u1, u2) = ((k as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                let ((x, y), (across, down)) = d.pick(u1, u2);
                assert!((0.0..1.0).contains(&across) && (0.0..1.0).contains(&down));
                counts[d.width * y + x] += 1;
                remainder.0 += across as f64 / (m * m) as f64;
                remainder.1 += down as f64 / (m * m) as f64;
            }
        }
        for (i, (count, density)) in counts.iter().zip(&d.density).enumerate() {
            let expected = *density as f64 / cells as f64;
            assert!(
                (*count as f64 / (m * m) as f64 - expected).abs() < 2e-3,
                "cell {i}"
            );
        }
        assert!((remainder.0 - 0.5).abs() < 1e-2 && (remainder.1 - 0.5).abs() < 1e-2);
    }

    /// Inversion is monotone: larger first numbers pick rows no higher up, larger second
    /// numbers (in one row) cells no further left, so stratified numbers stay stratified;
    /// and a cell of weight 0 is never picked (what an alias table guarantees neither of).
    #[test]
    fn picks_are_monotone_and_skip_empty_cells() {
        // Texel columns 0..3 and rows 1..4 black: the filter leaves the cells of texel column
        // 1 and texel row 2 weightless.
        let (w, h) = (8usize, 6usize);
        let black = |i: usize| i % w < 3 || (1..4).contains(&(i / w));
        let texels: Vec<f32> = (0..w * h)
            .flat_map(|i| [if black(i) { 0.0 } else { (i % 5) as f32 + 1.0 }; 3])
            .collect();
        let image = Image::from_linear("gaps", w as u32, h as u32, texels).unwrap();
        let d = Distribution::new(&image);
        let cw = d.width;
        assert!(d.density[4 * cw + 9] == 0.0 && d.density[2 * cw + 2] == 0.0);
        let m = 997;
        let mut last_y = 0;
        for k in 0..m {
            let u1 = k as f32 / m as f32;
            let ((_, y), _) = d.pick(u1, 0.5);
            assert!(y >= last_y, "u1 {u1}: row {y} after {last_y}");
            last_y = y;
            let mut last_x = 0;
            for j in 0..m {
                let u2 = j as f32 / m as f32;
                let ((x, row), _) = d.pick(u1, u2);
                assert_eq!(row, y);
                assert!(x >= last_x && d.density[row * cw + x] > 0.0, "({x}, {row})");
                last_x = x;
                // What the guided walk finds is the last value at most u2, as a scan finds it.
                let cdf: Vec<f32> = d.columns.values(row, cw).collect();
                assert_eq!(x, cdf[..cw].iter().rposition(|&c| c <= u2).unwrap());
            }
        }
    }

    /// Numbers at either end pick the first and last slots of weight, never one of weight 0
    /// before or after them (nor one whose value rounds to 1).
    #[test]
    fn picks_at_the_ends_skip_empty_slots() {
        let table = |weights: &[f64]| {
            let mut t = Cdfs::default();
            t.push(weights);
            t
        };
        let gaps = table(&[0.0, 0.0, 1.0, 2.0, 0.0, 0.0]);
        assert_eq!(gaps.pick(0, 6, 0.0).0, 2);
        assert_eq!(gaps.pick(0, 6, ONE_BELOW).0, 3);
        let tiny = table(&[1.0, 1e-12, 0.0]);
        assert_eq!(tiny.pick(0, 3, ONE_BELOW).0, 0, "a weight lost to rounding");
        assert_eq!(tiny.pick(0, 3, 0.0).0, 0);
    }
}
