//! Progress bars: drawn on a terminal, silent when stderr is piped or redirected.

use std::io::IsTerminal;
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar over `len` steps labelled `what`, or a hidden one when stderr is not a
/// terminal (so piped output stays clean).
pub fn bar(len: u64, what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

/// A spinner with a message, for a step of unknown length, or a hidden one when stderr is not
/// a terminal.
pub fn spinner(what: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_message(what.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}

/// The application layer's progress, shown as bars and spinners on a terminal.
#[derive(Default)]
pub struct Terminal {
    current: Mutex<Option<ProgressBar>>,
}

impl gleaner_app::Progress for Terminal {
    fn start(&self, what: &str, total: Option<u64>) {
        let pb = match total {
            Some(n) => bar(n, what),
            None => spinner(what),
        };
        if let Ok(mut c) = self.current.lock()
            && let Some(old) = c.replace(pb)
        {
            old.finish_and_clear();
        }
    }
    fn advance(&self, n: u64) {
        if let Ok(c) = self.current.lock()
            && let Some(pb) = c.as_ref()
        {
            pb.inc(n);
        }
    }
    fn finish(&self) {
        if let Ok(mut c) = self.current.lock()
            && let Some(pb) = c.take()
        {
            pb.finish_and_clear();
        }
    }
}
