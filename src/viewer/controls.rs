//! The viewer's camera moves: what mouse drags, the wheel and keys do to a scene's camera, and
//! the camera as the `[camera]` table of a scene file. Window events and a test's scripted input
//! both arrive as an [`Input`], and take the same path from there.

use crate::scene::Camera;
use glam::{DVec3, Vec3};

/// One thing the user did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// A drag with the left button: orbit the look-at point by (dx, dy) window pixels.
    Orbit(f32, f32),
    /// A drag with the right button (or shift and the left): move the camera and its look-at
    /// point across the view by (dx, dy) window pixels.
    Pan(f32, f32),
    /// Wheel steps: positive moves toward the look-at point.
    Dolly(f32),
    /// WASD/QE: forward, right and up steps in the camera's frame.
    Fly(Vec3),
    /// Write the film (S).
    Save,
    /// Print the camera as a `[camera]` table (C).
    PrintCamera,
    /// Start the film again (R).
    Restart,
    /// Read the scene again, as its files are now (F5).
    Reload,
    /// Show the film denoised, or the live film again (N).
    Denoise,
    /// Quit (Esc).
    Quit,
}

/// Radians of orbit per window pixel dragged.
const ORBIT_PER_PIXEL: f64 = 0.005;
/// How much closer one wheel step brings the camera (as a fraction of the distance).
const DOLLY_PER_STEP: f64 = 0.1;
/// A fly step, as a fraction of the distance to the look-at point.
const FLY_PER_STEP: f64 = 0.05;

/// The camera after `input`, a move (None for inputs that are not moves); `height` is the
/// window's height in pixels, which a pan's pixels are measured against.
pub fn moved(camera: &Camera, input: Input, height: u32) -> Option<Camera> {
    let from = camera.look_from.as_dvec3();
    let at = camera.look_at.as_dvec3();
    let world_up = camera.up.as_dvec3().normalize();
    let offset = from - at;
    let distance = offset.length();
    let forward = -offset / distance;
    let right = forward.cross(world_up).normalize();
    let up = right.cross(forward);
    let (look_from, look_at) = match input {
        Input::Orbit(dx, dy) => {
            let yaw = -dx as f64 * ORBIT_PER_PIXEL;
            // Pitch stops short of the poles, where the frame would flip about `up`.
            let elevation = (offset.dot(world_up) / distance).clamp(-1.0, 1.0).asin();
            let limit = 89f64.to_radians();
            let pitch = (elevation + dy as f64 * ORBIT_PER_PIXEL).clamp(-limit, limit) - elevation;
            let turned = rotate(offset, world_up, yaw);
            let axis = rotate(right, world_up, yaw);
            (at + rotate(turned, axis, -pitch), at)
        }
        Input::Pan(dx, dy) => {
            // A pixel at the look-at point's distance spans 2 tan(fov / 2) distance / height.
            let half_fov = (camera.vfov_degrees as f64).to_radians() * 0.5;
            let per_pixel = 2.0 * half_fov.tan() * distance / height.max(1) as f64;
            let shift = (-right * dx as f64 + up * dy as f64) * per_pixel;
            (from + shift, at + shift)
        }
        Input::Dolly(steps) => {
            let scale = (1.0 - DOLLY_PER_STEP).powf(steps as f64);
            (at + offset * scale.max(1e-6), at)
        }
        Input::Fly(v) => {
            let step = (forward * v.x as f64 + right * v.y as f64 + up * v.z as f64)
                * (distance * FLY_PER_STEP);
            (from + step, at + step)
        }
        Input::Save
        | Input::PrintCamera
        | Input::Restart
        | Input::Reload
        | Input::Denoise
        | Input::Quit => {
            return None;
        }
    };
    let camera = Camera {
        look_from: look_from.as_vec3(),
        look_at: look_at.as_vec3(),
        ..*camera
    };
    // A move that would put the camera on its look-at point (or overflow) is not made.
    let valid = (camera.look_from - camera.look_at).length() > 0.0
        && camera.look_from.is_finite()
        && camera.look_at.is_finite();
    valid.then_some(camera)
}

