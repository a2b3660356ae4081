//! Primary rays (twin: `shaders/camera.wgsl`).

use crate::options::RenderOptions;
use crate::scene::flat::CameraFrame;
use crate::shared::ray::Ray;
use crate::shared::sampler::Sampler;
use crate::shared::warp::unit_disk;

/// A ray through a uniformly jittered point of pixel (x, y): pixel x covers [x, x+1)/width of the
/// film, row 0 is the top. Draws 2 random numbers, plus 2 for the lens when it has an aperture.
#[inline]
pub fn generate_ray(
    cam: &CameraFrame,
    opts: &RenderOptions,
    x: u32,
    y: u32,
    sampler: &mut Sampler,
) -> Ray {
    let s = (x as f32 + sampler.next_f32()) / opts.width as f32;
    let t = (y as f32 + sampler.next_f32()) / opts.height as f32;
    // Relative to the camera, so the direction's precision does not depend on where it is.
    let mut to_target = cam.to_upper_left + s * cam.horizontal - t * cam.vertical;
    let mut origin = cam.origin;
    if cam.lens_radius > 0.0 {
        sampler.begin();
        let (dx, dy) = unit_disk(sampler.next_f32(), sampler.next_f32());
        let on_lens = cam.lens_radius * (dx * cam.right + dy * cam.up);
        origin += on_lens;
        to_target -= on_lens;
    }
    Ray {
        origin,
        dir: to_target.normalize(),
    }
}
