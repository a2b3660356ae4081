//! A whole render in one call: a [`Request`] (a scene, its options, the backend, where the image
//! and checkpoints go) runs to its written outputs, and a [`Finished`] comes back: the film, why
//! the passes ended, how long they took. The outputs are claimed before the first pass (an
//! unwritable destination fails before a long render, not after it); a checkpoint resumes; the
//! passes report progress and ask whether to stop through [`Hooks`]. The command line builds a
//! request from its arguments and prints what comes back; the Python package (next) builds one
//! from a call.

use super::checkpoint::{CheckpointWriter, pass_seconds, resume_from};
use super::progressive::{Job, Outcome, Progress};
use super::{Backend, GpuChoice, RenderOptions, Rendered, Session};
use crate::denoise::{Denoiser, FeatureBuffers, render_feature_buffers};
use crate::film::file::{self as film_file, FilmMeta};
use crate::film::float_image::{FloatImage, NamedLayer};
use crate::film::output::{FileLock, ImageFormat, PendingOutput, Transfer};
use crate::film::{Film, check_memory};
use crate::scene::flat::FlatScene;
use crate::scene::{Scene, file};
use anyhow::Context;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A render, every option checked: what it renders, on what, and where its results go.
pub struct Request {
    pub scene: Scene,
    /// The file the scene came from, if any: no output replaces it.
    pub scene_file: Option<PathBuf>,
    /// `scene` flattened at the options' size.
    pub flat: FlatScene,
    /// The size, the samples (`first_sample` and `spp` after it), the integrator, ...
    pub opts: RenderOptions,
    pub backend: Backend,
    pub gpu: GpuChoice,
    /// Stop after this many seconds (the range is then an upper bound).
    pub budget: Option<f64>,
    /// Stop once the image's estimated relative error is below this.
    pub target_error: Option<f64>,
    /// Where the image goes, its format from its extension (an .exr is a film file); `None`:
    /// the film is only returned.
    pub output: Option<PathBuf>,
    /// How an 8-bit image output encodes light (`None`: its format's usual way).
    pub gamma: Option<Transfer>,
    pub checkpoint: Option<Checkpoint>,
    /// The film file's identity says the kernel ran unspecialised.
    pub unspecialised: bool,
    /// The longest a pass may take, where something between passes needs them short (a
    /// library caller that checks for Ctrl-C); `None`: as long as the checkpoints and the
    /// budget allow. Passes continue one another exactly: the image does not depend on them.
    pub pass_seconds: Option<f64>,
    /// Denoise the image (OIDN, `crate::denoise`): the albedo and normal feature buffers are
    /// rendered after the image (outside `budget`), and the output is the denoised image (an
    /// .exr output then holds it with the noisy image and the buffers as layers, not a film
    /// file). OIDN is opened before the render, so its absence fails first. A stopped render
    /// is not denoised.
    pub denoise: bool,
}

/// A denoised image and what it was made from.
pub struct Denoised {
    /// The film's mean, denoised.
    pub image: Vec<[f32; 3]>,
    /// The feature buffers that guided it.
    pub features: FeatureBuffers,
    /// Their samples per pixel.
    pub feature_spp: u32,
    /// Seconds spent rendering the feature buffers, and denoising.
    pub feature_seconds: f64,
    pub denoise_seconds: f64,
    /// The denoiser: its version and where it was loaded from.
    pub denoiser: String,
}

/// Where a long render's film is saved between passes.
pub struct Checkpoint {
    pub path: PathBuf,
    /// Seconds between checkpoints.
    pub every: f64,
    /// Continue the render the file holds (it must be of this render).
    pub resume: bool,
}

/// What a render reports while it runs.
pub struct Hooks<'a> {
    /// Once the outputs are claimed and the backend is ready (the kernel compiled), before
    /// the first pass.
    pub ready: &'a dyn Fn(),
    /// As the passes go.
    pub progress: &'a (dyn Fn(Progress) + Sync),
    /// Asked between passes: `true` ends the render after the pass in flight (its image and
    /// checkpoint are written).
    pub stop: &'a dyn Fn() -> bool,
}

/// A render that ran: its film, why its passes ended, and the samples it holds.
pub struct Finished {
    pub rendered: Rendered,
    pub outcome: Outcome,
    /// The passes' wall time (not the load's nor the outputs').
    pub seconds: f64,
    /// The sample a resumed render started from (`opts.first_sample` otherwise).
    pub resumed_at: u32,
    /// The end of the samples the film holds.
    pub done: u32,
    /// With `denoise`: the denoised image.
    pub denoised: Option<Denoised>,
}

