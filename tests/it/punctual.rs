//! Punctual lights (points, spots, the sun): their direct light against closed forms (CPU),
//! the GPU and the CPU alike on scenes lit by them (through smoke too), their scene
//! file syntax read back as written, and one-line errors for bad ones.
//!
//! Image comparisons use the equivalence test of tests/it/common/stats.rs (Welch z, family-wise
//! alpha 0.01, Sidak-corrected over every pixel, block and channel); each such assertion is
//! one test, and each has a negative control (2% more light) that the same test catches.
#![cfg_attr(not(feature = "gpu"), allow(unused))]

use crate::common;

#[cfg(feature = "gpu")]
use common::gpu::{render_gpu, renderer};
use common::stats::compare;
use common::{nee_opts, render_cpu, scene_error};
use glam::Vec3;
use rt_gpu::film::Film;
#[cfg(feature = "gpu")]
use rt_gpu::gpu::Tuning;
use rt_gpu::scene::Scene;
use rt_gpu::scene::file::{parse, to_toml};
use rt_gpu::scene::punctual::Punctual;
use std::f32::consts::PI;

/// A camera looking straight down at a wide white (albedo 0.5) floor at y = 0 from height 4,
/// lit by `lights` (scene-file tables) alone.
fn floor_under(lights: &str) -> Scene {
    let text = format!(
        r#"
[render]
background = [0, 0, 0]

[camera]
look_from = [0, 4, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
vfov = 10

[materials]
white = {{ type = "lambertian", albedo = [0.5, 0.5, 0.5] }}

[[object]]
quad = {{ q = [-100, 0, 100], u = [200, 0, 0], v = [0, 0, -200] }}
material = "white"
{lights}
"#
    );
    parse(&text, "floor.toml", "floor").expect("a valid scene")
}

/// The mean of the image's centre pixel, on the CPU.
fn centre(film: &Film) -> Vec3 {
    let p = film.pixel(film.width / 2, film.height / 2);
    p.mean().as_vec3()
}

/// Direct light alone (max depth 2: the floor's hit and its light sample).
fn direct(scene: &Scene) -> Film {
    render_cpu(scene, &nee_opts(9, 9, 64, 2, 0))
}

#[test]
fn direct_light_matches_closed_forms() {
    // A point light 2 above the floor, beside the point the centre pixel sees by 1: the floor
    // there gets I cos(theta) / d^2, and reflects albedo / pi of it.
    let point = floor_under("[[light]]\npoint = { position = [1, 2, 0], intensity = [8, 4, 2] }");
    let d2 = 5.0f32;
    let cos = 2.0 / d2.sqrt();
    let expected = Vec3::new(8.0, 4.0, 2.0) * (0.5 / PI * cos / d2);
    let got = centre(&direct(&point));
    assert!(
        (got - expected).abs().max_element() < 2e-3 * expected.max_element(),
        "{got} against {expected}"
    );

    // The sun at 60 degrees from overhead: E cos(60) everywhere, every sample exact.
    let sun = floor_under(
        "[[light]]\ndirectional = { direction = [0.8660254, -0.5, 0], irradiance = [2, 2, 2] }",
    );
    let expected = 2.0 * 0.5 * 0.5 / PI;
    let got = centre(&direct(&sun));
    assert!(
        (got - Vec3::splat(expected)).abs().max_element() < 1e-4,
        "{got} against {expected}"
    );

    // A spot straight above: full inside its inner cone, nothing outside its outer; between
    // them glTF's ramp, squared.
    let spot = |inner: f32, outer: f32| {
        floor_under(&format!(
            "[[light]]\nspot = {{ position = [0, 2, 0], look_at = [1, 0, 0], intensity = [5, 5, 5], inner = {inner}, outer = {outer} }}"
        ))
    };
    // The axis leans 26.57 degrees toward +x; the centre pixel's point is 26.57 degrees off it
    // (and the pixel spans +-1.1 degrees about it).
    let off_axis = (0.5f32).atan().to_degrees();
    let full = Vec3::splat(5.0 * 0.5 / PI / 4.0); // straight below, at distance 2
    let got = centre(&direct(&spot(off_axis + 3.0, off_axis + 8.0)));
    assert!(
        (got - full).abs().max_element() < 2e-3 * full.x,
        "inside: {got} against {full}"
    );
    let got = centre(&direct(&spot(off_axis - 8.0, off_axis - 3.0)));
    assert_eq!(got, Vec3::ZERO, "outside the outer cone");
    let (inner, outer) = ((off_axis - 4.0).to_radians(), (off_axis + 4.0).to_radians());
    let t =
        ((off_axis.to_radians().cos() - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
    let ramp = full * (t * t);
    let got = centre(&direct(&spot(off_axis - 4.0, off_axis + 4.0)));
    assert!(
        (got - ramp).abs().max_element() < 0.02 * full.x,
        "between: {got} against {ramp}"
    );

    // A narrow spot (Blender's smallest, 1 degree across) far above: full on its axis.
    let narrow = floor_under(
        "[[light]]\nspot = { position = [0, 200, 0], look_at = [0, 0, 0], intensity = [5, 5, 5], inner = 0.25, outer = 0.5 }",
    );
    let full = Vec3::splat(5.0 * 0.5 / PI / 40000.0);
    let got = centre(&direct(&narrow));
    assert!(
        (got - full).abs().max_element() < 2e-3 * full.x,
        "narrow: {got} against {full}"
    );
}

/// A red sphere on a white floor under a point, a spot and the sun, with a smoke ball beside:
/// the scene the CPU and the GPU must render alike.
fn lit_by_lamps(strength: f32, smoke: bool) -> Scene {
    let smoke = if smoke {
        "[[object]]\nsphere = { center = [-1, 0.6, 0.5], radius = 0.6 }\nmaterial = \"smoke\"\n"
    } else {
        ""
    };
    let s = strength;
    let text = format!(
        r#"
[render]
background = [0, 0, 0]

[camera]
look_from = [0, 1, 4]
look_at = [0, 0.3, 0]
vfov = 45

[materials]
white = {{ type = "lambertian", albedo = [0.7, 0.7, 0.7] }}
red = {{ type = "lambertian", albedo = [0.7, 0.2, 0.2] }}
smoke = {{ type = "medium", density = 1.5, albedo = [0.9, 0.9, 0.9] }}

[[object]]
quad = {{ q = [-2, 0, 2], u = [4, 0, 0], v = [0, 0, -4] }}
material = "white"

[[object]]
sphere = {{ center = [0.5, 0.5, 0], radius = 0.5 }}
material = "red"
{smoke}
[[light]]
point = {{ position = [1, 2, 1], intensity = [{p}, {p}, {p}] }}

[[light]]
spot = {{ position = [-1.5, 2, 0.5], look_at = [-1, 0, 0], intensity = [{a}, {b}, {c}], inner = 15, outer = 25 }}

[[light]]
directional = {{ direction = [0.3, -1, -0.2], irradiance = [{e}, {e}, {f}] }}
"#,
        p = 3.0 * s,
        a = 6.0 * s,
        b = 5.0 * s,
        c = 4.0 * s,
        e = 0.5 * s,
        f = 0.6 * s,
    );
    parse(&text, "lamps.toml", "lamps").expect("a valid scene")
}

#[cfg(feature = "gpu")]
#[test]
fn gpu_renders_punctual_lights_as_the_cpu_does() {
    let Some(gpu) = renderer() else { return };
    for smoke in [false, true] {
        let opts = |seed| nee_opts(24, 24, 2048, 5, seed);
        let cpu = render_cpu(&lit_by_lamps(1.0, smoke), &opts(1));
        let film = render_gpu(
            &gpu,
            &lit_by_lamps(1.0, smoke),
            &opts(2),
            &Tuning::default(),
        );
        let verdict = compare(&cpu, &film);
        eprintln!("smoke {smoke}: cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "smoke {smoke}: {verdict:?}");
        let brighter = render_gpu(
            &gpu,
            &lit_by_lamps(1.02, smoke),
            &opts(2),
            &Tuning::default(),
        );
        let verdict = compare(&cpu, &brighter);
        eprintln!("smoke {smoke}: gpu with 2% brighter lamps: {verdict:?}");
        assert!(
            !verdict.passed(),
            "smoke {smoke}: 2% brighter lamps went undetected"
        );
    }
}

#[test]
fn lamps_read_back_as_written_and_bad_ones_are_one_line_errors() {
    let scene = lit_by_lamps(1.0, true);
    assert_eq!(scene.punctual.len(), 3);
    assert!(matches!(scene.punctual[1], Punctual::Spot { .. }));
    let again = parse(&to_toml(&scene), "again.toml", "again").expect("reads back");
    assert_eq!(again.punctual.len(), 3);
    for (a, b) in scene.punctual.iter().zip(&again.punctual) {
        let close = |x: Vec3, y: Vec3| (x - y).length() < 1e-5;
        match (a, b) {
            (
                Punctual::Spot {
                    direction: d,
                    inner: i,
                    outer: o,
                    ..
                },
                Punctual::Spot {
                    direction: e,
                    inner: j,
                    outer: p,
                    ..
                },
            ) => assert!(close(*d, *e) && (i - j).abs() < 1e-6 && (o - p).abs() < 1e-6),
            _ => assert_eq!(a, b),
        }
    }
    let base = "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n\n";
    for (light, expected) in [
        (
            "[[light]]\npoint = { position = [0, 1, 0], intensity = [1, 1, 1] }\ndirectional = { direction = [0, -1, 0], irradiance = [1, 1, 1] }",
            "one of point",
        ),
        (
            "[[light]]\nspot = { position = [0, 1, 0], look_at = [0, 0, 0], intensity = [1, 1, 1], inner = 30, outer = 20 }",
            "inner < outer",
        ),
        (
            "[[light]]\npoint = { position = [0, 1, 0], intensity = [1, -1, 1] }",
            "intensity",
        ),
        (
            "[[light]]\ndirectional = { direction = [0, 0, 0], irradiance = [1, 1, 1] }",
            "direction",
        ),
        (
            "[[light]]\nspot = { position = [0, 1, 0], look_at = [0, 1, 0], intensity = [1, 1, 1], inner = 10, outer = 20 }",
            "direction",
        ),
    ] {
        let error = scene_error(&format!("{base}{light}\n"));
        assert!(error.contains(expected), "{light}: {error}");
        assert!(error.contains("bad.toml:"), "located: {error}");
        assert_eq!(error.lines().count(), 1, "{error}");
    }
    // Issue 61: a direction of tiny components is a direction (it was refused as [0, 0, 0]).
    let tiny =
        "[[light]]\ndirectional = { direction = [1e-30, -1e-30, 0], irradiance = [1, 1, 1] }";
    let scene = rt_gpu::scene::file::parse(&format!("{base}{tiny}\n"), "tiny.toml", "tiny")
        .expect("a direction");
    match scene.punctual[0] {
        Punctual::Directional { direction, .. } => {
            assert!((direction - glam::Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-6)
        }
        ref other => panic!("{other:?}"),
    }
}
