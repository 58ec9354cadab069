//! `gleaner evaluate peer`'s run: one protocol from the shared data directory, its files
//! written into an output directory.

use std::path::Path;

use crate::EvalError;
use crate::{hubbard, peer};

/// Which evaluation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerRun {
    /// The peer protocol on CAF data.
    Caf(peer::PeerData),
    /// Every data set of a Hubbard Brook registration.
    Hubbard(hubbard::Registration),
}

/// Runs `on` from the shared data directory `data` with the unshared drift weight
/// `unshared_weight` (≥ 0; CAF only, 0 for Hubbard Brook) and writes its files into `out`
/// (created if missing): `outcomes.csv` (Hubbard Brook: one per data set), `summary.md`, and
/// with several windows `windows.csv`. `progress(done, total)` after each layout or window.
/// Returns the summary.
pub fn run_peer(
    data: &Path,
    out: &Path,
    on: PeerRun,
    unshared_weight: f64,
    progress: impl FnMut(usize, usize),
) -> Result<String, EvalError> {
    let load = |dir: &Path| {
        let dir = dir.to_path_buf();
        move |e: EvalError| EvalError::Load {
            dir,
            source: Box::new(e),
        }
    };
    let mut files: Vec<(String, String)> = match on {
        PeerRun::Caf(on) => {
            let loaded = peer::load_data(data, on).map_err(load(data))?;
            if !(unshared_weight.is_finite() && unshared_weight >= 0.0) {
                return Err(EvalError::Data(format!(
                    "--unshared-weight {unshared_weight}: expected a number >= 0"
                )));
            }
            let e = peer::evaluate(loaded, on, unshared_weight, progress)?;
            let windows = e.windows_csv.map(|w| ("windows.csv".to_string(), w));
            let rest = [
                ("outcomes.csv".to_string(), e.outcomes_csv),
                ("summary.md".to_string(), e.summary),
            ];
            windows.into_iter().chain(rest).collect()
        }
        PeerRun::Hubbard(registration) => {
            if unshared_weight != 0.0 {
                return Err(EvalError::Data(
                    "--unshared-weight is not used with --on hubbard-brook".into(),
                ));
            }
            let dir = data.join("hubbard_brook");
            let e = hubbard::evaluate(&dir, registration, progress).map_err(load(&dir))?;
            let mut files = e.outcomes;
            files.push(("summary.md".to_string(), e.summary));
            files
        }
    };
    let cannot = |what: &str, path: &Path, e: std::io::Error| {
        EvalError::Data(format!("cannot {what} {}: {e}", path.display()))
    };
    std::fs::create_dir_all(out).map_err(|e| cannot("create", out, e))?;
    for (name, text) in &files {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| cannot("write", &path, e))?;
    }
    // summary.md comes last.
    Ok(files.pop().map(|(_, summary)| summary).unwrap_or_default())
}