impl Request {
    /// Runs the render and writes its outputs: the image even when the last checkpoint cannot
    /// be written (which is then the error).
    pub fn run(&self, hooks: &Hooks) -> anyhow::Result<Finished> {
        let opts = &self.opts;
        check_memory(opts.width, opts.height).map_err(anyhow::Error::msg)?;
        let format = match &self.output {
            Some(output) => Some(ImageFormat::from_path(output)?),
            None => None,
        };
        let identity = self.identity(format);
        // Held until the render ends: a second render checkpointing to the same file is
        // refused.
        let _checkpoint_lock = match &self.checkpoint {
            Some(c) => Some(FileLock::acquire(&c.path)?),
            None => None,
        };
        let range = opts.first_sample..opts.first_sample + opts.spp;
        let resume = match &self.checkpoint {
            Some(c) if c.resume => Some(resume_from(&c.path, &identity, &range)?),
            _ => None,
        };
        let denoiser = match self.denoise {
            true => Some(Denoiser::new(Some(rayon::current_num_threads()))?),
            false => None,
        };
        let pending = self.claim_outputs()?;
        let resumed_at = resume.as_ref().map_or(range.start, |(_, done)| *done);
        let session = Session::new(self.backend, &self.gpu, &self.flat, opts.integrator)?;
        let device = session.device();
        let meta = |done: u32| FilmMeta {
            identity: identity.clone(),
            samples: std::iter::once(range.start..done).collect(),
            device: device.clone(),
        };
        (hooks.ready)();
        let start = Instant::now();
        let mut passes = self.run_passes(&session, resume, &meta, hooks)?;
        let seconds = start.elapsed().as_secs_f64();
        let done = range.start + passes.rendered.film.pixels.first().map_or(0, |p| p.n) as u32;
        // Not after a stop (a signal, Ctrl-C: the checkpoint and the image so far are written
        // at once, undenoised), nor of no samples.
        let stopped = passes.outcome == Outcome::Stopped || (hooks.stop)();
        let denoised = match &denoiser {
            Some(denoiser) if !stopped && done > range.start => {
                Some(self.denoise(denoiser, &passes.rendered.film, done))
            }
            _ => None,
        };
        let (denoised, failure) = match denoised {
            Some(Ok(d)) => (Some(d), None),
            Some(Err(e)) => (None, Some(e)),
            None => (None, None),
        };
        // Where denoising failed the output is left as it was; the checkpoint is still written.
        let pending = if failure.is_some() { None } else { pending };
        self.write_outputs(format, pending, &mut passes, &meta(done), denoised.as_ref())?;
        if let Some(e) = failure {
            return Err(match &self.checkpoint {
                Some(c) => e.context(format!(
                    "not denoised (the checkpoint {} was written)",
                    c.path.display()
                )),
                None => e.context("not denoised"),
            });
        }
        Ok(Finished {
            rendered: passes.rendered,
            outcome: passes.outcome,
            seconds,
            resumed_at,
            done,
            denoised,
        })
    }

    /// Renders the feature buffers (`denoise::render_feature_buffers`) on the image's backend
    /// and denoises the film's mean with them.
    fn denoise(&self, denoiser: &Denoiser, film: &Film, done: u32) -> anyhow::Result<Denoised> {
        let start = Instant::now();
        let spp = done - self.opts.first_sample;
        let (features, feature_spp) = render_feature_buffers(&self.opts, spp, |opts| {
            super::render(self.backend, &self.gpu, &self.flat, opts, &|_| {})
                .map(|rendered| rendered.film)
        })?;
        let feature_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let image = denoiser.denoise(film.width, film.height, &film.mean_rgb(), Some(&features))?;
        Ok(Denoised {
            image,
            features,
            feature_spp,
            feature_seconds,
            denoise_seconds: start.elapsed().as_secs_f64(),
            denoiser: denoiser.describe(),
        })
    }

    /// The identity film files of this render carry (empty where none are written: digesting
    /// a scene of many objects takes a while).
    fn identity(&self, format: Option<ImageFormat>) -> String {
        if self.checkpoint.is_none() && format != Some(ImageFormat::Exr) {
            return String::new();
        }
        identity(&self.scene, self.backend, &self.opts, self.unspecialised)
    }

    /// Claims the output (and checks the checkpoint can be claimed) now, so that an
    /// unwritable destination fails before a long render, not after it.
    fn claim_outputs(&self) -> anyhow::Result<Option<PendingOutput>> {
        let inputs: Vec<&Path> = (self.scene_file.iter().map(|p| p.as_path()))
            .chain(self.scene.input_paths())
            .collect();
        let pending = match &self.output {
            Some(output) => Some(PendingOutput::claim(output, &inputs)?),
            None => None,
        };
        if let Some(c) = &self.checkpoint {
            // Fail now, not at the first checkpoint a minute in.
            drop(PendingOutput::claim(&c.path, &inputs)?);
        }
        Ok(pending)
    }

