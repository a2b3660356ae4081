//! The files a scene reads (images, meshes, material libraries, glTF buffers), each with a digest
//! of its bytes taken as it is read. Outputs must not overwrite them (`output::PendingOutput`),
//! and a film's identity holds their digests, so that films of a scene whose files changed
//! neither resume nor merge (`film_file::identity`).
//!
//! Loaders read through [`read`], which opens the file once, checks the handle it opened (a
//! regular file, within a size), reads it and digests the bytes; a [`recorded`] scope collects
//! what was read under it on this thread (and on threads that [`Recorders::install`] it). Caches
//! of decoded files keep what their loading recorded and [`note`] it again on a hit.

use std::cell::RefCell;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A file a scene read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputFile {
    /// As the scene names it (relative to the folder of the file that names it): a film's
    /// identity holds this name, so that shards rendered in other folders agree.
    pub shown: String,
    /// Where it is on this machine, symbolic links resolved.
    pub path: PathBuf,
    /// The first 128 bits of the BLAKE3 hash of its bytes.
    pub digest: [u8; 16],
}

impl InputFile {
    /// The digest in hexadecimal.
    pub fn hex_digest(&self) -> String {
        self.digest.iter().map(|b| format!("{b:02x}")).collect()
    }
}

/// The digest [`InputFile`] keeps of `bytes`.
pub fn digest(bytes: &[u8]) -> [u8; 16] {
    let hash = blake3::hash(bytes);
    let mut digest = [0u8; 16];
    digest.copy_from_slice(&hash.as_bytes()[..16]);
    digest
}

type Log = Arc<Mutex<Vec<InputFile>>>;

thread_local! {
    /// The recordings open on this thread, innermost last.
    static RECORDING: RefCell<Recorders> = const { RefCell::new(Recorders(Vec::new())) };
}

/// The recordings open on a thread, to be installed on another that reads for it.
#[derive(Clone, Default)]
pub struct Recorders(Vec<Log>);

impl Recorders {
    /// Those of this thread.
    pub fn current() -> Self {
        RECORDING.with(|r| r.borrow().clone())
    }

    /// Runs `f` with these recordings open on this thread (a thread that reads files for
    /// another).
    pub fn install<R>(&self, f: impl FnOnce() -> R) -> R {
        let previous = RECORDING.with(|r| r.replace(self.clone()));
        let _restore = Restore(Some(previous));
        f()
    }
}

/// Puts a thread's previous recordings back, however the scope ends.
struct Restore(Option<Recorders>);

impl Drop for Restore {
    fn drop(&mut self) {
        if let Some(previous) = self.0.take() {
            RECORDING.with(|r| *r.borrow_mut() = previous);
        }
    }
}

/// Runs `f` and returns what it read, each file once (by `path`, the first reading kept), in
/// the order first read. Files read in a nested recording reach this one too.
pub fn recorded<R>(f: impl FnOnce() -> R) -> (R, Vec<InputFile>) {
    let log: Log = Default::default();
    let mut inner = Recorders::current();
    inner.0.push(log.clone());
    let result = inner.install(f);
    let files = std::mem::take(&mut *log.lock().unwrap_or_else(|p| p.into_inner()));
    (result, files)
}

/// Records `file` as read in the open recordings (a cache handing out what it decoded before).
pub fn note(file: &InputFile) {
    RECORDING.with(|r| {
        for log in &r.borrow().0 {
            let mut files = log.lock().unwrap_or_else(|p| p.into_inner());
            if !files.iter().any(|f| f.path == file.path) {
                files.push(file.clone());
            }
        }
    });
}

/// Reads the regular file at `path` of at most `max_bytes`, recording it as `shown`; returns
/// its bytes and what was recorded. The path is looked at before it is opened (opening a FIFO
/// would wait) and the handle opened is checked again before it is read, so the file checked
/// is the file read. The error is the reason alone, for the caller to say which file it is.
pub fn read(path: &Path, shown: &str, max_bytes: u64) -> Result<(Vec<u8>, InputFile), String> {
    // Opening a FIFO waits for a writer: what is not a regular file is not opened at all.
    if !std::fs::metadata(path)
        .map_err(|e| e.to_string())?
        .is_file()
    {
        return Err("it is not a regular file".into());
    }
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let meta = file.metadata().map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("it is not a regular file".into());
    }
    if meta.len() > max_bytes {
        return Err(format!(
            "it is {} bytes, more than the {max_bytes} rt-gpu reads",
            meta.len()
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // A file that grows while it is read stops at the limit.
    file.take(max_bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > max_bytes {
        return Err(format!("it grew beyond the {max_bytes} bytes rt-gpu reads"));
    }
    let input = InputFile {
        shown: shown.to_string(),
        path: path.canonicalize().unwrap_or_else(|_| path.to_path_buf()),
        digest: digest(&bytes),
    };
    note(&input);
    Ok((bytes, input))
}

/// The fields of a film's identity that hold `files`' digests (`film_file::identity`).
pub fn identity_fields(files: &[InputFile]) -> Vec<String> {
    files
        .iter()
        .map(|f| crate::film::file::file_field(&f.shown, &f.hex_digest()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_collects_each_file_once_and_nested_ones_reach_the_outer() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.bin");
        let b = dir.path().join("b.bin");
        std::fs::write(&a, b"one").unwrap();
        std::fs::write(&b, b"two").unwrap();
        let ((), outer) = recorded(|| {
            read(&a, "a.bin", 10).unwrap();
            let ((), inner) = recorded(|| {
                read(&b, "b.bin", 10).unwrap();
                read(&a, "a.bin", 10).unwrap();
            });
            assert_eq!(inner.len(), 2);
            // On another thread, with this thread's recordings installed.
            let recorders = Recorders::current();
            std::thread::scope(|s| {
                s.spawn(|| recorders.install(|| read(&b, "b.bin", 10).unwrap()));
            });
        });
        let shown: Vec<&str> = outer.iter().map(|f| f.shown.as_str()).collect();
        assert_eq!(shown, ["a.bin", "b.bin"]);
        assert_eq!(outer[0].digest, digest(b"one"));
        assert_ne!(outer[0].digest, outer[1].digest);
        // Nothing is recorded outside a recording.
        assert!(RECORDING.with(|r| r.borrow().0.is_empty()));
    }

    #[test]
    fn only_regular_files_within_the_limit_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.bin");
        std::fs::write(&big, [0u8; 11]).unwrap();
        let err = read(&big, "big.bin", 10).unwrap_err();
        assert!(err.contains("11 bytes"), "{err}");
        let err = read(dir.path(), "dir", 10).unwrap_err();
        assert!(err.contains("not a regular file"), "{err}");
        #[cfg(unix)]
        {
            let err = read(Path::new("/dev/zero"), "zero", 10).unwrap_err();
            assert!(err.contains("not a regular file"), "{err}");
        }
    }
}
