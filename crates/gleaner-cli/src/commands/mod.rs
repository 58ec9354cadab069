//! One module per subcommand: each turns parsed arguments into an application-layer call and
//! its typed result into text, JSON or files. No lifecycle logic lives here.

pub mod bench;
pub mod cells;
pub mod crash;
pub mod demo;
pub mod evaluate;
pub mod explore;
pub mod export;
pub mod ingest;
pub mod init;
pub mod migrate;
pub mod missions;
pub mod plan;
pub mod reconstruct;
pub mod record;
pub mod replan;
pub mod score;
pub mod serve;
pub mod simulate;
pub mod synth;
