//! The convergence report: its error figures, its fits, its self-estimate of error, and its files.
#![cfg_attr(not(feature = "plot"), allow(unused))]

use crate::common;

use glam::Vec3;
use rt_gpu::converge::{ConvergeOptions, errors, fit_loglog, run};
use rt_gpu::render::{Backend, GpuChoice, Integrator};
use rt_gpu::scene::flat::FlatScene;
use rt_gpu::scene::{Background, Material, Shape};
use std::sync::Mutex;

/// Timing-sensitive tests take turns: the fitted exponent is measured against wall time.
static CPU: Mutex<()> = Mutex::new(());

#[test]
fn error_against_itself_is_zero_and_against_an_offset_is_the_offset() {
    let reference: Vec<[f32; 3]> = (0..50).map(|i| [i as f32 * 0.1, 0.5, 2.0]).collect();
    let same = errors(&reference, &reference);
    assert_eq!((same.rmse, same.relmse, same.mae), (0.0, 0.0, 0.0));

    let offset = 0.25f32;
    let shifted: Vec<[f32; 3]> = reference.iter().map(|p| p.map(|c| c + offset)).collect();
    let e = errors(&shifted, &reference);
    assert!(
        (e.rmse - 0.25).abs() < 1e-6 && (e.mae - 0.25).abs() < 1e-6,
        "{e:?}"
    );
    let relmse: f64 = reference
        .iter()
        .flatten()
        .map(|&r| 0.0625 / ((r as f64) * (r as f64) + 0.01))
        .sum::<f64>()
        / 150.0;
    assert!((e.relmse - relmse).abs() < 1e-6 * relmse);
}

#[test]
fn loglog_fit_recovers_a_power_law() {
    let points: Vec<(f64, f64)> = (0..8)
        .map(|i| (2f64.powi(i), 3.0 * 2f64.powi(i).powf(-0.5)))
        .collect();
    let fit = fit_loglog(&points).expect("fits");
    assert!((fit.exponent + 0.5).abs() < 1e-9 && !fit.suspicious());
    assert!((fit.seconds_to(3.0 / 4.0) - 16.0).abs() < 1e-6);
    let biased: Vec<(f64, f64)> = points.iter().map(|&(x, y)| (x, y + 0.5)).collect();
    assert!(
        fit_loglog(&biased).expect("fits").suspicious(),
        "an error floor must be flagged"
    );
    // Stratified samples may converge faster than Monte Carlo, but not implausibly fast.
    let with_exponent = |e: f64, stratified| {
        let pts: Vec<(f64, f64)> = (0..8)
            .map(|i| (2f64.powi(i), 2f64.powi(i).powf(e)))
            .collect();
        let fit = fit_loglog(&pts).expect("fits");
        rt_gpu::converge::Fit { stratified, ..fit }.suspicious()
    };
    assert!(with_exponent(-1.0, false) && !with_exponent(-1.0, true));
    assert!(!with_exponent(-0.5, true) && with_exponent(-0.3, true));
    assert!(with_exponent(-2.0, true), "faster than -1.6 is implausible");
}

/// On the furnace scene, the render's own error estimate (from its variance buffer) matches its
/// true error against a 256x-spp reference within a factor of 1.5. The reference's own noise
/// (its estimate, 1/16 of the render's) is subtracted from the measured mean squared error.
#[test]
fn self_estimated_error_tracks_the_true_error() {
    let _turn = CPU.lock().unwrap_or_else(|p| p.into_inner());
    let scene = common::furnace_scene();
    let reference = common::render_cpu(&scene, &common::opts(24, 24, 8192, 10, 1));
    for spp in [8, 32] {
        let film = common::render_cpu(&scene, &common::opts(24, 24, spp, 10, 2));
        let mse = errors(&film.mean_rgb(), &reference.mean_rgb()).rmse.powi(2);
        let truth = (mse - reference.estimated_rmse().powi(2)).sqrt();
        let estimate = film.estimated_rmse();
        let ratio = estimate / truth;
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "{spp} spp: estimate {estimate:.3e}, truth {truth:.3e}"
        );
    }
}

