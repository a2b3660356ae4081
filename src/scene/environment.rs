//! An environment light: an equirectangular HDR image around the scene (looked up and sampled
//! by `src/cpu/environment.rs`, twin `shaders/environment.wgsl`), and the tables both
//! backends sample it with.
//!
//! Mapping: a direction's longitude and latitude as `sphere_uv` gives them (u from -x round
//! through +z..., v from the south pole), after turning the direction by -`rotate_y`: image
//! column u, image row 1 - v (row 0 is the sky straight up).

use super::image::Image;

/// `background = { image = "sky.hdr", strength = 1, rotate_y = 0 }`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Environment {
    pub image: &'static Image,
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
    pub fn new(
        image: &'static Image,
        strength: f32,
        rotate_y_degrees: f32,
    ) -> Result<Self, String> {
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
    pub fn distribution(&self) -> &'static Distribution {
        self.image
            .sampling
            .get_or_init(|| Distribution::new(self.image))
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

/// A piecewise-constant density over the image, texel by texel, in proportion to the mean over
/// the texel of the luminance as looked up (bilinearly filtered) times sin(theta) (the solid
/// angle a texel spans), sampled by inverting cumulative distributions: the first number picks
/// a row from the rows' CDF, the second a column from that row's, and their remainders place
/// the direction across the texel. Inversion is monotone, so stratified numbers (Sobol points)
/// give stratified directions; an alias table would scatter neighbouring numbers over distant
/// texels and lose that (pbrt-v4 and Mitsuba invert too). (One table over all texels would ask
/// one f32 number to tell apart more texels than its 24 bits can in a large image, and leave no
/// bits to place the direction.) Built in f64, stored in f32; each texel's density is the
/// product of its row's and column's steps of the stored CDFs, so that it is the chance with
/// which the picks land on it.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    /// The rows' CDF (height + 1 values).
    pub rows: Cdfs,
    /// Per row, its columns' CDF (width + 1 values each), row by row.
    pub columns: Cdfs,
    /// Per texel, row by row: its density in image coordinates (s, t) in [0, 1]^2, its share
    /// of the whole times the number of texels.
    pub density: Vec<f32>,
    /// The integral of luminance over directions (steradians), strength 1.
    pub integral: f64,
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
        let lum: Vec<f64> = (0..w * h)
            .map(|i| {
                let t = image.texel((i % w) as u32, (i / w) as u32);
                luminance(t.x, t.y, t.z)
            })
            .collect();
        // Over each texel, the mean of the radiance as it is looked up, filtered bilinearly
        // (wrapping across, clamped at the poles): 1/8, 3/4, 1/8 of the texel and its
        // neighbours on each axis. A texel beside a small bright sun receives some of the sun's
        // light through the filter; weighed by its own value alone it would be picked too
        // rarely for that light, and each pick would be a firefly.
        const SIDE: f64 = 0.125;
        const CENTRE: f64 = 0.75;
        let across: Vec<f64> = (0..w * h)
            .map(|i| {
                let (x, row) = (i % w, i - i % w);
                let (left, right) = ((x + w - 1) % w, (x + 1) % w);
                SIDE * lum[row + left] + CENTRE * lum[i] + SIDE * lum[row + right]
            })
            .collect();
        let mut weights = Vec::with_capacity(w * h);
        for y in 0..h {
            let sin_theta = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
            let (up, down) = (y.saturating_sub(1), (y + 1).min(h - 1));
            for x in 0..w {
                let filtered = SIDE * across[up * w + x]
                    + CENTRE * across[y * w + x]
                    + SIDE * across[down * w + x];
                weights.push(filtered * sin_theta);
            }
        }
        let total: f64 = weights.iter().sum();
        let texel_solid_angle =
            2.0 * std::f64::consts::PI / w as f64 * std::f64::consts::PI / h as f64;
        let integral = total * texel_solid_angle;
        if !(total > 0.0) {
            weights.fill(1.0); // nothing to favour: uniform over the image
        }
        let row_sums: Vec<f64> = weights.chunks_exact(w).map(|r| r.iter().sum()).collect();
        let mut rows = Cdfs::default();
        rows.push(&row_sums);
        let mut columns = Cdfs::default();
        for row in weights.chunks_exact(w) {
            columns.push(row);
        }
        let n = (w * h) as f64;
        let density = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                (rows.step(0, h, y) * columns.step(y, w, x) * n) as f32
            })
            .collect();
        Distribution {
            rows,
            columns,
            density,
            integral,
        }
    }

    /// The texel (x, y) that (u1, u2) in [0, 1)^2 pick, and where across it (in [0, 1)^2).
    #[inline]
    pub fn pick(
        &self,
        width: usize,
        height: usize,
        u1: f32,
        u2: f32,
    ) -> ((usize, usize), (f32, f32)) {
        let (y, down) = self.rows.pick(0, height, u1);
        let (x, across) = self.columns.pick(y, width, u2);
        ((x, y), (across, down))
    }
}

