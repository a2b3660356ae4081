//! Error against run time: ladders of renders at 1, 2, 4, ... spp per series (backend x
//! integrator), each compared with a reference image, with log-log fits of RMSE against seconds.

#[cfg(feature = "plot")]
pub mod plot;

use crate::denoise::{Denoiser, render_feature_buffers};
use crate::film::output::{read_pfm, write_atomically, write_image};
use crate::options::SamplerKind;
use crate::render::{Backend, GpuChoice, Integrator, RenderOptions, Session};
use crate::scene::flat::FlatScene;
use anyhow::{Context, bail};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Error figures of one image against a reference, over linear radiance, all pixels and channels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Errors {
    pub rmse: f64,
    /// mean of (x - ref)^2 / (ref^2 + 0.01)
    pub relmse: f64,
    pub mae: f64,
    /// The image's mean over the reference's, less 1: a bias in the mean (a denoiser's, say).
    pub mean_bias: f64,
}

pub fn errors(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Errors {
    assert_eq!(image.len(), reference.len());
    let (mut se, mut rel, mut abs, mut sum, mut reference_sum) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (x, r) in image.iter().flatten().zip(reference.iter().flatten()) {
        let d = *x as f64 - *r as f64;
        se += d * d;
        rel += d * d / ((*r as f64) * (*r as f64) + 0.01);
        abs += d.abs();
        sum += *x as f64;
        reference_sum += *r as f64;
    }
    let n = (image.len() * 3).max(1) as f64;
    Errors {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
        mae: abs / n,
        mean_bias: if reference_sum > 0.0 {
            sum / reference_sum - 1.0
        } else {
            0.0
        },
    }
}

/// The image errors are measured against, with its own noise where known.
pub struct Reference {
    pub rgb: Vec<[f32; 3]>,
    /// RMSE of the reference itself (from its variance buffer); the floor of every error figure.
    pub noise_rmse: Option<f64>,
    pub description: String,
}

/// One render of a ladder.
#[derive(Clone, Debug)]
pub struct Rung {
    pub series: String,
    pub spp: u32,
    pub seconds: f64,
    pub gpu_seconds: Option<f64>,
    pub samples_per_second: f64,
    pub errors: Errors,
    pub estimated_rmse: f64,
}

/// log(rmse) = intercept + exponent * log(seconds), least squares.
#[derive(Clone, Copy, Debug)]
pub struct Fit {
    pub exponent: f64,
    pub intercept: f64,
    pub points: usize,
    /// Fitted to renders with stratified samples, whose error may fall faster than Monte
    /// Carlo's.
    pub stratified: bool,
}

impl Fit {
    /// The exponents a sound estimator's error can have: Monte Carlo's time^-0.5 (within
    /// [-0.6, -0.4]); with stratified samples anything from that down to -1.6 (randomised
    /// QMC reaches -1.5 on smooth integrands). Outside points to bias, correlation, or error
    /// that stopped falling.
    pub fn plausible_range(&self) -> std::ops::RangeInclusive<f64> {
        if self.stratified {
            -1.6..=-0.4
        } else {
            -0.6..=-0.4
        }
    }

    pub fn suspicious(&self) -> bool {
        !self.plausible_range().contains(&self.exponent)
    }

    /// Seconds at which the fitted line reaches `rmse`.
    pub fn seconds_to(&self, rmse: f64) -> f64 {
        ((rmse.ln() - self.intercept) / self.exponent).exp()
    }
}

pub fn fit_loglog(points: &[(f64, f64)]) -> Option<Fit> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let exponent = sxy / sxx;
    Some(Fit {
        exponent,
        intercept: my - exponent * mx,
        points: pts.len(),
        stratified: false,
    })
}

/// Rungs used for a series' fit: those whose error is more than twice the reference's noise
/// (below that the floor flattens the line) and whose time is at least 5% of the series'
/// longest (shorter renders are dominated by fixed per-render costs and timer noise).
pub fn fit_series(rungs: &[&Rung], floor: Option<f64>) -> Option<Fit> {
    let longest = rungs.iter().map(|r| r.seconds).fold(0.0, f64::max);
    let points: Vec<(f64, f64)> = rungs
        .iter()
        .filter(|r| floor.is_none_or(|f| r.errors.rmse > 2.0 * f))
        .filter(|r| r.seconds >= 0.05 * longest)
        .map(|r| (r.seconds, r.errors.rmse))
        .collect();
    fit_loglog(&points)
}

