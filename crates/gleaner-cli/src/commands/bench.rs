//! `gleaner bench op`: runs a route planner over standard orienteering benchmark files and
//! tabulates the scores against the known targets.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use gleaner_op_formats::{BenchRow, benchmark_files, format_csv, format_table, run_benchmark};
use gleaner_orienteering::{SolveOptions, SolverKind};

use crate::progress;

// The arguments of `gleaner bench op` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct BenchOpArgs {
    /// A benchmark file, or a directory searched recursively.
    pub path: PathBuf,
    /// Solver: default, greedy (the paper's heuristic) or exact (small instances).
    #[arg(long, default_value = "default")]
    pub solver: String,
    /// Time limit per instance, seconds.
    #[arg(long, default_value_t = 1.0)]
    pub time_limit: f64,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Skip instances with more nodes than this.
    #[arg(long)]
    pub max_n: Option<usize>,
    /// Also write the rows as CSV to this file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Stop an instance after this many iterations without a new best; 0 (the default)
    /// searches for the whole time limit.
    #[arg(long, default_value_t = 0)]
    pub max_stall: u64,
    /// Stop each instance after this many search iterations, so that results do not depend
    /// on the machine's speed (the time limit still applies).
    #[arg(long)]
    pub iterations: Option<u64>,
    /// Also write every route (node ids as numbered in the instance file) to this file, so
    /// anyone can re-check a score with their own tools.
    #[arg(long)]
    pub routes: Option<PathBuf>,
}

/// Runs the benchmark; returns the table with its summary line.
pub fn run(args: &BenchOpArgs) -> Result<(Vec<BenchRow>, String)> {
    let files = benchmark_files(&args.path, args.max_n)?;
    if files.is_empty() {
        bail!("{}: no benchmark instances found", args.path.display());
    }
    let solver: SolverKind = args.solver.parse().map_err(anyhow::Error::msg)?;
    let mut options = SolveOptions::default()
        .with_time_limit(
            gleaner_orienteering::time_limit_from_secs(args.time_limit).context("--time-limit")?,
        )
        .with_seed(args.seed);
    options.max_stall = (args.max_stall > 0).then_some(args.max_stall);
    options.max_iterations = args.iterations;
    let pb = progress::bar(files.len() as u64, "solving");
    let rows = run_benchmark(&files, solver, &options, &mut |done, _, row| {
        pb.set_position(done as u64);
        pb.set_message(row.instance.clone());
    })?;
    pb.finish_and_clear();
    if let Some(csv) = &args.csv {
        std::fs::write(csv, format_csv(&rows))
            .with_context(|| format!("{}: cannot write", csv.display()))?;
    }
    if let Some(path) = &args.routes {
        let file = std::fs::File::create(path)
            .with_context(|| format!("{}: cannot create", path.display()))?;
        let mut w = std::io::BufWriter::new(file);
        gleaner_op_formats::write_routes(&rows, &mut w)
            .and_then(|()| std::io::Write::flush(&mut w))
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    let table = format_table(&rows);
    Ok((rows, table))
}
