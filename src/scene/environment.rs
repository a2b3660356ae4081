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
/// times sin(theta) (the solid angle a texel spans): rows first (the marginal), then the
/// column within the row (the conditional), as cumulative tables rounded to f32 from f64 sums.
/// The density of texel (x, y) in image coordinates (s, t) in [0, 1]^2 is
/// `(rows[y + 1] - rows[y]) * height * (columns[y][x + 1] - columns[y][x]) * width`: exactly
/// the density sampling by inversion of these f32 tables gives.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    /// `height + 1` values from 0 to 1.
    pub rows: Vec<f32>,
    /// Per row, `width + 1` values from 0 to 1.
    pub columns: Vec<f32>,
    /// The integral of luminance over directions (steradians), strength 1.
    pub integral: f64,
}

impl Distribution {
    pub fn new(image: &Image) -> Self {
        let (w, h) = (image.width as usize, image.height as usize);
        let mut columns = Vec::with_capacity(h * (w + 1));
        let mut row_sums = Vec::with_capacity(h);
        for y in 0..h {
            let sin_theta = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
            let weights: Vec<f64> = (0..w)
                .map(|x| {
                    let t = image.texel(x as u32, y as u32);
                    luminance(t.x, t.y, t.z) * sin_theta
                })
                .collect();
            let sum: f64 = weights.iter().sum();
            cumulative(&weights, sum, &mut columns);
            row_sums.push(sum);
        }
        let total: f64 = row_sums.iter().sum();
        let mut rows = Vec::with_capacity(h + 1);
        cumulative(&row_sums, total, &mut rows);
        let texel_solid_angle =
            2.0 * std::f64::consts::PI / w as f64 * std::f64::consts::PI / h as f64;
        Distribution {
            rows,
            columns,
            integral: total * texel_solid_angle,
        }
    }
}

/// Appends the cumulative shares of `weights` (summing to `sum`): 0 first, exactly 1 last;
/// uniform where nothing has weight.
fn cumulative(weights: &[f64], sum: f64, out: &mut Vec<f32>) {
    let n = weights.len();
    out.push(0.0);
    let mut running = 0.0;
    for (i, w) in weights.iter().enumerate() {
        running += w;
        let share = if sum > 0.0 {
            running / sum
        } else {
            (i + 1) as f64 / n as f64
        };
        out.push(if i + 1 == n { 1.0 } else { share as f32 });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_cumulative_and_weigh_by_solid_angle() {
        // A uniform white image: rows weighted by sin(theta), columns uniform.
        let image = Image::from_linear("white", 4, 3, vec![1.0; 36]).unwrap();
        let d = Distribution::new(&image);
        assert_eq!(d.rows.len(), 4);
        assert_eq!(d.columns.len(), 3 * 5);
        assert_eq!((d.rows[0], d.rows[3]), (0.0, 1.0));
        let middle = d.rows[2] - d.rows[1];
        let top = d.rows[1] - d.rows[0];
        assert!((middle / top - 1.0 / (std::f32::consts::PI / 6.0).sin()).abs() < 1e-5);
        for row in d.columns.chunks(5) {
            assert_eq!(row, &[0.0, 0.25, 0.5, 0.75, 1.0]);
        }
        // The integral of 1 over the sphere is 4 pi, up to the midpoint rule's error.
        assert!((d.integral / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.1);
        // A black image is sampled uniformly and has no power.
        let black = Image::from_linear("black", 2, 2, vec![0.0; 12]).unwrap();
        let d = Distribution::new(&black);
        assert_eq!(d.rows, vec![0.0, 0.5, 1.0]);
        assert_eq!(d.integral, 0.0);
    }
}
