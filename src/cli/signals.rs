//! Unix signals: a checkpointing render stops gracefully at the first; otherwise temporary
//! outputs are removed and the process exits.

use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

/// Set while a render can stop gracefully (it checkpoints): a first signal then asks it to stop.
pub static GRACEFUL: AtomicBool = AtomicBool::new(false);
/// The signal that asked a graceful render to stop (0: none).
pub static STOP_SIGNAL: AtomicI32 = AtomicI32::new(0);

/// On SIGINT, SIGTERM or SIGHUP: during a checkpointing render, the first asks it to finish the
/// pass in flight, write the checkpoint and the image so far, and exit with 128 + the signal.
/// Otherwise (or at a second signal) remove temporary output files (a killed process runs no
/// destructors, and they can be as large as the image) and exit with 128 + the signal.
#[cfg(unix)]
pub fn install_signal_handler() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        for signal in signals.forever() {
            if GRACEFUL.load(Ordering::SeqCst)
                && STOP_SIGNAL
                    .compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst)
                    .is_ok()
            {
                note!(
                    "\nstopping: finishing this pass (at most 10 s), then writing the checkpoint and the image (signal again to quit at once)"
                );
                continue;
            }
            rt_gpu::film::output::remove_pending_files();
            if GRACEFUL.load(Ordering::SeqCst) {
                note!("\ninterrupted: the last checkpoint is kept");
            } else {
                note!("\ninterrupted: nothing was written");
            }
            std::process::exit(128 + signal);
        }
    });
}

#[cfg(not(unix))]
pub fn install_signal_handler() {}
