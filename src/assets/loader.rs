//! The loader a scene file's parse reads its images and meshes through: it owns the directory
//! the file's relative paths start from (the file's own; the working directory for text that
//! came from no file), as pbrt-v4's scene loader owns its search directory and hands
//! `Material::Create` the images it read.
//!
//! Materials are read by serde, which passes no context to a type's deserialiser: the parse
//! makes its loader the thread's own for its duration ([`Loader::during`]), and the texture,
//! normal-map and material readers ask for it ([`image`], [`data_image`]). Outside a parse there
//! is none, and naming an image file is an error, not a path silently taken from the working
//! directory (a deserialiser run on another thread, say).

use super::image::Image;
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Reads the files a scene names, relative to `base_dir` (absolute paths as they are).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Loader {
    base_dir: PathBuf,
}

thread_local! {
    /// The loader of the parse running on this thread, if any.
    static CURRENT: RefCell<Option<Loader>> = const { RefCell::new(None) };
}

impl Loader {
    /// Paths relative to `base_dir`.
    pub fn new(base_dir: &Path) -> Self {
        Loader {
            base_dir: base_dir.to_path_buf(),
        }
    }

    /// The loader of the scene file at `path`: paths relative to its directory.
    pub fn for_file(path: &Path) -> Self {
        Self::new(path.parent().unwrap_or(Path::new(".")))
    }

    /// Paths relative to the working directory (scene text that came from no file).
    pub fn working_directory() -> Self {
        Self::new(Path::new(""))
    }

    /// The path a scene names as `source`.
    pub fn resolve(&self, source: &str) -> PathBuf {
        let path = Path::new(source);
        if path.is_relative() {
            self.base_dir.join(path)
        } else {
            path.to_path_buf()
        }
    }

    /// The colour image a scene names as `source` (8- and 16-bit values decoded from sRGB).
    pub fn image(&self, source: &str) -> Result<Arc<Image>, String> {
        super::image::load(&self.resolve(source), source)
    }

    /// The data image (a normal map, a parameter image) a scene names as `source` (8- and
    /// 16-bit values linear).
    pub fn data_image(&self, source: &str) -> Result<Arc<Image>, String> {
        super::image::load_as(&self.resolve(source), source, false)
    }

    /// Runs `f` (a parse) with this loader as the thread's own; the previous one is back
    /// however `f` ends.
    pub fn during<R>(&self, f: impl FnOnce() -> R) -> R {
        struct Restore(Option<Loader>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let previous = self.0.take();
                CURRENT.with(|c| *c.borrow_mut() = previous);
            }
        }
        let _restore = Restore(CURRENT.with(|c| c.replace(Some(self.clone()))));
        f()
    }
}

/// The running parse's loader: an error where none runs.
fn current(source: &str) -> Result<Loader, String> {
    CURRENT.with(|c| c.borrow().clone()).ok_or_else(|| {
        format!("image {source} is named outside a scene file's parse: no loader to read it (rt-gpu bug)")
    })
}

/// The colour image the scene being parsed names as `source` ([`Loader::image`]).
pub fn image(source: &str) -> Result<Arc<Image>, String> {
    current(source)?.image(source)
}

/// The data image the scene being parsed names as `source` ([`Loader::data_image`]).
pub fn data_image(source: &str) -> Result<Arc<Image>, String> {
    current(source)?.data_image(source)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_start_at_the_base_directory_and_need_a_parse() {
        let loader = Loader::for_file(Path::new("scenes/blender/bumpy.toml"));
        assert_eq!(loader.resolve("a.png"), Path::new("scenes/blender/a.png"));
        assert_eq!(loader.resolve("/tmp/a.png"), Path::new("/tmp/a.png"));
        let err = image("a.png").unwrap_err();
        assert!(err.contains("outside a scene file"), "{err}");
        let inner = Loader::new(Path::new("inner"));
        let err = loader.during(|| {
            inner.during(|| assert_eq!(current("x").unwrap(), inner));
            image("no-such.png").unwrap_err()
        });
        assert!(err.contains("no-such.png"), "{err}");
        assert!(current("x").is_err(), "the loader is gone after its parse");
    }
}
