//! Progressive rendering: a range of sample indices rendered in passes over the whole image,
//! each continuing the last and added to one film. The film's sums are exact (see `film.rs`),
//! so however the range is cut into passes, and wherever a render stops and resumes, the image
//! is bit-identical to one pass over the whole range. Between passes the caller may write a
//! checkpoint, and a time budget, a target error or a stop request ends the render.

use crate::backend::Rendered;
use crate::film::Film;
use crate::render::{RenderOptions, Session};
use crate::scene::flat::FlatScene;
use crate::shared::sampler::REPLICAS;
use std::time::Instant;

/// How a progressive render ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Every sample of the range was rendered.
    Complete,
    /// The time budget was spent first.
    BudgetSpent,
    /// A stop was requested (a signal): the last pass was finished first.
    Stopped,
    /// The image's estimated relative error fell to the target.
    TargetReached,
}

/// Where a progressive render stands, for progress bars.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Samples per pixel done, counting the pass in flight's finished part.
    pub spp: f64,
    /// Samples per pixel of the whole range (it may be `u32::MAX` with a budget).
    pub total_spp: u32,
    /// Seconds since the render started, and the estimated seconds left.
    pub elapsed: f64,
    pub eta: Option<f64>,
}

/// A progressive render of samples `opts.first_sample .. opts.first_sample + opts.spp`.
pub struct Job<'a> {
    pub session: &'a Session,
    pub scene: &'a FlatScene,
    pub opts: RenderOptions,
    /// Seconds the render may take (checked between passes).
    pub budget: Option<f64>,
    /// Seconds a pass should take: how often a stop is noticed and a checkpoint can be written.
    pub pass_seconds: f64,
    /// Stop once the film's estimated relative RMSE ([`relative_error`]) is at most this.
    pub target_error: Option<f64>,
}

/// The fewest samples per pixel before the error is estimated: two per replica, so that the
/// replicas' spread means something.
const MIN_ESTIMATE_SPP: u32 = 2 * REPLICAS;

/// The film's estimated relative error: its self-estimated RMSE (the replicas' spread for
/// stratified samples, see `Film::estimated_rmse`) over its mean radiance; 0 for a black
/// image.
pub fn relative_error(film: &Film) -> f64 {
    let mean = film.image_mean();
    let mean = (mean[0] + mean[1] + mean[2]) / 3.0;
    if mean > 0.0 {
        film.estimated_rmse() / mean
    } else {
        0.0
    }
}

/// Samples per pixel for the next pass toward `target`, `done` spp in with estimated relative
/// error `error`: what error ~ 1 / sqrt(spp) predicts is still needed, at most doubling the
/// count (the estimate is noisy, and stratified samplers converge faster than that), in whole
/// rounds of the replicas.
fn pass_toward(target: f64, error: Option<f64>, done: u32) -> u32 {
    let done = done as u64;
    let wanted = match error {
        // At least an eighth more: near the target the estimate wavers, and each pass costs a
        // read-back and a merge.
        Some(e) if done >= MIN_ESTIMATE_SPP as u64 => {
            let needed = done as f64 * (e / target).powi(2);
            (needed - done as f64).clamp((done / 8).max(1) as f64, done as f64) as u64
        }
        _ => (MIN_ESTIMATE_SPP as u64).saturating_sub(done).max(1),
    };
    let pass = (done + wanted).div_ceil(REPLICAS as u64) * REPLICAS as u64 - done;
    pass.min(u32::MAX as u64) as u32
}

