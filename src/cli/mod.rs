//! The `rt-gpu` command line, one file per subcommand: `render` (the default: a scene to an
//! image, run by the library's `render::request`), `view` (a window), `scenes`, `devices`,
//! `bench`, `converge` and `merge`; `args` is the syntax of them all, `signals` how a render stops on Ctrl-C. The
//! library renders; these files parse options, draw progress bars and print summaries.

pub mod args;
pub mod bench;
pub mod converge;
pub mod devices;
pub mod host_cpu;
#[cfg(target_os = "linux")]
pub mod huge_pages;
pub mod merge;
pub mod render;
pub mod scenes;
pub mod signals;
#[cfg(feature = "viewer")]
pub mod view;

/// Most characters of an error message: a scene can hold names megabytes long.
pub const MAX_MESSAGE_CHARS: usize = 600;

/// `message` on one line, its middle cut out if it is too long.
pub fn one_line(message: &str) -> String {
    let flat = message.replace(['\n', '\r'], " ");
    let count = flat.chars().count();
    if count <= MAX_MESSAGE_CHARS {
        return flat;
    }
    let keep = MAX_MESSAGE_CHARS / 2;
    let head: String = flat.chars().take(keep).collect();
    let tail: String = flat.chars().skip(count - keep).collect();
    format!("{head} [... {} characters ...] {tail}", count - 2 * keep)
}

/// A mean radiance as the summary line shows it: five decimals where that shows five
/// significant digits' worth, else in scientific notation (a dim or bright scene is not 0.00000).
pub fn shown_radiance(mean: glam::DVec3) -> String {
    let one = |x: f64| {
        if x == 0.0 || (1e-2..1e6).contains(&x.abs()) {
            format!("{x:.5}")
        } else {
            format!("{x:.4e}")
        }
    };
    format!("({}, {}, {})", one(mean.x), one(mean.y), one(mean.z))
}

/// A number a user gave, as a message shows it: plainly where that is short, else in
/// scientific notation (`--target-error 1e-300` is not 300 zeros).
pub fn shown_number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