#[derive(Clone)]
pub struct ConvergeOptions {
    pub scene: FlatScene,
    pub scene_name: String,
    /// A stable digest of the scene, keying the cached reference.
    pub scene_digest: u64,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub backends: Vec<Backend>,
    pub integrators: Vec<Integrator>,
    pub samplers: Vec<SamplerKind>,
    /// Russian roulette from this many segments on (0: off).
    pub roulette_depth: u32,
    /// Seconds each series may spend.
    pub budget: f64,
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a rendered reference; `None` picks 8x what the fastest series is
    /// predicted to reach within the budget.
    pub reference_spp: Option<u32>,
    pub out_dir: PathBuf,
    pub gpu: GpuChoice,
    /// Also denoise every render (a series `<series>-denoised` beside each): its time includes
    /// the feature buffers' and the denoiser's.
    pub denoise: bool,
}

pub struct Report {
    pub reference: Reference,
    pub rungs: Vec<Rung>,
    pub fits: Vec<(String, Option<Fit>)>,
    /// With `denoise`: the denoiser (its version and where it was found).
    pub denoiser: Option<String>,
}

/// What denoising a ladder's renders needs: the denoiser, and per backend sessions of the
/// albedo and normal integrators.
struct Denoising {
    denoiser: Denoiser,
    features: Vec<(Backend, Session, Session)>,
}

impl Denoising {
    fn new(o: &ConvergeOptions) -> anyhow::Result<Option<Denoising>> {
        if !o.denoise {
            return Ok(None);
        }
        let denoiser = Denoiser::new(Some(rayon::current_num_threads()))?;
        let mut features = Vec::new();
        for &backend in &o.backends {
            let session = |integrator| Session::new(backend, &o.gpu, &o.scene, integrator);
            features.push((
                backend,
                session(Integrator::Albedo)?,
                session(Integrator::Normal)?,
            ));
        }
        Ok(Some(Denoising { denoiser, features }))
    }

    /// `film` (rendered on `backend` with `opts`) denoised, guided by feature buffers of the
    /// same samples, as `--denoise` makes them.
    fn denoise(
        &self,
        o: &ConvergeOptions,
        backend: Backend,
        opts: &RenderOptions,
        film: &crate::film::Film,
    ) -> anyhow::Result<Vec<[f32; 3]>> {
        let (_, albedo, normal) = (self.features.iter())
            .find(|(b, _, _)| *b == backend)
            .context("no feature sessions for this backend")?;
        let (features, _) = render_feature_buffers(opts, opts.spp, |opts| {
            let session = match opts.integrator {
                Integrator::Albedo => albedo,
                _ => normal,
            };
            session.render(&o.scene, opts, &|_| {}).map(|r| r.film)
        })?;
        Ok(self
            .denoiser
            .denoise(o.width, o.height, &film.mean_rgb(), Some(&features))?)
    }
}

fn options(
    o: &ConvergeOptions,
    spp: u32,
    seed: u32,
    integrator: Integrator,
    sampler: SamplerKind,
) -> RenderOptions {
    RenderOptions {
        width: o.width,
        height: o.height,
        spp,
        first_sample: 0,
        seed,
        max_depth: o.max_depth,
        integrator,
        sampler,
        roulette_depth: o.roulette_depth,
    }
}

/// Reference images are keyed by everything that changes them.
fn reference_key(o: &ConvergeOptions) -> String {
    format!(
        "{}-{:016x}-{}x{}-d{}",
        o.scene_name, o.scene_digest, o.width, o.height, o.max_depth
    )
}

fn load_reference(o: &ConvergeOptions, path: &Path) -> anyhow::Result<Reference> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let (w, h, rgb) = match ext.as_str() {
        "pfm" => read_pfm(path)?,
        "exr" => {
            let img = image::open(path)
                .with_context(|| format!("cannot read reference {}", path.display()))?
                .into_rgb32f();
            let (w, h) = img.dimensions();
            (w, h, img.pixels().map(|p| p.0).collect())
        }
        _ => bail!(
            "the reference must be an .exr or .pfm file, got {}",
            path.display()
        ),
    };
    if (w, h) != (o.width, o.height) {
        bail!(
            "reference {} is {w}x{h} but the renders are {}x{}: pass --size {w}x{h}",
            path.display(),
            o.width,
            o.height
        );
    }
    check_radiance(&rgb).with_context(|| format!("reference {}", path.display()))?;
    Ok(Reference {
        rgb,
        noise_rmse: None,
        description: format!("{} (given; its noise is unknown)", path.display()),
    })
}

