//! Finding and opening Intel Open Image Denoise 2 at run time (`libloading`), so that no build
//! or test needs it: the C functions rt-gpu calls, looked up once. Where it is looked for, in
//! order: `$OIDN_DIR/lib` (an OIDN installation, as its CMake package and the `oidn` crate name
//! it), the copy `scripts/install-oidn.py` unpacks into the user's cache
//! (`$XDG_CACHE_HOME/rt-gpu/oidn-2.5.1/lib`, else `~/.cache/...`), then the system's library
//! path. OIDN finds its CPU device module beside itself.

use libloading::{Library, Symbol};
use std::ffi::{c_char, c_void};
use std::path::{Path, PathBuf};

/// The version `scripts/install-oidn.py` installs, and the cache directory named after it.
pub const INSTALLED_VERSION: &str = "2.5.1";

/// OIDN 2's library, by its versioned name (its ABI is 2.x's).
#[cfg(target_os = "linux")]
const LIBRARY: &str = "libOpenImageDenoise.so.2";
#[cfg(target_os = "macos")]
const LIBRARY: &str = "libOpenImageDenoise.2.dylib";
#[cfg(windows)]
const LIBRARY: &str = "OpenImageDenoise.dll";

/// What to do where OIDN is not found: one line.
pub const INSTALL_HINT: &str = "run `python3 scripts/install-oidn.py` in rt-gpu's checkout (it fetches Intel's OIDN 2.5.1 from PyPI), or set OIDN_DIR to an OIDN 2 installation";

pub type Device = *mut c_void;
pub type Filter = *mut c_void;

/// OIDN's enums, as its header `oidn.h` numbers them.
pub const DEVICE_TYPE_CPU: i32 = 1;
pub const FORMAT_FLOAT3: i32 = 3;
pub const ERROR_NONE: i32 = 0;

/// The C functions rt-gpu calls, looked up once from the opened library (which they borrow).
pub struct Functions {
    pub new_device: unsafe extern "C" fn(i32) -> Device,
    pub set_device_int: unsafe extern "C" fn(Device, *const c_char, i32),
    pub get_device_int: unsafe extern "C" fn(Device, *const c_char) -> i32,
    pub commit_device: unsafe extern "C" fn(Device),
    pub release_device: unsafe extern "C" fn(Device),
    pub get_device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> i32,
    pub new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    pub set_shared_filter_image: unsafe extern "C" fn(
        Filter,
        *const c_char,
        *mut c_void,
        i32,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    pub set_filter_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    pub commit_filter: unsafe extern "C" fn(Filter),
    pub execute_filter: unsafe extern "C" fn(Filter),
    pub release_filter: unsafe extern "C" fn(Filter),
}

/// OIDN's library, open, and its functions.
pub struct Oidn {
    pub functions: Functions,
    /// Where it was found (the bare name: the system's library path), for the summary line.
    pub path: PathBuf,
    // Last: dropped after nothing can call into it.
    _library: Library,
}

/// Why OIDN could not be used: one line each.
#[derive(Debug, thiserror::Error)]
pub enum OidnError {
    #[error("Open Image Denoise 2 (OIDN) is not installed: {INSTALL_HINT}")]
    NotFound,
    #[error("cannot load Open Image Denoise from {path}: {message}; {INSTALL_HINT}")]
    Broken { path: String, message: String },
    #[error("Open Image Denoise failed: {0}")]
    Failed(String),
}

/// The places OIDN is looked for, in order: each a library file to open, or the bare name the
/// system's loader resolves.
pub fn candidates() -> Vec<PathBuf> {
    let mut found = Vec::new();
    if let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) {
        found.push(Path::new(&dir).join("lib").join(LIBRARY));
    }
    if let Some(cache) = cache_dir() {
        found.push(cache.join("lib").join(LIBRARY));
    }
    found.push(PathBuf::from(LIBRARY));
    found
}

/// Where `scripts/install-oidn.py` unpacks OIDN: `$XDG_CACHE_HOME/rt-gpu/oidn-VERSION`, else
/// `~/.cache/rt-gpu/oidn-VERSION` (the script says the same).
pub fn cache_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))?;
    Some(
        base.join("rt-gpu")
            .join(format!("oidn-{INSTALLED_VERSION}")),
    )
}

impl Oidn {
    /// Opens the first OIDN found among [`candidates`]. A file that is there but does not load
    /// (or lacks a function) is an error, not passed over: the user meant that one.
    pub fn open() -> Result<Oidn, OidnError> {
        for (i, candidate) in candidates().into_iter().enumerate() {
            let bare = candidate.components().count() == 1;
            if !bare && !candidate.exists() {
                if i == 0 && std::env::var_os("OIDN_DIR").is_some_and(|d| !d.is_empty()) {
                    // Named by the user: its absence is the error, not a reason to look on.
                    return Err(OidnError::Broken {
                        path: candidate.display().to_string(),
                        message: "no such file (from OIDN_DIR)".into(),
                    });
                }
                continue;
            }
            // SAFETY: loading runs the library's initialisers; OIDN's are its own (and TBB's).
            let library = match unsafe { Library::new(&candidate) } {
                Ok(library) => library,
                // None on the system's path; one there that does not load (a dependency
                // missing, another architecture) is an error.
                Err(e) if bare && absent(&e.to_string()) => continue,
                Err(e) => {
                    return Err(OidnError::Broken {
                        path: candidate.display().to_string(),
                        message: one_line(&e.to_string()),
                    });
                }
            };
            let path = if bare {
                PathBuf::from(LIBRARY)
            } else {
                candidate
            };
            return Oidn::from_library(library, path);
        }
        Err(OidnError::NotFound)
    }

    fn from_library(library: Library, path: PathBuf) -> Result<Oidn, OidnError> {
        let broken = |e: libloading::Error| OidnError::Broken {
            path: path.display().to_string(),
            message: one_line(&e.to_string()),
        };
        macro_rules! function {
            ($name:literal) => {{
                // SAFETY: the symbol's type is its declaration in OIDN 2's oidn.h.
                let symbol: Symbol<_> =
                    unsafe { library.get(concat!($name, "\0").as_bytes()) }.map_err(broken)?;
                *symbol
            }};
        }
        let functions = Functions {
            new_device: function!("oidnNewDevice"),
            set_device_int: function!("oidnSetDeviceInt"),
            get_device_int: function!("oidnGetDeviceInt"),
            commit_device: function!("oidnCommitDevice"),
            release_device: function!("oidnReleaseDevice"),
            get_device_error: function!("oidnGetDeviceError"),
            new_filter: function!("oidnNewFilter"),
            set_shared_filter_image: function!("oidnSetSharedFilterImage"),
            set_filter_bool: function!("oidnSetFilterBool"),
            commit_filter: function!("oidnCommitFilter"),
            execute_filter: function!("oidnExecuteFilter"),
            release_filter: function!("oidnReleaseFilter"),
        };
        Ok(Oidn {
            functions,
            path,
            _library: library,
        })
    }
}

/// Whether the loader's message says OIDN's library itself is not there (not a dependency).
fn absent(message: &str) -> bool {
    message.contains(&format!("{LIBRARY}: cannot open shared object file"))
}

/// A loader's message on one line.
fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}
