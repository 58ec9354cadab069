//! One module per subcommand. Each takes plain settings (already parsed from the command line)
//! and returns values or text; only `main.rs` knows clap.

pub mod bench;
pub mod cells;
pub mod demo;
pub mod explore;
pub mod export;
pub mod ingest;
pub mod init;
pub mod plan;
pub mod record;
pub mod score;
pub mod synth;
