//! What escaped rays see (twin: `shaders/background.wgsl`).

use crate::scene::Background;
use crate::shared::constants::SKY_ZENITH;
use glam::Vec3;

/// Radiance arriving from the environment along unit direction `dir`.
#[inline]
pub fn background(bg: &Background, dir: Vec3) -> Vec3 {
    match *bg {
        Background::Constant(c) => c,
        Background::Sky => {
            let t = 0.5 * (dir.y + 1.0);
            (1.0 - t) * Vec3::ONE + t * Vec3::from(SKY_ZENITH)
        }
        Background::Environment(ref env) => super::environment::radiance(env, dir),
    }
}
