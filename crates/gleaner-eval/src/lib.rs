//! Reproducible evaluations of gleaner's field model and sensor choice on published
//! protocols, with every number recomputed from the data files.
//!
//! [`peer`] is the one-shot sensor-selection protocol of a peer study on the Cook Agronomy
//! Farm network: sensors laid out in a box with a depot at (0, 0), a UAV tour from the depot
//! within an energy capacity (J per metre flown plus J per sensor visited), the visited
//! sensors observed at every test hour, the unvisited ones estimated from what is known, and
//! the error summed over the unvisited sensors. gleaner chooses the sensors by the
//! information its field model expects from them ([`gleaner_orienteering::solve_marginal`]
//! over [`gleaner_kriging::DynamicModel::remaining_variance`]) and estimates them with each
//! estimator side by side.
//!
//! [`hubbard`] runs the same protocol on another network's hourly data (Hubbard Brook), a
//! hold-out no setting was chosen on: windows at the peer's horizon, capacities scaled to
//! the layout.
//!
//! [`run_peer`] runs either from the shared data directory and writes its files.
//!
//! Units: positions metres, energies J, times seconds, values in the modality's unit
//! (errors in its square).
#![deny(missing_docs)]

pub mod hubbard;
pub mod peer;
mod run;

pub use run::{PeerRun, run_peer};

use std::path::PathBuf;

use thiserror::Error;

/// A file of an evaluation that cannot be used.
#[derive(Debug, Error)]
pub enum EvalError {
    /// The file cannot be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A row or field of the file is not what the protocol needs.
    #[error("{path}:{line}: field `{field}`: {message}")]
    Bad {
        /// The file.
        path: PathBuf,
        /// 1-based line (0: the file as a whole).
        line: u64,
        /// The column.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The readings could not be read.
    #[error(transparent)]
    Ingest(#[from] gleaner_ingest::IngestError),
    /// A protocol's data could not be loaded from the shared data directory `dir`.
    #[error("{} (set GLEANER_DATA_DIR): {source}", dir.display())]
    Load {
        /// The directory.
        dir: PathBuf,
        /// Why.
        source: Box<EvalError>,
    },
    /// The data are not enough for the protocol.
    #[error("{0}")]
    Data(String),
}