    /// Runs the passes, writing a checkpoint every `checkpoint.every` seconds, until the
    /// samples, the budget or the target are done or `hooks.stop` says so.
    fn run_passes(
        &self,
        session: &Session,
        resume: Option<(Film, u32)>,
        meta: &dyn Fn(u32) -> FilmMeta,
        hooks: &Hooks,
    ) -> anyhow::Result<Passes> {
        let every = self.checkpoint.as_ref().map(|c| c.every);
        let job = Job {
            session,
            scene: &self.flat,
            opts: self.opts,
            budget: self.budget,
            pass_seconds: (self.pass_seconds.into_iter())
                .fold(pass_seconds(every, self.budget), f64::min),
            target_error: self.target_error,
        };
        let mut last_checkpoint = Instant::now();
        let checkpoint_failure: std::cell::RefCell<Option<anyhow::Error>> = Default::default();
        let mut checkpoints =
            CheckpointWriter::new(self.checkpoint.as_ref().map(|c| c.path.clone()));
        let (rendered, outcome) = job.run(
            resume,
            &mut |film, done| {
                // A checkpoint that cannot be written stops the render; the image so far is
                // still written before the error is reported.
                if every.is_some_and(|every| last_checkpoint.elapsed().as_secs_f64() >= every)
                    && checkpoint_failure.borrow().is_none()
                {
                    if let Err(e) = checkpoints.write(film, meta(done)) {
                        *checkpoint_failure.borrow_mut() = Some(e);
                    }
                    last_checkpoint = Instant::now();
                }
                Ok(())
            },
            hooks.progress,
            &|| (hooks.stop)() || checkpoint_failure.borrow().is_some(),
        )?;
        Ok(Passes {
            rendered,
            outcome,
            checkpoints,
            checkpoint_failure: checkpoint_failure.into_inner(),
        })
    }

    /// Writes the last checkpoint and the image (the image even when the checkpoint fails,
    /// which is then the error).
    fn write_outputs(
        &self,
        format: Option<ImageFormat>,
        pending: Option<PendingOutput>,
        passes: &mut Passes,
        meta: &FilmMeta,
        denoised: Option<&Denoised>,
    ) -> anyhow::Result<()> {
        let film = &passes.rendered.film;
        // The last checkpoint and an .exr output hold the same film file: encoded once (a
        // 512x512 film takes about 0.3 s), written twice. A denoised .exr is no film file.
        let output_is_film = format == Some(ImageFormat::Exr) && denoised.is_none();
        let encoded = if passes.checkpoints.writes() || output_is_film {
            Some(film_file::encode(film, Some(meta))?)
        } else {
            None
        };
        let checkpointed = match passes.checkpoint_failure.take() {
            Some(e) => Err(e),
            None => passes.checkpoints.finish(encoded.as_deref()),
        };
        let Some(pending) = pending else {
            return checkpointed;
        };
        match (&encoded, denoised) {
            (Some(bytes), _) if output_is_film => pending.commit(bytes)?,
            (_, Some(denoised)) => {
                let image = denoised_image(film, denoised);
                pending.commit_encoded(self.gamma, |format, transfer| {
                    image.encode(format, transfer)
                })?
            }
            _ => pending.commit_image(film, self.gamma)?,
        }
        checkpointed.with_context(|| {
            let output = self.output.as_deref().unwrap_or(Path::new(""));
            format!(
                "the image was written to {}, but not the checkpoint",
                output.display()
            )
        })
    }
}

/// A denoised image as written: the denoised image, and beside it (in an EXR) the noisy one and
/// the feature buffers, named as Cycles names its passes' channels.
pub fn denoised_image(film: &Film, denoised: &Denoised) -> FloatImage {
    let layer = |name, channels, pixels: &[[f32; 3]]| NamedLayer {
        name,
        channels,
        pixels: pixels.to_vec(),
    };
    FloatImage {
        width: film.width,
        height: film.height,
        rgb: denoised.image.clone(),
        layers: vec![
            layer("noisy", ["R", "G", "B"], &film.mean_rgb()),
            layer("albedo", ["R", "G", "B"], &denoised.features.albedo),
            layer("normal", ["X", "Y", "Z"], &denoised.features.normal),
        ],
    }
}

/// The identity a film file of `scene` rendered with `opts` on `backend` carries: what a film
/// must share with another to resume or merge with it (the viewer's saved films carry it too).
pub fn identity(
    scene: &Scene,
    backend: Backend,
    opts: &RenderOptions,
    unspecialised: bool,
) -> String {
    let digest = file::digest(scene);
    let files = crate::assets::inputs::identity_fields(&scene.inputs);
    film_file::identity(digest, &files, backend, opts, unspecialised)
}

/// What the passes left: the render, why they ended, the checkpoints still to finish and the
/// first checkpoint that could not be written.
struct Passes {
    rendered: Rendered,
    outcome: Outcome,
    checkpoints: CheckpointWriter,
    checkpoint_failure: Option<anyhow::Error>,
}
