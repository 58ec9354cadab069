//! `gleaner-fuzz`: runs the mutation fuzzer on one reader (or all, one after the other) for a
//! given time and prints executions, refusals and panics per target.
//!
//! ```sh
//! cargo run --release -p gleaner-benches --bin gleaner-fuzz -- --target all --seconds 600 --seed 1
//! ```

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, bail};
use clap::Parser;
use gleaner_benches::fuzz::{FuzzConfig, Target, fuzz};

/// Fuzz gleaner's readers of untrusted input with mutated and arbitrary bytes; a panic is a
/// bug (its input is saved), an error is the expected answer to bad input.
#[derive(Debug, Parser)]
#[command(
    name = "gleaner-fuzz",
    after_help = "Targets: sensors, long, wide, caf, hubbard-brook, hubbard-brook-metadata, cell-csv, flight, config, op-instance, all.\n\nExample:\n  gleaner-fuzz --target long --seconds 600 --seed 1"
)]
struct Args {
    /// Reader to fuzz, or `all` (each in turn, `--seconds` each).
    #[arg(long, default_value = "all")]
    target: String,
    /// Seconds per target.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Stop a target after this many executions.
    #[arg(long, default_value_t = u64::MAX)]
    max_execs: u64,
    /// Seed of the random choices.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Repository root (the corpus is read from its test data).
    #[arg(long, default_value = ".")]
    root: PathBuf,
    /// Where inputs that panicked are saved.
    #[arg(long, default_value = "target/fuzz-crashes")]
    crashes: PathBuf,
    /// Largest input, bytes.
    #[arg(long, default_value_t = 65_536)]
    max_len: usize,
    /// Folder for the per-execution input file (e.g. `/dev/shm`); default: the temporary folder.
    #[arg(long)]
    scratch: Option<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= 86_400.0) {
        bail!(
            "--seconds {}: expected a number of seconds in (0, 86400]",
            args.seconds
        );
    }
    let targets: Vec<Target> = if args.target == "all" {
        Target::ALL.to_vec()
    } else {
        vec![
            Target::from_name(&args.target)
                .with_context(|| format!("unknown target {:?} (see --help)", args.target))?,
        ]
    };
    let mut total_panics = 0;
    println!(
        "target\tseconds\texecs\texecs/s\taccepted\trefused\tpanics\tseeds\terror shapes\tslowest ms"
    );
    for target in targets {
        let config = FuzzConfig {
            target,
            seed: args.seed,
            duration: Duration::from_secs_f64(args.seconds),
            max_execs: args.max_execs,
            root: args.root.clone(),
            crashes: args.crashes.clone(),
            max_len: args.max_len,
            scratch: args.scratch.clone(),
        };
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new_spinner();
            bar.set_prefix(target.name());
            bar.set_style(
                indicatif::ProgressStyle::with_template("{prefix:>24} {spinner} {msg}")
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
            );
            bar
        });
        let report = fuzz(&config, |r| {
            if let Some(bar) = &bar {
                bar.set_message(format!(
                    "{:.0}/{:.0} s, {} execs, {} panics",
                    r.elapsed.as_secs_f64(),
                    args.seconds,
                    r.execs,
                    r.panics
                ));
                bar.tick();
            }
        })
        .with_context(|| format!("fuzzing {}", target.name()))?;
        if let Some(bar) = bar {
            bar.finish_and_clear();
        }
        let secs = report.elapsed.as_secs_f64();
        println!(
            "{}\t{:.0}\t{}\t{:.0}\t{}\t{}\t{}\t{}\t{}\t{:.1}",
            target.name(),
            secs,
            report.execs,
            report.execs as f64 / secs.max(1e-9),
            report.accepted,
            report.refused,
            report.panics,
            report.seeds,
            report.distinct_errors,
            report.slowest.as_secs_f64() * 1e3,
        );
        for (message, file) in &report.crashes {
            eprintln!("PANIC ({}): {message}", file.display());
        }
        total_panics += report.panics;
    }
    if total_panics > 0 {
        bail!(
            "{total_panics} panic(s); inputs saved in {}",
            args.crashes.display()
        );
    }
    Ok(())
}
