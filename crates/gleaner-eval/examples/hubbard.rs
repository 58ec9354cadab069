//! Runs the peer protocol on Hubbard Brook hourly water content (both depths) and prints the
//! Markdown summary: `cargo run --release -p gleaner-eval --example hubbard -- DATA [OUT_DIR]`
//! (`gleaner evaluate peer --on hubbard-brook` is the user-facing form). With `OUT_DIR`, each
//! depth's outcomes are written there as CSV.
use std::path::PathBuf;

use gleaner_eval::hubbard::{self, Depth};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let data = PathBuf::from(args.get(1).map_or("../shared/data", String::as_str));
    for depth in Depth::ALL {
        let loaded = hubbard::load(&data.join("hubbard_brook"), depth)?;
        let out = hubbard::run(loaded, |done, total| eprint!("\r{done}/{total}"))?;
        eprintln!();
        println!("{}", out.summary());
        if let Some(dir) = args.get(2) {
            std::fs::create_dir_all(dir)?;
            let name = match depth {
                Depth::Shallow => "shallow",
                Depth::Cm50 => "cm50",
            };
            std::fs::write(
                PathBuf::from(dir).join(format!("hubbard-{name}.csv")),
                out.mean.outcomes_csv(),
            )?;
        }
    }
    Ok(())
}
