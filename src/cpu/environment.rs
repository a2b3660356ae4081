//! The environment light (twin: `shaders/environment.wgsl`): what an escaped ray sees, and
//! directions sampled in proportion to filtered luminance above the sky's mean x sin(theta) (see
//! `assets::environment`), with their solid-angle pdf.

use crate::assets::environment::Environment;
use crate::assets::image_lookup::bilinear;
use crate::shared::angles;
use glam::Vec3;
use std::f32::consts::PI;

/// `dir` turned by -rotate_y: the image's own frame.
#[inline]
fn to_local(env: &Environment, dir: Vec3) -> Vec3 {
    let [cos, sin] = env.rotation;
    Vec3::new(cos * dir.x - sin * dir.z, dir.y, sin * dir.x + cos * dir.z)
}

/// Image coordinates (s across, t down) of unit `local` direction.
#[inline]
fn image_coordinates(local: Vec3) -> (f32, f32) {
    let s = (angles::atan2(-local.z, local.x) + PI) / (2.0 * PI);
    let t = angles::acos(local.y) / PI;
    (s, t)
}

/// The image filtered at (s, t), times the strength. Rows do not wrap over the poles: t stays
/// within the first and last rows' centres.
#[inline]
fn radiance_at(env: &Environment, s: f32, t: f32) -> Vec3 {
    let h = env.image.height as f32;
    bilinear(&env.image, s, t.clamp(0.5 / h, 1.0 - 0.5 / h)) * env.strength
}

/// Radiance arriving from the environment along unit direction `dir`.
#[inline]
pub fn radiance(env: &Environment, dir: Vec3) -> Vec3 {
    let (s, t) = image_coordinates(to_local(env, dir));
    radiance_at(env, s, t)
}

/// A direction sampled from the environment's distribution with two uniform numbers, and its
/// solid-angle pdf; `None` at the poles (where the pdf would be infinite). The numbers pick
/// the row and the column of a cell (see `Distribution::pick`), their remainders place the
/// direction across the cell.
#[inline]
pub fn sample(env: &Environment, u1: f32, u2: f32) -> Option<(Vec3, f32)> {
    let d = env.distribution();
    let (w, h) = (d.width, d.height);
    let ((x, y), (across, down)) = d.pick(u1, u2);
    let s = (x as f32 + across) / w as f32;
    let t = (y as f32 + down) / h as f32;
    let (sin_theta, cos_theta) = angles::sin_cos_pi(t);
    if !(sin_theta > 0.0) {
        return None;
    }
    let (sin_phi, cos_phi) = angles::sin_cos_pi(2.0 * s - 1.0);
    let local = Vec3::new(sin_theta * cos_phi, cos_theta, -sin_theta * sin_phi);
    let [cos, sin] = env.rotation;
    let dir = Vec3::new(
        cos * local.x + sin * local.z,
        local.y,
        -sin * local.x + cos * local.z,
    );
    Some((dir, d.density[y * w + x] / (2.0 * PI * PI * sin_theta)))
}

/// The solid-angle pdf with which [`sample`] picks unit direction `dir`.
#[inline]
pub fn pdf(env: &Environment, dir: Vec3) -> f32 {
    let local = to_local(env, dir);
    let (s, t) = image_coordinates(local);
    pdf_at(env, local, s, t)
}

/// [`radiance`] and [`pdf`] together, the direction's image coordinates found once (what an
/// escaped ray needs for its MIS weight).
#[inline]
pub fn radiance_and_pdf(env: &Environment, dir: Vec3) -> (Vec3, f32) {
    let local = to_local(env, dir);
    let (s, t) = image_coordinates(local);
    (radiance_at(env, s, t), pdf_at(env, local, s, t))
}

/// The pdf of the local direction `local`, at image coordinates (s, t): its cell's density
/// over the solid angle's 2 pi^2 sin(theta).
#[inline]
fn pdf_at(env: &Environment, local: Vec3, s: f32, t: f32) -> f32 {
    let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    let d = env.distribution();
    let (width, height) = (d.width, d.height);
    let x = ((s * width as f32).floor().max(0.0) as usize).min(width - 1);
    let y = ((t * height as f32).floor().max(0.0) as usize).min(height - 1);
    let density = d.density[y * width + x];
    density / (2.0 * PI * PI * sin_theta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assets::image::Image;

    fn environment(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> Environment {
        let mut texels = Vec::new();
        for y in 0..height {
            for x in 0..width {
                texels.extend([f(x, y); 3]);
            }
        }
        let image = Image::from_linear("test", width, height, texels)
            .unwrap()
            .shared();
        Environment::new(image, 1.0, 30.0).unwrap()
    }

    #[test]
    fn samples_land_where_their_pdf_says() {
        let env = environment(8, 4, |x, y| 1.0 + (x * 3 + y) as f32);
        for (u1, u2) in [(0.1, 0.2), (0.51, 0.5), (0.93, 0.07), (0.3, 0.999)] {
            let (dir, pdf) = sample(&env, u1, u2).unwrap();
            assert!((dir.length() - 1.0).abs() < 1e-5);
            assert!(
                (pdf / super::pdf(&env, dir) - 1.0).abs() < 1e-3,
                "{u1} {u2}"
            );
        }
    }

    #[test]
    fn the_texel_straight_up_is_the_top_row() {
        // Only the top row is bright: straight up sees it, straight down does not.
        let env = environment(4, 4, |_, y| if y == 0 { 1.0 } else { 0.0 });
        assert!((radiance(&env, Vec3::Y) - Vec3::ONE).length() < 1e-6);
        assert_eq!(radiance(&env, Vec3::NEG_Y), Vec3::ZERO);
        // And sampling only ever picks the top row.
        let (dir, _) = sample(&env, 0.6, 0.4).unwrap();
        assert!(dir.y > (PI / 4.0).cos());
    }
}
