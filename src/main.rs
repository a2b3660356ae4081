//! The `rt-gpu` command line (see `cli/`).

use std::io::Write;
use std::process::ExitCode;

/// Prints a line to stdout. A closed pipe or a full device is an error to return with `?`,
/// never a panic (`println!` panics).
macro_rules! say {
    ($($arg:tt)*) => { writeln!(std::io::stdout().lock(), $($arg)*) };
}

/// Prints a line to stderr, ignoring failure: there is nowhere left to report it.
macro_rules! note {
    ($($arg:tt)*) => {{ let _ = writeln!(std::io::stderr().lock(), $($arg)*); }};
}

mod cli;

/// Large allocations on huge pages (`cli/huge_pages.rs`).
#[cfg(target_os = "linux")]
#[global_allocator]
static ALLOCATOR: cli::huge_pages::HugePages = cli::huge_pages::HugePages;

use clap::Parser;
use cli::args::{Cli, Command};
use cli::one_line;

fn main() -> ExitCode {
    // Checked when the binary was loaded (`cli/host_cpu.c`'s constructor), before the runtime
    // ran this crate's allocator; again here, before code built for this CPU's instructions
    // runs on one without them: main itself is only this test and a call. This call is also
    // what links host_cpu.c's object, and with it the constructor, into the binary.
    if !cli::host_cpu::runs_here() {
        return ExitCode::FAILURE;
    }
    run()
}

#[inline(never)]
fn run() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's Vulkan drivers print an "error:" line on every start without it.
        // SAFETY: nothing else runs yet: no other thread can read the environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    // A bug is one line too, never a backtrace.
    std::panic::set_hook(Box::new(|info| {
        if rt_gpu::panics_are_quiet() {
            return;
        }
        note!(
            "error: internal error, a bug in rt-gpu (please report it): {}",
            one_line(&info.to_string())
        )
    }));
    cli::signals::install_signal_handler();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return clap_error(e),
    };
    let result = match cli.command {
        Some(Command::Scenes { export, force }) => {
            cli::scenes::list_scenes(export.as_deref(), force)
        }
        #[cfg(feature = "viewer")]
        Some(Command::View(args)) => cli::view::view(&args),
        Some(Command::Devices) => cli::devices::list_devices(),
        Some(Command::Bench(args)) => cli::bench::bench(&args),
        Some(Command::Converge(args)) => cli::converge::converge(&args),
        Some(Command::Merge(args)) => cli::merge::merge(&args),
        None => cli::render::run_render(&cli.render),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`rt-gpu scenes | head -1`): stop quietly, as `cat` would.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            note!("error: {}", one_line(&format!("{e:#}")));
            ExitCode::FAILURE
        }
    }
}

/// `--help` and `--version` as clap prints them; a mistake in the arguments as one line, as
/// every other error (clap adds usage and "For more information" lines).
fn clap_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = e.print();
        return ExitCode::from(e.exit_code() as u8);
    }
    let rendered = e.render().to_string();
    let first = rendered
        .lines()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("error: invalid arguments");
    // clap's tips ("to pass '-1' as a value, use '-- -1'") would make -1 the scene: dropped.
    let hint = rendered
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("tip:") && !l.contains("'--'") && !l.contains("-- "))
        .map_or(String::new(), |tip| format!(" ({tip})"));
    note!(
        "{}{hint} (rt-gpu --help lists the options)",
        first.trim_end()
    );
    ExitCode::from(2)
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
