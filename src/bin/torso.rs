//! The `torso` command-line tool; see `torso --help`.

#[cfg(unix)]
unsafe extern "C" {
    /// The C library's `signal(2)`, linked into every Unix program.
    fn signal(signum: i32, handler: usize) -> usize;
}

/// Restores the default action of SIGPIPE (terminate quietly), as command-line tools expect:
/// `torso simulate | head` then ends when `head` closes the pipe instead of panicking on the
/// failed write (the Rust runtime ignores SIGPIPE, so every print would fail with EPIPE).
/// SIGPIPE is 13 and SIG_DFL is 0 on Linux and macOS.
#[cfg(unix)]
fn default_sigpipe() {
    // SAFETY: installing the default disposition of one signal, before any thread starts.
    unsafe {
        signal(13, 0);
    }
}

#[cfg(not(unix))]
fn default_sigpipe() {}

fn main() {
    default_sigpipe();
    std::process::exit(breathing_torso::cli::main());
}
