//! `gleaner bench op`: runs a route planner over standard orienteering benchmark files and
//! tabulates the scores against the known targets.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use gleaner_op_formats::{
    BenchRow, find_instances, format_csv, format_table, load_instance, run_benchmark,
};
use gleaner_orienteering::{SolveOptions, SolverKind};

use crate::progress;

/// Settings from the command line.
pub struct BenchOpArgs {
    /// A benchmark file or a directory searched recursively.
    pub path: PathBuf,
    /// Solver.
    pub solver: SolverKind,
    /// Time limit per instance, seconds.
    pub time_limit_s: f64,
    /// Seed.
    pub seed: u64,
    /// Skip instances with more nodes than this.
    pub max_n: Option<usize>,
    /// Also write the rows as CSV here.
    pub csv: Option<PathBuf>,
    /// Stop an instance after this many iterations without improvement (`None`: use the
    /// whole time limit).
    pub max_stall: Option<u64>,
    /// Stop each instance after this many search iterations (machine-independent results);
    /// the time limit still applies.
    pub iterations: Option<u64>,
    /// Also write every route here (node ids as in the instance files).
    pub routes: Option<PathBuf>,
}

/// Parses a solver name.
pub fn parse_solver(name: &str) -> Result<SolverKind> {
    Ok(match name {
        "default" => SolverKind::Default,
        "greedy" => SolverKind::Greedy,
        "exact" => SolverKind::Exact,
        other => bail!("unknown solver {other:?}: expected default, greedy or exact"),
    })
}

fn instances(path: &Path, max_n: Option<usize>) -> Result<Vec<PathBuf>> {
    let files = if path.is_dir() {
        find_instances(path)?
    } else if path.exists() {
        vec![path.to_path_buf()]
    } else {
        bail!("{}: no such file or directory", path.display());
    };
    let Some(max) = max_n else { return Ok(files) };
    let mut kept = Vec::new();
    for f in files {
        if load_instance(&f)?.n <= max {
            kept.push(f);
        }
    }
    Ok(kept)
}

/// Runs the benchmark; returns the table with its summary line.
pub fn run(args: &BenchOpArgs) -> Result<(Vec<BenchRow>, String)> {
    let files = instances(&args.path, args.max_n)?;
    if files.is_empty() {
        bail!("{}: no benchmark instances found", args.path.display());
    }
    let mut options = SolveOptions::default()
        .with_time_limit(
            gleaner_orienteering::time_limit_from_secs(args.time_limit_s)
                .context("--time-limit")?,
        )
        .with_seed(args.seed);
    options.max_stall = args.max_stall;
    options.max_iterations = args.iterations;
    let pb = progress::bar(files.len() as u64, "solving");
    let rows = run_benchmark(&files, args.solver, &options, &mut |done, _, row| {
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
