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

/// A piecewise-constant density over the image, texel by texel, in proportion to luminance
/// times sin(theta) (the solid angle a texel spans), sampled with an alias table (Walker 1977;
/// Vose 1991): one number picks a texel in constant time, whatever the image's size, and its
/// remainder places the direction across the texel. Built in f64, stored in f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    /// Per texel, row by row: the chance that a pick landing on it keeps it,
    pub keep: Vec<f32>,
    /// else the texel it passes to;
    pub alias: Vec<u32>,
    /// and its density in image coordinates (s, t) in [0, 1]^2: its share of the whole times
    /// the number of texels.
    pub density: Vec<f32>,
    /// The integral of luminance over directions (steradians), strength 1.
    pub integral: f64,
}

impl Distribution {
    pub fn new(image: &Image) -> Self {
        let (w, h) = (image.width as usize, image.height as usize);
        let mut weights = Vec::with_capacity(w * h);
        for y in 0..h {
            let sin_theta = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
            for x in 0..w {
                let t = image.texel(x as u32, y as u32);
                weights.push(luminance(t.x, t.y, t.z) * sin_theta);
            }
        }
        let total: f64 = weights.iter().sum();
        let texel_solid_angle =
            2.0 * std::f64::consts::PI / w as f64 * std::f64::consts::PI / h as f64;
        let integral = total * texel_solid_angle;
        if !(total > 0.0) {
            weights.fill(1.0); // nothing to favour: uniform over the image
        }
        let (keep, alias, density) = alias_table(&weights);
        Distribution {
            keep,
            alias,
            density,
            integral,
        }
    }

    /// The texel that `u` in [0, 1) picks, and `u`'s remainder, uniform in [0, 1) again (the
    /// kernel's `environment_pick` does the same f32 arithmetic).
    #[inline]
    pub fn pick(&self, u: f32) -> (usize, f32) {
        let n = self.keep.len();
        let scaled = u * n as f32;
        let i = (scaled as usize).min(n - 1);
        let r = scaled - i as f32;
        if r < self.keep[i] {
            (i, (r / self.keep[i]).min(ONE_BELOW))
        } else {
            let rest = ((r - self.keep[i]) / (1.0 - self.keep[i])).clamp(0.0, ONE_BELOW);
            (self.alias[i] as usize, rest)
        }
    }
}

/// The largest f32 below 1.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// Walker's alias table of `weights` (Vose's construction, in f64): (keep, alias, density).
fn alias_table(weights: &[f64]) -> (Vec<f32>, Vec<u32>, Vec<f32>) {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    let scaled: Vec<f64> = weights.iter().map(|w| w * n as f64 / total).collect();
    let density = scaled.iter().map(|&d| d as f32).collect();
    let mut keep = vec![1.0f32; n];
    let mut alias: Vec<u32> = (0..n as u32).collect();
    let mut left = scaled.clone();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| left[i] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        keep[s] = left[s] as f32;
        alias[s] = l as u32;
        left[l] -= 1.0 - left[s];
        if left[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What remains is 1 up to rounding: kept.
    (keep, alias, density)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_alias_table_gives_each_texel_its_share() {
        // Texels weighted 1..=12 times sin(theta) of their row: each texel's chance, summed
        // over every slot that can pick it, is its share.
        let texels: Vec<f32> = (0..12).flat_map(|i| [1.0 + i as f32; 3]).collect();
        let image = Image::from_linear("ramp", 4, 3, texels).unwrap();
        let d = Distribution::new(&image);
        let n = d.keep.len();
        let mut chance = vec![0.0f64; n];
        for i in 0..n {
            chance[i] += d.keep[i] as f64 / n as f64;
            chance[d.alias[i] as usize] += (1.0 - d.keep[i] as f64) / n as f64;
        }
        for (i, (chance, density)) in chance.iter().zip(&d.density).enumerate() {
            assert!(
                (chance * n as f64 - *density as f64).abs() < 1e-5,
                "texel {i}"
            );
        }
        let middle = d.density[5] / d.density[1];
        assert!((middle - 6.0 / 2.0 / (std::f32::consts::PI / 6.0).sin()).abs() < 1e-4);
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

    #[test]
    fn picks_land_in_proportion_and_leave_a_uniform_remainder() {
        let texels: Vec<f32> = (0..6).flat_map(|i| [(i * i) as f32; 3]).collect();
        let image = Image::from_linear("squares", 3, 2, texels).unwrap();
        let d = Distribution::new(&image);
        let m = 60_000;
        let mut counts = [0usize; 6];
        let mut remainder = 0.0;
        for k in 0..m {
            let (i, r) = d.pick((k as f32 + 0.5) / m as f32);
            assert!((0.0..1.0).contains(&r));
            counts[i] += 1;
            remainder += r as f64 / m as f64;
        }
        assert_eq!(counts[0], 0);
        for (i, (count, density)) in counts.iter().zip(&d.density).enumerate() {
            let expected = *density as f64 / 6.0;
            assert!(
                (*count as f64 / m as f64 - expected).abs() < 1e-3,
                "texel {i}"
            );
        }
        assert!((remainder - 0.5).abs() < 1e-3);
    }
}