/// `v` rotated by `angle` radians about the unit `axis` (Rodrigues).
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (sin, cos) = angle.sin_cos();
    v * cos + axis.cross(v) * sin + axis * axis.dot(v) * (1.0 - cos)
}

/// `camera` as a scene file's `[camera]` table: pasted into the scene file, it renders this
/// view exactly (each number written so that it reads back as the same f32).
pub fn camera_table(camera: &Camera) -> String {
    let number = |x: f32| format!("{:?}", x as f64);
    let vector = |v: Vec3| format!("[{}, {}, {}]", number(v.x), number(v.y), number(v.z));
    let mut out = format!(
        "[camera]\nlook_from = {}\nlook_at = {}\nup = {}\nvfov = {}\n",
        vector(camera.look_from),
        vector(camera.look_at),
        vector(camera.up),
        number(camera.vfov_degrees)
    );
    if camera.aperture != 0.0 {
        out.push_str(&format!("aperture = {}\n", number(camera.aperture)));
    }
    if let Some(f) = camera.focus_distance {
        out.push_str(&format!("focus_distance = {}\n", number(f)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            look_from: Vec3::new(278.0, 278.0, -800.0),
            look_at: Vec3::new(278.0, 278.0, 0.0),
            up: Vec3::Y,
            vfov_degrees: 40.0,
            aperture: 0.0,
            focus_distance: None,
        }
    }

    fn distance(c: &Camera) -> f32 {
        (c.look_from - c.look_at).length()
    }

    #[test]
    fn orbit_keeps_the_distance_and_the_look_at_point() {
        let c = camera();
        let m = moved(&c, Input::Orbit(100.0, 40.0), 600).expect("a move");
        assert_eq!(m.look_at, c.look_at);
        assert!((distance(&m) - distance(&c)).abs() < 1e-3);
        assert!(m.look_from.x != c.look_from.x && m.look_from.y > c.look_from.y);
        // Dragging up far enough stops short of the pole.
        let top = moved(&c, Input::Orbit(0.0, 1e6), 600).expect("a move");
        let elevation = ((top.look_from - top.look_at).normalize().y)
            .asin()
            .to_degrees();
        assert!((elevation - 89.0).abs() < 1e-3, "{elevation}");
    }

    #[test]
    fn pan_moves_both_points_across_the_view_and_dolly_only_the_eye() {
        let c = camera();
        let m = moved(&c, Input::Pan(60.0, 0.0), 600).expect("a move");
        let shift = m.look_from - c.look_from;
        assert_eq!(m.look_at - c.look_at, shift);
        // Dragging right carries the scene right: the camera moves to its left, which looking
        // along +z with +y up is +x.
        assert!(shift.x > 0.0 && shift.y.abs() < 1e-3 && shift.z.abs() < 1e-3);
        let d = moved(&c, Input::Dolly(1.0), 600).expect("a move");
        assert!((distance(&d) - 0.9 * distance(&c)).abs() < 1e-2);
        assert_eq!(d.look_at, c.look_at);
        let f = moved(&c, Input::Fly(Vec3::X), 600).expect("a move");
        assert!((f.look_from.z - (c.look_from.z + 40.0)).abs() < 1e-3);
        assert_eq!(moved(&c, Input::Save, 600), None);
    }

    #[test]
    fn the_camera_table_reads_back_as_the_same_camera() {
        let c = moved(&camera(), Input::Orbit(37.0, -11.0), 600).expect("a move");
        let c = Camera {
            aperture: 0.25,
            focus_distance: Some(812.5),
            ..c
        };
        let text = format!(
            "{}\n[materials]\nm = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5] }}\n\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 1 }}\nmaterial = \"m\"\n",
            camera_table(&c)
        );
        let scene = crate::scene::file::parse(&text, "view.toml", "view").expect("parses");
        assert_eq!(scene.camera, c);
    }
}
