//! Writing images. The format follows the file extension; every write goes to a temporary file
//! beside the target and is renamed over it only when complete, so a failed or interrupted render
//! never clobbers an existing image.

use crate::film::Film;
use crate::film::levels::Levels;
use anyhow::Context;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit, sRGB by default.
    Png,
    /// ASCII P3, gamma 2, as the original project wrote.
    Ppm,
    /// Linear float radiance.
    Exr,
    /// Linear float radiance (Portable Float Map).
    Pfm,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> anyhow::Result<Self> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        Ok(match ext.as_str() {
            "png" => ImageFormat::Png,
            "ppm" => ImageFormat::Ppm,
            "exr" => ImageFormat::Exr,
            "pfm" => ImageFormat::Pfm,
            _ => anyhow::bail!(
                "cannot tell the image format of {}: use a .png, .ppm, .exr or .pfm file name",
                path.display()
            ),
        })
    }
}

/// How linear radiance becomes 8-bit values in PNG and PPM files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transfer {
    /// The sRGB curve, which image viewers assume for PNG.
    Srgb,
    /// `c^(1/g)`, as 256 * clamp(c^(1/g), 0, 0.999): the original project wrote gamma 2.
    Gamma(f32),
}

impl Transfer {
    /// What a format's readers expect: sRGB for PNG, gamma 2 for PPM (as the original wrote).
    pub fn default_for(format: ImageFormat) -> Self {
        match format {
            ImageFormat::Ppm => Transfer::Gamma(2.0),
            _ => Transfer::Srgb,
        }
    }

    /// Parses `srgb` or a gamma such as `2` or `2.2`.
    pub fn parse(text: &str) -> Result<Self, String> {
        if text.eq_ignore_ascii_case("srgb") {
            return Ok(Transfer::Srgb);
        }
        match text.parse::<f32>() {
            Ok(g) if (0.1..=10.0).contains(&g) => Ok(Transfer::Gamma(g)),
            _ => Err(format!(
                "expected `srgb` or a gamma in [0.1, 10] such as 2, got '{text}'"
            )),
        }
    }

    /// The 8-bit levels of this curve, decided on a pixel's exact sum (what image files and
    /// the viewer show).
    pub fn levels(self) -> Levels {
        match self {
            Transfer::Srgb => Levels::new(|c, _| Transfer::Srgb.encode(c), 0.0),
            Transfer::Gamma(g) => Levels::new(|c, g| Transfer::Gamma(g).encode(c), g),
        }
    }

    /// One linear value as 8 bits; negative and non-finite values are black.
    pub fn encode(self, linear: f32) -> u8 {
        let c = if linear.is_finite() {
            linear.max(0.0)
        } else {
            0.0
        };
        match self {
            Transfer::Srgb => {
                let v = if c <= 0.003_130_8 {
                    12.92 * c
                } else {
                    1.055 * c.powf(1.0 / 2.4) - 0.055
                };
                (255.0 * v.clamp(0.0, 1.0)).round() as u8
            }
            // sqrt, not powf(0.5): bit-for-bit the original's values.
            Transfer::Gamma(2.0) => (256.0 * c.sqrt().clamp(0.0, 0.999)) as u8,
            Transfer::Gamma(g) => (256.0 * c.powf(1.0 / g).clamp(0.0, 0.999)) as u8,
        }
    }
}

/// Writes `film`'s mean image to `path` atomically, in the format its extension names, with
/// that format's default transfer curve.
pub fn write_image(path: &Path, film: &Film) -> anyhow::Result<()> {
    PendingOutput::claim(path, &[])?.commit_image(film, None)
}

