//! Progress of long use cases, reported to whatever the adapter shows (a terminal bar, a log,
//! nothing).

/// Receives progress; every method has a do-nothing default.
pub trait Progress {
    /// A step starts: `what` it is and, when known, how many units it has.
    fn start(&self, what: &str, total: Option<u64>) {
        let _ = (what, total);
    }
    /// `n` more units of the current step are done.
    fn advance(&self, n: u64) {
        let _ = n;
    }
    /// The current step is done.
    fn finish(&self) {}
    /// Whether the caller gave up on the work: a long use case (a campaign) checks it between
    /// units of work and stops with [`AppError::Cancelled`](crate::AppError::Cancelled).
    fn cancelled(&self) -> bool {
        false
    }
}

/// Reports nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {}
