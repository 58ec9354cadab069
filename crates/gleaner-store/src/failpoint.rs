//! Crash injection for the crash-safety harness: with `GLEANER_CRASH_AFTER=N` in the
//! environment, the process kills itself with SIGKILL at the N-th write step (N >= 1) of the
//! store, where a write step is one statement or one block of bulk-loaded rows of a write
//! transaction, or its commit. Unset (the normal case), a step costs one relaxed atomic load.
//!
//! The harness (`gleaner crash-test`, see the README) first runs a use case with
//! `GLEANER_CRASH_REPORT=<file>`, where the store writes its step count after every commit,
//! to learn how many steps the use case makes; then it kills copies of it at chosen steps.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU64, Ordering};

/// The configured kill step (0: never), read once from the environment.
fn limit() -> u64 {
    static LIMIT: OnceLock<u64> = OnceLock::new();
    *LIMIT.get_or_init(|| {
        std::env::var("GLEANER_CRASH_AFTER")
            .ok()
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or(0)
    })
}

static STEPS: AtomicU64 = AtomicU64::new(0);

/// Write steps taken so far by this process.
pub fn steps() -> u64 {
    STEPS.load(Ordering::Relaxed)
}

/// Counts one write step; at the configured step, kills the process with SIGKILL (no
/// destructors, no rollback, no flush: what a power cut or the OOM killer does to a client).
pub(crate) fn step() {
    let n = STEPS.fetch_add(1, Ordering::Relaxed) + 1;
    let at = limit();
    if at != 0 && n == at {
        kill_self();
    }
}

/// Sends SIGKILL to this process with the system's `kill` command (the crate forbids `unsafe`,
/// so no direct syscall), then waits for it to land.
fn kill_self() -> ! {
    let pid = std::process::id().to_string();
    let _ = std::process::Command::new("kill")
        .args(["-KILL", &pid])
        .status();
    // SIGKILL cannot be caught; if `kill` could not be run, abort (SIGABRT) instead.
    std::process::abort();
}

/// After a commit: with `GLEANER_CRASH_REPORT=<file>` set, writes the number of write steps
/// taken so far to that file (for the harness to choose kill points).
pub(crate) fn committed() {
    if let Some(path) = std::env::var_os("GLEANER_CRASH_REPORT") {
        // Best effort: the report is a test aid, never a reason to fail a committed write.
        let _ = std::fs::write(path, steps().to_string());
    }
}
