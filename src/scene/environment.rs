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
/// angle a texel spans), sampled with alias tables (Walker 1977;
/// Vose 1991): the first number picks a row from the rows' table, the second a column from that
/// row's table, each in constant time, and their remainders place the direction across the
/// texel. (One table over all texels would ask one f32 number to tell apart more texels than
/// its 24 bits can in a large image, and leave no bits to place the direction.) Built in f64,
/// stored in f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    /// The rows' alias table.
    pub rows: AliasTable,
    /// Per row, its columns' alias table, row by row (`alias` counts columns within the row).
    pub columns: AliasTable,
    /// Per texel, row by row: its density in image coordinates (s, t) in [0, 1]^2, its share
    /// of the whole times the number of texels.
    pub density: Vec<f32>,
    /// The integral of luminance over directions (steradians), strength 1.
    pub integral: f64,
}

/// Walker's alias tables, one or several side by side.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct AliasTable {
    /// Per slot: the chance that a pick landing on it keeps it,
    pub keep: Vec<f32>,
    /// else the slot (of its own table) it passes to.
    pub alias: Vec<u32>,
}

impl AliasTable {
    /// The slot of the table of `n` slots starting at `start` that `u` in [0, 1) picks, and
    /// `u`'s remainder, uniform in [0, 1) again (the kernel's `alias_pick` does the same f32
    /// arithmetic).
    #[inline]
    pub fn pick(&self, start: usize, n: usize, u: f32) -> (usize, f32) {
        let scaled = u * n as f32;
        let i = (scaled as usize).min(n - 1);
        let r = scaled - i as f32;
        let keep = self.keep[start + i];
        if r < keep {
            (i, (r / keep).min(ONE_BELOW))
        } else {
            let rest = ((r - keep) / (1.0 - keep)).clamp(0.0, ONE_BELOW);
            ((self.alias[start + i] as usize).min(n - 1), rest)
        }
    }

    /// Appends the table of `weights` (Vose's construction, in f64; uniform if they are all 0).
    fn push(&mut self, weights: &[f64]) {
        let n = weights.len();
        let total: f64 = weights.iter().sum();
        let mut left: Vec<f64> = if total > 0.0 {
            weights.iter().map(|w| w * n as f64 / total).collect()
        } else {
            vec![1.0; n]
        };
        let start = self.keep.len();
        self.keep.extend(std::iter::repeat_n(1.0f32, n));
        self.alias.extend(0..n as u32);
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| left[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            self.keep[start + s] = left[s] as f32;
            self.alias[start + s] = l as u32;
            left[l] -= 1.0 - left[s];
            if left[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What remains is 1 up to rounding: kept.
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
        let total: f64 = weights.iter().sum();
        let row_sums: Vec<f64> = weights.chunks_exact(w).map(|r| r.iter().sum()).collect();
        let mut rows = AliasTable::default();
        rows.push(&row_sums);
        let mut columns = AliasTable::default();
        for row in weights.chunks_exact(w) {
            columns.push(row);
        }
        let n = (w * h) as f64;
        Distribution {
            rows,
            columns,
            density: weights.iter().map(|x| (x * n / total) as f32).collect(),
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
        let (x, across) = self.columns.pick(y * width, width, u2);
        ((x, y), (across, down))
    }
}

/// The largest f32 below 1.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_alias_tables_give_each_texel_its_share() {
        // Texels weighted 1..=12 times sin(theta) of their row: each texel's chance, summed
        // over every pair of slots that can pick it, is its share.
        let texels: Vec<f32> = (0..12).flat_map(|i| [1.0 + i as f32; 3]).collect();
        let image = Image::from_linear("ramp", 4, 3, texels).unwrap();
        let d = Distribution::new(&image);
        let chances = |t: &AliasTable, start: usize, n: usize| {
            let mut chance = vec![0.0f64; n];
            for i in 0..n {
                chance[i] += t.keep[start + i] as f64 / n as f64;
                chance[t.alias[start + i] as usize] += (1.0 - t.keep[start + i] as f64) / n as f64;
            }
            chance
        };
        let rows = chances(&d.rows, 0, 3);
        for (y, row) in rows.iter().enumerate() {
            for (x, column) in chances(&d.columns, 4 * y, 4).iter().enumerate() {
                let texel = row * column * 12.0;
                assert!(
                    (texel - d.density[4 * y + x] as f64).abs() < 1e-5,
                    "({x}, {y})"
                );
            }
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
}