/// `film`'s mean image encoded in `format`; 8-bit formats use `transfer`.
pub fn encode_image(
    format: ImageFormat,
    film: &Film,
    transfer: Transfer,
) -> anyhow::Result<Vec<u8>> {
    let (w, h) = (film.width, film.height);
    let mut out = std::io::Cursor::new(Vec::new());
    match format {
        ImageFormat::Png => {
            let levels = transfer.levels();
            let bytes: Vec<u8> = film.pixels.iter().flat_map(|p| levels.pixel(p)).collect();
            let img = image::RgbImage::from_raw(w, h, bytes).context("image buffer size")?;
            img.write_to(&mut out, image::ImageFormat::Png)?;
        }
        ImageFormat::Ppm => {
            let levels = transfer.levels();
            let mut text = BufWriter::new(&mut out);
            writeln!(text, "P3\n{w} {h}\n255")?;
            for p in &film.pixels {
                let [r, g, b] = levels.pixel(p);
                writeln!(text, "{r} {g} {b}")?;
            }
            text.flush()?;
        }
        // The film's whole state, without what would let rt-gpu continue or merge it.
        ImageFormat::Exr => return crate::film::file::encode(film, None),
        ImageFormat::Pfm => {
            let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
            // PFM stores rows bottom to top; -1.0 marks little-endian.
            for row in film.mean_rgb().chunks(w as usize).rev() {
                for c in row.iter().flatten() {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.write_all(&bytes)?;
        }
    }
    Ok(out.into_inner())
}

/// Reads a PFM written by [`write_image`] (or any little- or big-endian RGB PFM) as
/// (width, height, row-major RGB from the top).
pub fn read_pfm(path: &Path) -> anyhow::Result<(u32, u32, Vec<[f32; 3]>)> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 && pos < bytes.len() {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1;
    let bad = || anyhow::anyhow!("{} is not an RGB PFM file", path.display());
    if fields.len() < 4 || fields[0] != "PF" {
        return Err(bad());
    }
    let w: u32 = fields[1].parse().map_err(|_| bad())?;
    let h: u32 = fields[2].parse().map_err(|_| bad())?;
    let scale = fields[3].parse::<f32>().map_err(|_| bad())?;
    if !(scale.is_finite() && scale != 0.0) {
        return Err(bad());
    }
    let little = scale < 0.0;
    let data = bytes.get(pos..).ok_or_else(bad)?;
    if data.len() < w as usize * h as usize * 12 {
        return Err(bad());
    }
    let value = |i: usize| {
        let b: [u8; 4] = data[4 * i..4 * i + 4].try_into().unwrap_or_default();
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut rgb = vec![[0.0; 3]; (w * h) as usize];
    for y in 0..h as usize {
        let src_row = h as usize - 1 - y;
        for x in 0..w as usize {
            let i = (src_row * w as usize + x) * 3;
            rgb[y * w as usize + x] = [value(i), value(i + 1), value(i + 2)];
        }
    }
    Ok((w, h, rgb))
}

/// Runs `write` into a buffer, then puts it at `path` atomically (see [`PendingOutput`]).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::io::Cursor<Vec<u8>>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let pending = PendingOutput::claim(path, &[])?;
    let mut buffer = std::io::Cursor::new(Vec::new());
    write(&mut buffer).with_context(|| format!("cannot encode {}", path.display()))?;
    pending.commit(&buffer.into_inner())
}

/// Refuses `output` if it is one of `inputs`, the files a run reads (the same file, by any
/// name: a symbolic or hard link too).
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    for input in inputs {
        if same_file(output, input) {
            anyhow::bail!(
                "output {} is {}, a file this run reads: choose another output",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Whether `a` and `b` name one existing file (through links too).
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        std::fs::canonicalize(a).is_ok_and(|ca| std::fs::canonicalize(b).is_ok_and(|cb| ca == cb))
    }
}

/// Longest file name most file systems take (NAME_MAX on Linux).
const MAX_NAME_BYTES: usize = 255;

/// Temporary files not yet renamed into place, which a signal handler removes before exiting
/// (a killed process runs no destructors).
static PENDING_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary output file still pending; for signal handlers.
pub fn remove_pending_files() {
    let files = PENDING_FILES.lock().unwrap_or_else(|p| p.into_inner());
    for file in files.iter() {
        let _ = std::fs::remove_file(file);
    }
}

/// An output file claimed before the work that produces it, so that a destination that cannot
/// be written fails at once, not after a long render: the destination is checked and a
/// temporary file is created beside it now; [`commit`](Self::commit) writes the temporary file
/// and renames it over the destination, so a failed or interrupted run never leaves a partial
/// file. It refuses a destination that is a directory or not a regular file, is read-only (as
/// `cp` does), or is one of the run's inputs; a symbolic link is written through, to its target.
pub struct PendingOutput {
    /// The destination as the user named it, for messages.
    shown: PathBuf,
    /// Where the file goes: `shown` with symbolic links resolved.
    target: PathBuf,
    /// `None` once committed.
    tmp: Option<tempfile::NamedTempFile>,
}

impl PendingOutput {
    /// Claims `path`; `inputs` are files this run reads, which it must not overwrite.
    pub fn claim(path: &Path, inputs: &[&Path]) -> anyhow::Result<Self> {
        let shown = path.to_path_buf();
        let name = path
            .file_name()
            .with_context(|| format!("output {} does not name a file", path.display()))?;
        if name.len() > MAX_NAME_BYTES {
            anyhow::bail!(
                "output file name is {} bytes long; file systems take at most {MAX_NAME_BYTES}",
                name.len()
            );
        }
        let mut target = path.to_path_buf();
        if let Ok(meta) = std::fs::symlink_metadata(path) {
            if meta.file_type().is_symlink() {
                target = std::fs::canonicalize(path).with_context(|| {
                    format!(
                        "output {} is a symbolic link to a missing file",
                        path.display()
                    )
                })?;
            }
            let meta = std::fs::metadata(&target)
                .with_context(|| format!("cannot inspect output {}", path.display()))?;
            if meta.is_dir() {
                anyhow::bail!("output {} is a directory", path.display());
            }
            if !meta.is_file() {
                anyhow::bail!(
                    "output {} exists and is not a regular file: refusing to replace it",
                    path.display()
                );
            }
            if meta.permissions().readonly() {
                anyhow::bail!(
                    "output {} exists and is read-only: choose another file or make it writable",
                    path.display()
                );
            }
            check_not_input(path, inputs)?;
        }
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        check_directory(&dir)?;
        // Named after the destination and held locked while this process owns it, so that a
        // later run can remove what a killed one left (`remove_stale_temporaries`).
        let prefix = temporary_prefix(name);
        remove_stale_temporaries(&dir, &prefix);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // Temporary files are private (0600); an output is an ordinary file, or keeps the
        // permissions of the file it replaces.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&target).map_or(0o644, |m| m.permissions().mode());
            builder.permissions(std::fs::Permissions::from_mode(mode & 0o7777));
        }
        let tmp = builder
            .tempfile_in(&dir)
            .with_context(|| format!("cannot create a file in {}", dir.display()))?;
        // Advisory: where the file system has no locks, stale files are only left in place.
        let _ = tmp.as_file().try_lock();
        PENDING_FILES
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push(tmp.path().to_path_buf());
        Ok(PendingOutput {
            shown,
            target,
            tmp: Some(tmp),
        })
    }

    /// Writes `film`'s mean image in the format the destination's extension names, 8-bit
    /// formats with `transfer` [default: the format's own].
    pub fn commit_image(self, film: &Film, transfer: Option<Transfer>) -> anyhow::Result<()> {
        self.commit_encoded(transfer, |format, transfer| {
            encode_image(format, film, transfer)
        })
    }

    /// Writes what `encode` makes of the image in the format the destination's extension names,
    /// 8-bit formats with `transfer` [default: the format's own] (a float image's
    /// `film::float_image::FloatImage::encode`, say).
    pub fn commit_encoded(
        self,
        transfer: Option<Transfer>,
        encode: impl FnOnce(ImageFormat, Transfer) -> anyhow::Result<Vec<u8>>,
    ) -> anyhow::Result<()> {
        let format = ImageFormat::from_path(&self.shown)?;
        let transfer = transfer.unwrap_or(Transfer::default_for(format));
        let bytes = encode(format, transfer)
            .with_context(|| format!("cannot encode {}", self.shown.display()))?;
        self.commit(&bytes)
    }

    /// Writes a render's `film`: as a film file with `meta` when the destination is .exr (an
    /// image that rt-gpu can continue or merge), else as an image encoded with `transfer`.
    pub fn commit_render(
        self,
        film: &Film,
        meta: &crate::film::file::FilmMeta,
        transfer: Option<Transfer>,
    ) -> anyhow::Result<()> {
        if ImageFormat::from_path(&self.shown)? == ImageFormat::Exr {
            self.commit_film(film, meta)
        } else {
            self.commit_image(film, transfer)
        }
    }

    /// Writes `film` as a film file (an EXR image that rt-gpu can continue or merge).
    pub fn commit_film(
        self,
        film: &Film,
        meta: &crate::film::file::FilmMeta,
    ) -> anyhow::Result<()> {
        let bytes = crate::film::file::encode(film, Some(meta))
            .with_context(|| format!("cannot encode {}", self.shown.display()))?;
        self.commit(&bytes)
    }

    /// Writes `bytes` to the temporary file and renames it over the destination.
    pub fn commit(mut self, bytes: &[u8]) -> anyhow::Result<()> {
        let mut tmp = self.tmp.take().context("output already written")?;
        let tmp_path = tmp.path().to_path_buf();
        let written = tmp
            .write_all(bytes)
            .and_then(|_| tmp.as_file().sync_all())
            .map_err(anyhow::Error::from)
            .and_then(|_| tmp.persist(&self.target).map_err(|e| e.error.into()));
        forget_pending(&tmp_path);
        written.with_context(|| format!("cannot write {}", self.shown.display()))?;
        Ok(())
    }
}

impl Drop for PendingOutput {
    fn drop(&mut self) {
        if let Some(tmp) = &self.tmp {
            forget_pending(tmp.path());
        }
    }
}

fn forget_pending(tmp: &Path) {
    PENDING_FILES
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .retain(|p| p != tmp);
}

/// The start of the temporary files' names of an output named `name`.
fn temporary_prefix(name: &std::ffi::OsStr) -> String {
    // Long names are cut (on a character boundary) to keep within file systems' limits.
    let name = name.to_string_lossy();
    let mut end = name.len().min(64);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    format!(".rt-gpu-{}-", &name[..end])
}

/// Removes temporary files of this output that no running process holds: what a killed render
/// (`kill -9`, a power cut) left behind.
fn remove_stale_temporaries(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        // The random part tempfile adds is 6 characters: longer names are another output's.
        let Some(rest) = name.strip_prefix(prefix) else {
            continue;
        };
        if rest.len() != 6 + ".tmp".len() || !rest.ends_with(".tmp") {
            continue;
        }
        let path = entry.path();
        if let Ok(file) = std::fs::OpenOptions::new().write(true).open(&path)
            && file.try_lock().is_ok()
            && std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file())
        {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// Where `path` leads once its directory and any link at it are resolved (the path itself
/// when it cannot be resolved), so that two spellings of one file compare equal.
pub fn resolved(path: &Path) -> PathBuf {
    if let Ok(canonical) = std::fs::canonicalize(path) {
        return canonical;
    }
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match (std::fs::canonicalize(dir), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => path.to_path_buf(),
    }
}

/// A lock held while a render owns a checkpoint file, so that a second render cannot
/// checkpoint to it at the same time. It lives beside the file (`.NAME.rt-gpu-lock`, since
/// the file itself is replaced at every write) and goes when the render ends.
pub struct FileLock {
    path: PathBuf,
    _file: std::fs::File,
}

impl FileLock {
    pub fn acquire(owned: &Path) -> anyhow::Result<FileLock> {
        let target = resolved(owned);
        let name = target
            .file_name()
            .with_context(|| format!("{} does not name a file", owned.display()))?;
        let path = target.with_file_name(format!(".{}.rt-gpu-lock", name.to_string_lossy()));
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .with_context(|| format!("cannot create the lock file {}", path.display()))?;
        match file.try_lock() {
            #[cfg(unix)]
            Ok(()) => {
                // A render that just ended may have removed the path we opened: then the lock
                // is on a file no one else will open; take the new one instead.
                use std::os::unix::fs::MetadataExt;
                let ours = file.metadata().map(|m| m.ino()).ok();
                if std::fs::metadata(&path).map(|m| m.ino()).ok() != ours {
                    return FileLock::acquire(owned);
                }
            }
            #[cfg(not(unix))]
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => anyhow::bail!(
                "{} is in use by another rt-gpu render: wait for it, or checkpoint elsewhere",
                owned.display()
            ),
            // A file system without locks: rendering goes on unguarded.
            Err(std::fs::TryLockError::Error(_)) => {}
        }
        Ok(FileLock { path, _file: file })
    }
}

impl Drop for FileLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Says what is wrong with `dir` as a place for an output file, if anything.
fn check_directory(dir: &Path) -> anyhow::Result<()> {
    if dir.is_dir() {
        return Ok(());
    }
    // Name the first ancestor that is in the way.
    for ancestor in dir.ancestors().collect::<Vec<_>>().into_iter().rev() {
        if ancestor.as_os_str().is_empty() {
            continue;
        }
        match std::fs::metadata(ancestor) {
            Ok(m) if m.is_dir() => continue,
            Ok(_) => anyhow::bail!(
                "{} is a file, not a directory: no output can go inside it",
                ancestor.display()
            ),
            Err(_) => break,
        }
    }
    anyhow::bail!("output directory {} does not exist", dir.display())
}