/// The largest f32 below 1.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cdfs_give_each_texel_its_share() {
        // Texels weighted 1..=12 times sin(theta) of their row: each table rises from 0 to 1
        // in order.
        let texels: Vec<f32> = (0..12).flat_map(|i| [1.0 + i as f32; 3]).collect();
        let image = Image::from_linear("ramp", 4, 3, texels).unwrap();
        let d = Distribution::new(&image);
        let tables = std::iter::once(d.rows.values(0, 3).collect::<Vec<_>>())
            .chain((0..3).map(|row| d.columns.values(row, 4).collect()));
        for (table, n) in tables.zip([3, 4, 4, 4]) {
            assert_eq!(table.len(), n + 1);
            assert_eq!((table[0], table[n]), (0.0, 1.0));
            assert!(table.windows(2).all(|w| w[0] < w[1]), "{table:?}");
        }
        // Filtered, a ramp keeps its values inside; at the top row the pole's clamp leaves
        // texel (1, 0) 7/8 of its 2 and 1/8 of the 6 below: 2.5.
        let middle = d.density[5] / d.density[1];
        assert!((middle - 6.0 / 2.5 / (std::f32::consts::PI / 6.0).sin()).abs() < 1e-4);
        // The integral of a white image is 4 pi, up to the midpoint rule's error.
        let white = Image::from_linear("white", 8, 4, vec![1.0; 96]).unwrap();
        let d = Distribution::new(&white);
        assert!((d.integral / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.05);
        // A black image is sampled uniformly and has no power.
        let black = Image::from_linear("black", 2, 2, vec![0.0; 12]).unwrap();
        let d = Distribution::new(&black);
        assert_eq!(d.density, vec![1.0; 4]);
        assert_eq!(d.integral, 0.0);
    }

    /// A bright texel in a black image shares its weight with its neighbours as the bilinear
    /// filter shares its light: each side 1/8 of the texel's 3/4 on an axis (wrapping across),
    /// nothing two texels away.
    #[test]
    fn a_bright_texel_shares_its_weight_with_its_neighbours() {
        let (w, h) = (8usize, 5usize);
        for bright in [(3, 2), (0, 2)] {
            let texels: Vec<f32> = (0..w * h)
                .flat_map(|i| [if (i % w, i / w) == bright { 1.0 } else { 0.0 }; 3])
                .collect();
            let image = Image::from_linear("sun", w as u32, h as u32, texels).unwrap();
            let d = Distribution::new(&image);
            let at = |x: usize, y: usize| d.density[y * w + x] as f64;
            let (x, y) = bright;
            let (left, right) = ((x + w - 1) % w, (x + 1) % w);
            let centre = at(x, y);
            for side in [left, right] {
                assert!(
                    (at(side, y) / centre - 1.0 / 6.0).abs() < 1e-6,
                    "{bright:?}"
                );
            }
            let sin = |row: usize| (std::f64::consts::PI * (row as f64 + 0.5) / h as f64).sin();
            let below = at(x, y + 1) / centre;
            assert!(
                (below - sin(y + 1) / sin(y) / 6.0).abs() < 1e-6,
                "{bright:?}"
            );
            assert_eq!(at((x + 2) % w, y), 0.0);
            assert_eq!(at(x, y + 2), 0.0);
        }
    }

    #[test]
    fn picks_land_in_proportion_and_leave_a_uniform_remainder() {
        let texels: Vec<f32> = (0..6).flat_map(|i| [(i * i) as f32; 3]).collect();
        let image = Image::from_linear("squares", 3, 2, texels).unwrap();
        let d = Distribution::new(&image);
        let m = 400;
        let mut counts = [0usize; 6];
        let mut remainder = (0.0, 0.0);
        for k in 0..m {
            for j in 0..m {
                let (u1, u2) = ((k as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                let ((x, y), (across, down)) = d.pick(3, 2, u1, u2);
                assert!((0.0..1.0).contains(&across) && (0.0..1.0).contains(&down));
                counts[3 * y + x] += 1;
                remainder.0 += across as f64 / (m * m) as f64;
                remainder.1 += down as f64 / (m * m) as f64;
            }
        }
        for (i, (count, density)) in counts.iter().zip(&d.density).enumerate() {
            let expected = *density as f64 / 6.0;
            assert!(
                (*count as f64 / (m * m) as f64 - expected).abs() < 2e-3,
                "texel {i}"
            );
        }
        assert!((remainder.0 - 0.5).abs() < 1e-2 && (remainder.1 - 0.5).abs() < 1e-2);
    }

    /// Inversion is monotone: larger first numbers pick rows no higher up, larger second
    /// numbers (in one row) columns no further left, so stratified numbers stay stratified;
    /// and a texel of weight 0 is never picked (what an alias table guarantees neither of).
    #[test]
    fn picks_are_monotone_and_skip_empty_texels() {
        // Columns 0..3 and rows 1..4 black: the filter leaves column 1 and row 2 weightless.
        let (w, h) = (8usize, 6usize);
        let black = |i: usize| i % w < 3 || (1..4).contains(&(i / w));
        let texels: Vec<f32> = (0..w * h)
            .flat_map(|i| [if black(i) { 0.0 } else { (i % 5) as f32 + 1.0 }; 3])
            .collect();
        let image = Image::from_linear("gaps", w as u32, h as u32, texels).unwrap();
        let d = Distribution::new(&image);
        assert!(d.density[2 * w + 4] == 0.0 && d.density[w + 1] == 0.0);
        let m = 997;
        let mut last_y = 0;
        for k in 0..m {
            let u1 = k as f32 / m as f32;
            let ((_, y), _) = d.pick(w, h, u1, 0.5);
            assert!(y >= last_y, "u1 {u1}: row {y} after {last_y}");
            last_y = y;
            let mut last_x = 0;
            for j in 0..m {
                let u2 = j as f32 / m as f32;
                let ((x, row), _) = d.pick(w, h, u1, u2);
                assert_eq!(row, y);
                assert!(x >= last_x && d.density[row * w + x] > 0.0, "({x}, {row})");
                last_x = x;
                // What the guided walk finds is the last value at most u2, as a scan finds it.
                let cdf: Vec<f32> = d.columns.values(row, w).collect();
                assert_eq!(x, cdf[..w].iter().rposition(|&c| c <= u2).unwrap());
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