impl Job<'_> {
    /// Renders the range, continuing `resume` (a film of samples `opts.first_sample ..
    /// done`), calling `after_pass(film, done)` after each pass and `on_progress` during them.
    /// `stop` is polled between passes.
    pub fn run(
        &self,
        resume: Option<(Film, u32)>,
        after_pass: &mut dyn FnMut(&Film, u32) -> anyhow::Result<()>,
        on_progress: &(dyn Fn(Progress) + Sync),
        stop: &dyn Fn() -> bool,
    ) -> anyhow::Result<(Rendered, Outcome)> {
        let start = Instant::now();
        let opts = &self.opts;
        let end = opts.first_sample as u64 + opts.spp as u64;
        let end = end.min(u32::MAX as u64) as u32;
        let (mut film, mut done) = match resume {
            Some((film, done)) => (Some(film), done),
            None => (None, opts.first_sample),
        };
        let (mut gpu_seconds, mut longest_dispatch_seconds): (Option<f64>, Option<f64>) =
            (None, None);
        let mut rays: Option<u64> = None;
        let mut host_seconds: Option<f64> = None;
        let mut seconds_per_spp: Option<f64> = None;
        let outcome = loop {
            // Checked before each pass, so that a resumed film that meets it renders no more.
            let error = match (self.target_error, &film) {
                (Some(_), Some(f)) => Some(relative_error(f)),
                _ => None,
            };
            if let (Some(target), Some(e)) = (self.target_error, error)
                && done - opts.first_sample >= MIN_ESTIMATE_SPP
                && e <= target
            {
                break Outcome::TargetReached;
            }
            if done >= end {
                break Outcome::Complete;
            }
            let elapsed = start.elapsed().as_secs_f64();
            let left = self.budget.map_or(f64::INFINITY, |b| b - elapsed);
            // At least one pass: a budget shorter than starting the device still gives an image.
            if left <= 0.0 && film.is_some() {
                break Outcome::BudgetSpent;
            }
            if stop() {
                break Outcome::Stopped;
            }
            // Unbounded, one pass does it all. Otherwise the first pass is one sample: it measures
            // the rate the others are sized from.
            let seconds = left.min(self.pass_seconds);
            let pass = match seconds_per_spp {
                _ if seconds.is_infinite() => (end - done) as f64,
                Some(s) => (seconds / s).floor(),
                None => 1.0,
            };
            let pass = match self.target_error {
                Some(target) => {
                    pass.min(pass_toward(target, error, done - opts.first_sample) as f64)
                }
                None => pass,
            };
            let pass = (pass.max(1.0).min((end - done) as f64)) as u32;
            let pass_start = Instant::now();
            let spp_before = (done - opts.first_sample) as f64;
            let (total_spp, budget) = (end - opts.first_sample, self.budget);
            let rendered = self.session.render(
                self.scene,
                &RenderOptions {
                    first_sample: done,
                    spp: pass,
                    ..*opts
                },
                &|f| {
                    let spp = spp_before + f * pass as f64;
                    let elapsed = start.elapsed().as_secs_f64();
                    on_progress(Progress {
                        spp,
                        total_spp,
                        elapsed,
                        eta: eta(spp, total_spp, elapsed, budget),
                    })
                },
            )?;
            seconds_per_spp = Some(pass_start.elapsed().as_secs_f64() / pass as f64);
            done += pass;
            match &mut film {
                Some(f) => f.merge(&rendered.film),
                None => film = Some(rendered.film),
            }
            gpu_seconds = sum_of_known(gpu_seconds, rendered.gpu_seconds);
            rays = sum_of_known(rays, rendered.rays);
            host_seconds = sum_of_known(host_seconds, rendered.host_seconds);
            longest_dispatch_seconds =
                match (longest_dispatch_seconds, rendered.longest_dispatch_seconds) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                };
            if let Some(f) = &film {
                after_pass(f, done)?;
            }
        };
        let rendered = Rendered {
            film: film.unwrap_or_else(|| Film::new(opts.width, opts.height)),
            rays,
            gpu_seconds,
            longest_dispatch_seconds,
            host_seconds,
            device: self.session.device(),
        };
        Ok((rendered, outcome))
    }
}

/// The sum of the passes' figures that are known (a backend may measure none).
fn sum_of_known<T: std::ops::Add<Output = T>>(a: Option<T>, b: Option<T>) -> Option<T> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a + b),
        (a, b) => a.or(b),
    }
}

/// Seconds left: from the rate so far to the end of the range, or to the end of the budget if
/// that comes first.
fn eta(spp: f64, total_spp: u32, elapsed: f64, budget: Option<f64>) -> Option<f64> {
    let by_spp = (spp > 0.0 && total_spp < u32::MAX)
        .then(|| elapsed / spp * (total_spp as f64 - spp).max(0.0));
    let by_budget = budget.map(|b| (b - elapsed).max(0.0));
    match (by_spp, by_budget) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
