//! Runs the benchmark over files or directories given on the command line.
//!
//! `cargo run --release -p gleaner-op-formats --example run_bench -- [--secs S] [--greedy] [--max-n N] [--stall K] [--csv FILE] [--routes FILE] PATH...`

use gleaner_op_formats::{find_instances, format_csv, format_table, run_benchmark, write_routes};
use gleaner_orienteering::{SolveOptions, SolverKind, time_limit_from_secs};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut secs = 1.0;
    let mut kind = SolverKind::Default;
    let mut max_n = usize::MAX;
    let mut stall: Option<u64> = None;
    let mut csv: Option<PathBuf> = None;
    let mut routes: Option<PathBuf> = None;
    let mut seed = 0u64;
    let mut k: Option<usize> = None;
    let mut kicks: Option<usize> = None;
    let mut paths = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--secs" => secs = args.next().ok_or("--secs needs a value")?.parse()?,
            "--k" => k = Some(args.next().ok_or("--k needs a value")?.parse()?),
            "--kicks" => kicks = Some(args.next().ok_or("--kicks needs a value")?.parse()?),
            "--seed" => seed = args.next().ok_or("--seed needs a value")?.parse()?,
            "--greedy" => kind = SolverKind::Greedy,
            "--max-n" => max_n = args.next().ok_or("--max-n needs a value")?.parse()?,
            "--stall" => stall = Some(args.next().ok_or("--stall needs a value")?.parse()?),
            "--csv" => csv = Some(PathBuf::from(args.next().ok_or("--csv needs a value")?)),
            "--routes" => {
                routes = Some(PathBuf::from(args.next().ok_or("--routes needs a value")?))
            }
            p => {
                let p = PathBuf::from(p);
                if p.is_dir() {
                    paths.extend(find_instances(&p)?);
                } else {
                    paths.push(p);
                }
            }
        }
    }
    let mut selected = Vec::new();
    for p in paths {
        // Peek at the size without building the (n x n) problem.
        let text = std::fs::read_to_string(&p)?;
        let n = text
            .lines()
            .find_map(|l| l.trim().strip_prefix("DIMENSION"))
            .and_then(|v| {
                v.trim_start_matches([' ', ':'])
                    .trim()
                    .parse::<usize>()
                    .ok()
            })
            .unwrap_or_else(|| text.lines().count().saturating_sub(1));
        if n <= max_n {
            selected.push(p);
        }
    }
    let mut options = SolveOptions {
        time_limit: time_limit_from_secs(secs)?,
        max_stall: stall,
        seed,
        ..SolveOptions::default()
    };
    if let Some(k) = k {
        options.neighbours = k;
    }
    if let Some(kicks) = kicks {
        options.kicks = kicks;
    }
    let rows = run_benchmark(&selected, kind, &options, &mut |k, total, row| {
        eprintln!(
            "[{k}/{total}] {} n={} target={:?} ours={} gap={:?} {:.2}s feasible={}",
            row.instance, row.n, row.target, row.ours, row.gap_pct, row.seconds, row.feasible
        );
    })?;
    print!("{}", format_table(&rows));
    if let Some(c) = csv {
        std::fs::write(c, format_csv(&rows))?;
    }
    if let Some(r) = routes {
        let mut out = std::io::BufWriter::new(std::fs::File::create(r)?);
        write_routes(&rows, &mut out)?;
    }
    Ok(())
}