/// Radiance is finite and non-negative.
fn check_radiance(rgb: &[[f32; 3]]) -> anyhow::Result<()> {
    if let Some(c) = rgb
        .iter()
        .flatten()
        .find(|c| !(c.is_finite() && **c >= 0.0))
    {
        bail!("holds a value that is not a finite non-negative radiance ({c})");
    }
    Ok(())
}

/// The reference: the user's, the cached one, or a new high-spp render on the fastest backend
/// (with nee where a series uses it: it converges faster).
fn reference(
    o: &ConvergeOptions,
    sessions: &[(Backend, Session)],
    series: &[(usize, SamplerKind)],
    rate: &[f64],
    progress: &dyn Progress,
) -> anyhow::Result<Reference> {
    if let Some(path) = &o.reference {
        return load_reference(o, path);
    }
    let key = reference_key(o);
    let mean_path = o.out_dir.join(format!("reference-{key}.pfm"));
    let noise_path = o.out_dir.join(format!("reference-{key}.noise"));
    if let (Ok((w, h, rgb)), Ok(noise)) =
        (read_pfm(&mean_path), std::fs::read_to_string(&noise_path))
        && (w, h) == (o.width, o.height)
        && let Some((noise, spp)) = noise.trim().split_once(' ')
        && let (Ok(noise), Ok(spp)) = (noise.parse::<f64>(), spp.parse::<u32>())
        && o.reference_spp.is_none_or(|wanted| wanted == spp)
        && noise.is_finite()
        && noise >= 0.0
        && check_radiance(&rgb).is_ok()
    {
        return Ok(Reference {
            rgb,
            noise_rmse: Some(noise),
            description: format!("{} (cached, {spp} spp)", mean_path.display()),
        });
    }
    // The fastest series, preferring nee and stratified samples: they converge faster.
    let preferred = |i: usize| {
        let (session, sampler) = series[i];
        (
            sessions[session].1.integrator() == Integrator::Nee,
            sampler == SamplerKind::Sobol,
        )
    };
    let fastest = (0..series.len())
        .max_by(|&a, &b| {
            (preferred(a), rate[a])
                .partial_cmp(&(preferred(b), rate[b]))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .context("no backend to render a reference with")?;
    let (session_index, sampler) = series[fastest];
    let pixels = o.width as f64 * o.height as f64;
    let spp = o.reference_spp.unwrap_or_else(|| {
        let reachable = rate[fastest] * o.budget / pixels;
        (8.0 * reachable).clamp(64.0, 1_048_576.0) as u32
    });
    let (backend, session) = &sessions[session_index];
    let integrator = session.integrator();
    progress.start(&format!(
        "reference: {spp} spp on {}-{}-{}",
        backend.name(),
        integrator.name(),
        sampler.name()
    ));
    let opts = options(o, spp, 0x5EED_0000, integrator, sampler);
    let film = session
        .render(&o.scene, &opts, &|f| progress.advance(f))?
        .film;
    progress.finish();
    let noise = film.estimated_rmse();
    write_image(&mean_path, &film)?;
    write_atomically(&noise_path, |out| Ok(writeln!(out, "{noise} {spp}")?))?;
    Ok(Reference {
        rgb: film.mean_rgb(),
        noise_rmse: Some(noise),
        description: format!(
            "{} ({spp} spp on {}-{}-{})",
            mean_path.display(),
            backend.name(),
            integrator.name(),
            sampler.name()
        ),
    })
}

/// Where a convergence run reports how far it is: each task (the reference, then each series'
/// ladder) starts with its name, advances by the fraction done, and finishes. The library
/// draws nothing; the CLI draws bars. Renders may report from their worker threads.
pub trait Progress: Sync {
    fn start(&self, task: &str);
    fn advance(&self, fraction: f64);
    fn finish(&self);
}

/// Progress that goes nowhere.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _task: &str) {}
    fn advance(&self, _fraction: f64) {}
    fn finish(&self) {}
}

/// Runs every series' ladder and fits, reporting no progress.
pub fn run(o: &ConvergeOptions) -> anyhow::Result<Report> {
    run_with(o, &Silent)
}

/// [`run`], reporting progress to `progress`.
pub fn run_with(o: &ConvergeOptions, progress: &dyn Progress) -> anyhow::Result<Report> {
    if !(o.budget > 0.0 && o.budget.is_finite()) {
        bail!("--budget must be a positive number of seconds");
    }
    for (i, backend) in o.backends.iter().enumerate() {
        if o.backends[..i].contains(backend) {
            bail!("--backends lists {} twice", backend.name());
        }
    }
    for (i, integrator) in o.integrators.iter().enumerate() {
        if integrator.is_feature() {
            bail!(
                "--integrators compares light transport (nee, naive), not the {} buffer",
                integrator.name()
            );
        }
        if o.integrators[..i].contains(integrator) {
            bail!("--integrators lists {} twice", integrator.name());
        }
    }
    for (i, sampler) in o.samplers.iter().enumerate() {
        if o.samplers[..i].contains(sampler) {
            bail!("--samplers lists {} twice", sampler.name());
        }
    }
    let denoising = Denoising::new(o)?;
    std::fs::create_dir_all(&o.out_dir)
        .with_context(|| format!("cannot create {}", o.out_dir.display()))?;
    let mut sessions = Vec::new();
    for &backend in &o.backends {
        for &integrator in &o.integrators {
            sessions.push((
                backend,
                Session::new(backend, &o.gpu, &o.scene, integrator)?,
            ));
        }
    }
    // A series per session and sampler (the GPU compiles a kernel per sampler).
    let series: Vec<(usize, SamplerKind)> = (0..sessions.len())
        .flat_map(|i| o.samplers.iter().map(move |&s| (i, s)))
        .collect();
    // A 1-spp probe per series: warms it up (compiling its kernel) and measures its rate for
    // the reference.
    let mut rate = Vec::new();
    for &(i, sampler) in &series {
        let session = &sessions[i].1;
        let start = Instant::now();
        let opts = options(o, 1, 0x0B0E, session.integrator(), sampler);
        session.render(&o.scene, &opts, &|_| {})?;
        rate.push(o.width as f64 * o.height as f64 / start.elapsed().as_secs_f64());
    }
    let reference = reference(o, &sessions, &series, &rate, progress)?;

    let mut rungs = Vec::new();
    let mut fits = Vec::new();
    for &(i, sampler) in &series {
        let (backend, session) = &sessions[i];
        let integrator = session.integrator();
        let series = format!(
            "{}-{}-{}",
            backend.name(),
            integrator.name(),
            sampler.name()
        );
        progress.start(&series);
        let (mut spent, mut spp, mut last) = (0.0, 1u32, 0.0);
        // Stop before a rung that would overrun the budget (each rung doubles the last).
        while spent + 2.0 * last <= o.budget && spp <= 1 << 24 {
            let seed = 1000 + spp.trailing_zeros();
            let start = Instant::now();
            let opts = options(o, spp, seed, integrator, sampler);
            let rendered = session.render(&o.scene, &opts, &|_| {})?;
            let seconds = start.elapsed().as_secs_f64();
            let film = &rendered.film;
            rungs.push(Rung {
                series: series.clone(),
                spp,
                seconds,
                gpu_seconds: rendered.gpu_seconds,
                samples_per_second: o.width as f64 * o.height as f64 * spp as f64 / seconds,
                errors: errors(&film.mean_rgb(), &reference.rgb),
                estimated_rmse: film.estimated_rmse(),
            });
            let mut seconds = seconds;
            if let Some(d) = &denoising {
                let start = Instant::now();
                let image = d.denoise(o, *backend, &opts, film)?;
                seconds += start.elapsed().as_secs_f64();
                rungs.push(Rung {
                    series: format!("{series}-denoised"),
                    spp,
                    seconds,
                    gpu_seconds: None,
                    samples_per_second: o.width as f64 * o.height as f64 * spp as f64 / seconds,
                    errors: errors(&image, &reference.rgb),
                    estimated_rmse: f64::NAN,
                });
            }
            spent += seconds;
            last = seconds;
            spp *= 2;
            progress.advance((spent / o.budget).min(1.0));
        }
        progress.finish();
        let own: Vec<&Rung> = rungs.iter().filter(|r| r.series == series).collect();
        let fit = fit_series(&own, reference.noise_rmse).map(|f| Fit {
            stratified: sampler == SamplerKind::Sobol,
            ..f
        });
        fits.push((series, fit));
    }
    Ok(Report {
        reference,
        rungs,
        fits,
        denoiser: denoising.map(|d| d.denoiser.describe()),
    })
}

/// On one backend: how long nee takes to reach the error naive reaches at its largest spp.
#[derive(Clone, Debug)]
pub struct NeeSpeedup {
    pub backend: String,
    /// Naive's RMSE at its largest spp, and the seconds that render took.
    pub target_rmse: f64,
    pub naive_seconds: f64,
    /// Seconds on nee's fitted line to that RMSE.
    pub nee_fitted_seconds: Option<f64>,
    /// The first nee render at or below that RMSE: (spp, seconds).
    pub nee_first_below: Option<(u32, f64)>,
    /// Seconds to that RMSE between the two nee renders around it, interpolated as a power law.
    pub nee_interpolated_seconds: Option<f64>,
}

impl NeeSpeedup {
    /// naive seconds / nee seconds: nee's time interpolated between its renders around the
    /// target error, else on its fitted line.
    pub fn ratio(&self) -> Option<f64> {
        self.nee_interpolated_seconds
            .or(self.nee_fitted_seconds)
            .map(|s| self.naive_seconds / s)
    }
}

/// Seconds at which the (seconds, rmse) series reaches `target`, by a power law through the
/// last render above it and the first at or below it.
fn interpolate_seconds(series: &[(f64, f64)], target: f64) -> Option<f64> {
    let below = series.iter().position(|&(_, e)| e <= target)?;
    let (t1, e1) = series[below];
    let (t0, e0) = *series[..below].last()?;
    if !(e1 < e0 && t1 > t0 && t0 > 0.0 && e1 > 0.0) {
        return None;
    }
    let exponent = (e1 / e0).ln() / (t1 / t0).ln();
    Some(t0 * (target / e0).powf(1.0 / exponent))
}

impl Report {
    /// nee against naive on each backend that ran both.
    pub fn nee_speedups(&self) -> Vec<NeeSpeedup> {
        let mut out = Vec::new();
        for (series, _) in &self.fits {
            // "{backend}-naive-{sampler}" against "{backend}-nee-{sampler}".
            let Some((backend, sampler)) = series.split_once("-naive-") else {
                continue;
            };
            let nee = format!("{backend}-nee-{sampler}");
            let Some(naive_last) = self.rungs.iter().rev().find(|r| &r.series == series) else {
                continue;
            };
            let Some((_, nee_fit)) = self.fits.iter().find(|(s, _)| *s == nee) else {
                continue;
            };
            let target = naive_last.errors.rmse;
            let nee_series: Vec<(f64, f64)> = self
                .rungs
                .iter()
                .filter(|r| r.series == nee)
                .map(|r| (r.seconds, r.errors.rmse))
                .collect();
            out.push(NeeSpeedup {
                nee_interpolated_seconds: interpolate_seconds(&nee_series, target),
                backend: format!("{backend} ({sampler})"),
                target_rmse: target,
                naive_seconds: naive_last.seconds,
                nee_fitted_seconds: nee_fit.map(|f| f.seconds_to(target)),
                nee_first_below: self
                    .rungs
                    .iter()
                    .find(|r| r.series == nee && r.errors.rmse <= target)
                    .map(|r| (r.spp, r.seconds)),
            });
        }
        out
    }

    pub fn csv(&self) -> String {
        let mut out = String::from(
            "series,spp,seconds,gpu_seconds,rmse,relmse,mae,mean_bias,estimated_rmse\n",
        );
        for r in &self.rungs {
            out.push_str(&format!(
                "{},{},{:.6},{},{:.6e},{:.6e},{:.6e},{:.6e},{}\n",
                r.series,
                r.spp,
                r.seconds,
                r.gpu_seconds.map(|s| format!("{s:.6}")).unwrap_or_default(),
                r.errors.rmse,
                r.errors.relmse,
                r.errors.mae,
                r.errors.mean_bias,
                if r.estimated_rmse.is_nan() {
                    String::new()
                } else {
                    format!("{:.6e}", r.estimated_rmse)
                }
            ));
        }
        out
    }

    /// The error the time-to-error comparison aims at: the first cpu-naive series' error at its
    /// largest spp (else the first CPU series', else the first series'), unless given.
    pub fn target_rmse(&self, given: Option<f64>) -> Option<f64> {
        given.or_else(|| {
            let names = || self.fits.iter().map(|(s, _)| s);
            let series = names()
                .find(|s| s.starts_with("cpu-naive"))
                .or_else(|| names().find(|s| s.starts_with("cpu")))
                .or_else(|| names().next())?;
            self.rungs
                .iter()
                .rev()
                .find(|r| &r.series == series)
                .map(|r| r.errors.rmse)
        })
    }

    /// The report as text: the reference, a row per render, the fitted exponents, what
    /// next-event estimation gained, and the time each series takes to `target`.
    pub fn table(&self, target: Option<f64>) -> String {
        let mut out = String::new();
        self.write_rungs(&mut out);
        self.write_fits(&mut out);
        self.write_nee_speedups(&mut out);
        self.write_denoising(&mut out);
        if let Some(target) = target {
            self.write_times_to(target, &mut out);
        }
        out
    }

    /// The reference and a row per render.
    fn write_rungs(&self, out: &mut String) {
        let floor = self.reference.noise_rmse;
        out.push_str(&format!("reference: {}\n", self.reference.description));
        match floor {
            Some(f) => out.push_str(&format!(
                "reference noise (RMSE): {f:.3e}; '*' marks errors within 2x of it\n"
            )),
            None => out.push_str("reference noise: unknown\n"),
        }
        out.push_str(&format!(
            "{:<22} {:>8} {:>9} {:>9} {:>10} {:>11} {:>11} {:>11} {:>12}\n",
            "series", "spp", "seconds", "gpu s", "Msamples/s", "rmse", "relmse", "mae", "est. rmse"
        ));
        for r in &self.rungs {
            let near_floor = floor.is_some_and(|f| r.errors.rmse <= 2.0 * f);
            out.push_str(&format!(
                "{:<22} {:>8} {:>9.3} {:>9} {:>10.3} {:>10.4e}{} {:>11.4e} {:>11.4e} {:>12}\n",
                r.series,
                r.spp,
                r.seconds,
                r.gpu_seconds
                    .map(|s| format!("{s:.3}"))
                    .unwrap_or_else(|| "-".into()),
                r.samples_per_second / 1e6,
                r.errors.rmse,
                if near_floor { "*" } else { " " },
                r.errors.relmse,
                r.errors.mae,
                if r.estimated_rmse.is_nan() {
                    "-".to_string()
                } else {
                    format!("{:.4e}", r.estimated_rmse)
                }
            ));
        }
    }

    /// Each series' fitted exponent of RMSE against seconds.
    fn write_fits(&self, out: &mut String) {
        out.push_str(
            "fitted RMSE ~ seconds^exponent (Monte Carlo: -0.5; stratified samples may fall faster):\n",
        );
        for (series, fit) in &self.fits {
            match fit {
                Some(f) => out.push_str(&format!(
                    "  {series:<22} exponent {:+.3} over {} renders{}\n",
                    f.exponent,
                    f.points,
                    if f.suspicious() {
                        format!(
                            "  <- outside [{}, {}]: bias, correlated samples, or a floor?",
                            f.plausible_range().start(),
                            f.plausible_range().end()
                        )
                    } else {
                        String::new()
                    }
                )),
                None if self
                    .rungs
                    .iter()
                    .filter(|r| &r.series == series)
                    .all(|r| !(r.errors.rmse > 0.0)) =>
                {
                    out.push_str(&format!(
                        "  {series:<22} every render's error is 0 (the scene renders exactly as its reference, black say): nothing to fit\n"
                    ))
                }
                None => out.push_str(&format!(
                    "  {series:<22} too few renders above the reference's noise to fit\n"
                )),
            }
        }
    }

    /// Per backend, how much sooner next-event estimation reaches naive's final error.
    fn write_nee_speedups(&self, out: &mut String) {
        for n in self.nee_speedups() {
            out.push_str(&format!(
                "{}: naive reached RMSE {:.4e} at its largest spp in {:.3} s; nee ",
                n.backend, n.target_rmse, n.naive_seconds
            ));
            match n.nee_first_below {
                Some((spp, s)) => out.push_str(&format!("got below it at {spp} spp in {s:.3} s")),
                None => out.push_str("did not get below it"),
            }
            if let Some(i) = n.nee_interpolated_seconds {
                out.push_str(&format!(", interpolated {i:.3} s"));
            }
            if let Some(f) = n.nee_fitted_seconds {
                out.push_str(&format!(", fitted line {f:.3} s"));
            }
            match n.ratio() {
                Some(r) => out.push_str(&format!(": nee is {r:.2}x faster\n")),
                None => out.push('\n'),
            }
        }
    }

    /// Per denoised series: its 16-spp errors, the spp at which the noisy series first reaches
    /// each, the noisy 256-spp errors, and the denoised image's bias in the mean.
    fn write_denoising(&self, out: &mut String) {
        let Some(denoiser) = &self.denoiser else {
            return;
        };
        out.push_str(&format!("denoised by {denoiser}:\n"));
        for (series, _) in &self.fits {
            let rungs = |name: &str| -> Vec<&Rung> {
                self.rungs.iter().filter(|r| r.series == name).collect()
            };
            let (noisy, denoised) = (rungs(series), rungs(&format!("{series}-denoised")));
            let Some(at_16) = denoised.iter().find(|r| r.spp == 16) else {
                out.push_str(&format!(
                    "  {series:<22} no 16-spp render within the budget\n"
                ));
                continue;
            };
            let reached = |error: fn(&Errors) -> f64| {
                noisy
                    .iter()
                    .find(|r| error(&r.errors) <= error(&at_16.errors))
                    .map_or("beyond the ladder".to_string(), |r| {
                        format!("at {} spp", r.spp)
                    })
            };
            let noisy_256 = noisy.iter().find(|r| r.spp == 256).map_or(
                "no noisy 256-spp render".to_string(),
                |r| {
                    format!(
                        "noisy 256 spp: RMSE {:.4e}, relMSE {:.4e}",
                        r.errors.rmse, r.errors.relmse
                    )
                },
            );
            out.push_str(&format!(
                "  {series:<22} denoised 16 spp: RMSE {:.4e} (noisy reaches it {}), relMSE {:.4e} (noisy reaches it {}), mean {:+.2}%; {noisy_256}\n",
                at_16.errors.rmse,
                reached(|e| e.rmse),
                at_16.errors.relmse,
                reached(|e| e.relmse),
                100.0 * at_16.errors.mean_bias,
            ));
        }
    }

    /// The time each series takes to reach RMSE `target` on its fitted line, and its speed
    /// against the CPU's naive series.
    fn write_times_to(&self, target: f64, out: &mut String) {
        out.push_str(&format!(
            "time to reach RMSE {target:.4e} (on the fitted lines):\n"
        ));
        let times: Vec<(&String, Option<f64>)> = self
            .fits
            .iter()
            .map(|(s, f)| (s, f.map(|f| f.seconds_to(target))))
            .collect();
        // Ratios against the CPU naive series (the original estimator on the reference
        // renderer), else a CPU series, else the first.
        let (base_name, base) = times
            .iter()
            .find(|(s, t)| s.starts_with("cpu-naive") && t.is_some())
            .or_else(|| {
                times
                    .iter()
                    .find(|(s, t)| s.starts_with("cpu") && t.is_some())
            })
            .or_else(|| times.iter().find(|(_, t)| t.is_some()))
            .map(|(s, t)| (s.as_str(), *t))
            .unwrap_or(("", None));
        for (series, t) in &times {
            match (t, base) {
                (Some(t), Some(b)) => out.push_str(&format!(
                    "  {series:<22} {t:9.3} s   {:.2}x the speed of {base_name}\n",
                    b / t
                )),
                _ => out.push_str(&format!("  {series:<22} no fit\n")),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::interpolate_seconds;

    #[test]
    fn interpolates_time_to_error_as_a_power_law() {
        // rmse = 0.2 t^-0.5: 0.1414 is reached at t = 2.
        let series = [(0.5, 0.2828), (1.0, 0.2), (4.0, 0.1), (16.0, 0.05)];
        let t = interpolate_seconds(&series, 0.2 / 2f64.sqrt()).expect("brackets");
        assert!((t - 2.0).abs() < 1e-3, "{t}");
        assert_eq!(interpolate_seconds(&series, 0.01), None, "never reached");
        assert_eq!(
            interpolate_seconds(&series, 0.5),
            None,
            "no render above it"
        );
    }
}
