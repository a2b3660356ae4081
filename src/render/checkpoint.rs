//! A long render's checkpoints: written on a thread of their own between passes, and read back
//! to resume.

use crate::film::Film;
use crate::film::file::{self as film_file, FilmMeta};
use crate::film::output::PendingOutput;
use anyhow::bail;
use std::path::{Path, PathBuf};

/// Writes checkpoints on a thread of their own while the next passes render (encoding a
/// 512x512 film takes about 0.3 s); each waits for the one before, so they land in order.
pub struct CheckpointWriter {
    path: Option<PathBuf>,
    writing: Option<std::thread::JoinHandle<anyhow::Result<()>>>,
}

impl CheckpointWriter {
    /// A writer of checkpoints to `path`; none are written without one.
    pub fn new(path: Option<PathBuf>) -> Self {
        CheckpointWriter {
            path,
            writing: None,
        }
    }

    /// Whether it writes checkpoints anywhere.
    pub fn writes(&self) -> bool {
        self.path.is_some()
    }

    /// Starts writing `film` where checkpoints go, if anywhere, on a thread of its own (after
    /// the one before it).
    pub fn write(&mut self, film: &Film, meta: FilmMeta) -> anyhow::Result<()> {
        let Some(path) = self.path.clone() else {
            return Ok(());
        };
        self.wait()?;
        let pending = PendingOutput::claim(&path, &[])?;
        let film = film.clone();
        self.writing = Some(std::thread::spawn(move || {
            pending.commit_film(&film, &meta)
        }));
        Ok(())
    }

    /// Waits for the checkpoint in flight, if any, and reports how its writing went.
    fn wait(&mut self) -> anyhow::Result<()> {
        match self.writing.take() {
            Some(writing) => writing
                .join()
                .map_err(|_| anyhow::anyhow!("writing a checkpoint failed unexpectedly"))?,
            None => Ok(()),
        }
    }

    /// Waits for the checkpoint in flight, then writes the last one, `encoded` (a film file's
    /// bytes; `None` only when there are no checkpoints).
    pub fn finish(&mut self, encoded: Option<&[u8]>) -> anyhow::Result<()> {
        self.wait()?;
        match (&self.path, encoded) {
            (Some(path), Some(bytes)) => PendingOutput::claim(path, &[])?.commit(bytes),
            _ => Ok(()),
        }
    }
}

/// How long a pass should take. Each pass costs the host about 0.1 s on lavapipe (setting up,
/// reading back and merging its film), so passes are as long as what happens between them
/// allows: a quarter of the checkpoint interval (a stop waits for the pass in flight, so at most
/// 10 s) or a twentieth of the time budget, at least a second; one pass when nothing happens.
pub fn pass_seconds(checkpoint_every: Option<f64>, budget: Option<f64>) -> f64 {
    let limits = [checkpoint_every.map(|c| c / 4.0), budget.map(|b| b / 20.0)];
    match limits.into_iter().flatten().reduce(f64::min) {
        Some(limit) => limit.clamp(1.0, 10.0),
        None => f64::INFINITY,
    }
}

/// The film saved in `path` by a checkpoint of this render, and the sample it reached.
pub fn resume_from(
    path: &Path,
    identity: &str,
    range: &std::ops::Range<u32>,
) -> anyhow::Result<(Film, u32)> {
    let (film, meta) = film_file::read(path)?;
    if let Some(why) = film_file::identity_difference(identity, &meta.identity) {
        bail!(
            "{} is a checkpoint of another render ({why}): resume it with the options it was made with",
            path.display()
        );
    }
    let done = match meta.samples.as_slice() {
        [r] if r.start == range.start => r.end,
        _ => bail!(
            "{} holds samples {}, not a start of this render's {}..{}",
            path.display(),
            film_file::format_ranges(&meta.samples),
            range.start,
            range.end
        ),
    };
    if done > range.end {
        bail!(
            "{} already holds samples {}..{done}, more than this render's {}..{}: ask for at least {} spp",
            path.display(),
            range.start,
            range.start,
            range.end,
            done - range.start
        );
    }
    Ok((film, done))
}