/// A ladder on a plain lambertian scene falls as spp^-0.5 (so time^-0.5 at a steady rate), and
/// the report files are written (the plots need the `plot` feature).
#[cfg(feature = "plot")]
#[test]
fn ladder_on_a_lambertian_scene_falls_as_inverse_square_root_of_samples() {
    let _turn = CPU.lock().unwrap_or_else(|p| p.into_inner());
    let scene = common::scene(
        Vec3::new(0.0, 0.3, 3.0),
        Vec3::ZERO,
        45.0,
        Background::Sky,
        vec![Material::lambertian(Vec3::new(0.7, 0.5, 0.3))],
        vec![
            common::object(Shape::sphere(Vec3::ZERO, 0.7), 0),
            common::object(Shape::sphere(Vec3::new(0.0, -100.7, 0.0), 100.0), 0),
        ],
    );
    let dir = tempfile::tempdir().expect("tempdir");
    let options = ConvergeOptions {
        scene: FlatScene::new(&scene, 24, 24).expect("valid"),
        scene_name: "lambertian".into(),
        scene_digest: 1,
        width: 24,
        height: 24,
        max_depth: 6,
        backends: vec![Backend::Cpu],
        integrators: vec![Integrator::Naive],
        samplers: vec![rt_gpu::options::SamplerKind::Independent],
        roulette_depth: 0,
        budget: 3.0,
        reference: None,
        reference_spp: Some(32_768),
        out_dir: dir.path().to_path_buf(),
        gpu: GpuChoice::default(),
        denoise: false,
    };
    let report = run(&options).expect("runs");
    assert!(report.fits[0].1.is_some(), "no fit\n{}", report.table(None));
    // Against seconds the exponent depends on how steady this shared machine's clock is; against
    // samples it does not (the renders are seeded), so the rate is asserted on spp.
    let by_spp: Vec<(f64, f64)> = report
        .rungs
        .iter()
        .filter(|r| r.errors.rmse > 2.0 * report.reference.noise_rmse.unwrap_or(0.0))
        .map(|r| (r.spp as f64, r.errors.rmse))
        .collect();
    let fit = fit_loglog(&by_spp).expect("fits");
    assert!(
        !fit.suspicious(),
        "exponent {} outside [-0.6, -0.4]\n{}",
        fit.exponent,
        report.table(None)
    );
    assert!(report.rungs.len() >= 6, "{}", report.table(None));

    // The reference was cached: a second run reuses it.
    let cached = std::fs::read_dir(dir.path())
        .expect("lists")
        .filter_map(|e| e.ok())
        .any(|e| e.file_name().to_string_lossy().starts_with("reference-"));
    assert!(cached);
    let quick = ConvergeOptions {
        budget: 0.2,
        ..options.clone()
    };
    let again = run(&quick).expect("runs");
    assert!(
        again.reference.description.contains("cached, 32768 spp"),
        "{}",
        again.reference.description
    );
    // Asking for another reference spp renders a new reference rather than reusing the cache.
    let other = run(&ConvergeOptions {
        reference_spp: Some(64),
        ..quick
    })
    .expect("runs");
    assert!(
        !other.reference.description.contains("cached")
            && other.reference.description.contains("64 spp"),
        "{}",
        other.reference.description
    );

    let csv = report.csv();
    assert!(
        csv.starts_with(
            "series,spp,seconds,gpu_seconds,rmse,relmse,mae,mean_bias,estimated_rmse\n"
        )
    );
    assert_eq!(csv.lines().count(), report.rungs.len() + 1);
    let stem = dir.path().join("converge");
    rt_gpu::converge::plot::write_plot(&report, "test", &stem).expect("plots");
    let svg = std::fs::read_to_string(stem.with_extension("svg")).expect("svg written");
    assert!(svg.contains("<svg") && svg.contains("cpu-naive"));
    let png = std::fs::read(stem.with_extension("png")).expect("png written");
    assert!(png.starts_with(b"\x89PNG"));
}
