//! `gleaner demo`: the whole story on built-in data (a seeded synthetic farm) or on the real
//! CAF network — exploration sorties that visit every cell, then adaptive missions, each
//! planned, exported, flown in simulation, recorded with the readings brought back, and
//! followed by a rescoring. The lifecycle is `gleaner_campaign::demo`; this module writes the
//! missions' files and prints.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;
use gleaner_campaign::demo::{DemoFarm, DemoRequest, MISSIONS};

use crate::clock_now;
use crate::commands::{export, plan};
use crate::progress::Terminal;

// The arguments of `gleaner demo` (no doc comment: the variant's is the help).
#[derive(clap::Args)]
pub struct DemoArgs {
    /// Working directory; the files the demo writes there are replaced.
    #[arg(long, default_value = "gleaner-demo")]
    pub dir: PathBuf,
    /// The score the demo's project plans by (`gleaner`, the default, or the paper's S).
    #[arg(long, value_enum, default_value_t = crate::MethodArg::Gleaner)]
    pub method: crate::MethodArg,
    /// Seed of the synthetic farm.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of sensors.
    #[arg(long, default_value_t = 60)]
    pub sensors: usize,
    /// Days of history.
    #[arg(long, default_value_t = 180)]
    pub days: u32,
    /// Run on the real CAF network instead (the shared data directory, e.g.
    /// ../shared/data), with the paper's energy preset.
    #[arg(long)]
    pub data: Option<PathBuf>,
}

/// The paper's line: "selected 8 cells; 55,309.8 J of 66,500 J, 83.2%".
fn paper_line(m: &gleaner_wire::MissionDoc) -> String {
    format!(
        "selected {} cells; {} J of {} J, {:.1}%",
        m.stops.len(),
        thousands(m.energy.total_j),
        thousands(m.energy.budget_j),
        100.0 * m.energy.utilisation
    )
}

/// 55309.8 -> "55,309.8".
fn thousands(x: f64) -> String {
    let s = format!("{x:.1}");
    let (int, frac) = s.split_once('.').unwrap_or((&s, "0"));
    let (sign, digits) = int.strip_prefix('-').map_or(("", int), |d| ("-", d));
    let mut out = String::new();
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    format!("{sign}{out}.{frac}")
}

/// Runs the demo (`gleaner_campaign::demo`), writes its missions' files; returns its report.
pub fn run(args: &DemoArgs) -> Result<String> {
    let mut out = String::new();
    let d = gleaner_campaign::demo::demo(
        &DemoRequest {
            dir: args.dir.clone(),
            gleaner_method: matches!(args.method, crate::MethodArg::Gleaner),
            seed: args.seed,
            sensors: args.sensors,
            days: args.days,
            data: args.data.clone(),
        },
        clock_now(),
        &Terminal::default(),
    )?;
    let project_line = format!(
        "project {}: {} sensors in {} cells of {} m",
        d.init.settings.project.name,
        d.init.sensors,
        d.init.n_cells,
        d.init.settings.field.cell_size_m
    );
    match &d.farm {
        DemoFarm::Synthetic {
            dir,
            readings,
            events,
        } => {
            writeln!(
                out,
                "1. synthetic farm (seed {}): {} sensors, {} days, {readings} readings, {events} ground-truth events -> {}",
                args.seed,
                args.sensors,
                args.days,
                dir.display()
            )?;
            writeln!(
                out,
                "2. {project_line}; the sensors log {} readings, none collected yet",
                d.truth_readings
            )?;
        }
        DemoFarm::Caf { files } => {
            writeln!(
                out,
                "1. CAF network (doi:10.15482/USDA.ADC/1349683): {files} daily files, {} readings",
                d.truth_readings
            )?;
            let preset = &d.init.settings.energy.preset;
            writeln!(out, "2. {project_line}, energy preset {preset}")?;
        }
    }
    let doc = gleaner_wire::convert::exploration(&d.exploration);
    writeln!(
        out,
        "3. exploration at {}: {} cells in {} sorties (lower bound {}), {:.1} kJ in all",
        doc.planned_at,
        doc.cells,
        doc.sorties.len(),
        doc.lower_bound_sorties,
        doc.total_energy_j / 1000.0
    )?;
    let missions_dir = args.dir.join("missions");
    for s in &d.sorties {
        let files = export::write_files(&s.export, &missions_dir.join(s.id.to_string()))?;
        writeln!(
            out,
            "   sortie #{}: {}; brought back {} readings from {} sensors ({} files)",
            s.id,
            paper_line(&gleaner_wire::convert::stored_mission(&s.export.mission)),
            s.record.readings_inserted,
            s.record.sensors_collected,
            files.files.len()
        )?;
    }
    let map = export::write_exploration_map(&d.project, &missions_dir)?;
    writeln!(out, "   overview map: {}", map.join(", "))?;
    writeln!(
        out,
        "4. {MISSIONS} adaptive missions, one a day, each planned from what was collected, flown in simulation and recorded:"
    )?;
    for (k, (planned, m)) in d.missions.iter().enumerate() {
        let doc = gleaner_wire::convert::planned_mission(planned);
        let files = export::write_files(&m.export, &missions_dir.join(m.id.to_string()))?;
        writeln!(
            out,
            "   mission #{} at {}: {}; total S = {:.3} (paper's greedy {:.3}); brought back {} readings; files in {}",
            m.id,
            doc.planned_at,
            paper_line(&doc),
            doc.total_score,
            doc.greedy_baseline.as_ref().map_or(0.0, |g| g.total_score),
            m.record.readings_inserted,
            files
                .files
                .first()
                .and_then(|f| f.parent())
                .map_or(String::new(), |p| p.display().to_string())
        )?;
        if k == 0 {
            writeln!(out, "{}", indent(&plan::table(&doc)))?;
        }
    }
    // The first mission's cells after their collection: fresh again.
    if let Some((k, after, m)) = &d.rescored
        && let Some(before) = d.missions[*k].0.scoring.as_ref()
    {
        let before = gleaner_wire::convert::scoring(before);
        let after = gleaner_wire::convert::scoring(after);
        writeln!(
            out,
            "5. mission #{}'s cells, scored before it and after the campaign (F resets when collected):",
            m.id
        )?;
        for stop in m.mission.stops.iter().take(5) {
            let label = stop.cell.to_string();
            let b = before.cells.iter().find(|c| c.cell == label);
            let a = after.cells.iter().find(|c| c.cell == label);
            if let (Some(b), Some(a)) = (b, a) {
                writeln!(
                    out,
                    "   {label:<10} F {:.3} -> {:.3}   U {:.3} -> {:.3}   S {:.3} -> {:.3}",
                    b.f, a.f, b.u, a.u, b.s, a.s
                )?;
            }
        }
    }
    Ok(out)
}

fn indent(s: &str) -> String {
    s.lines()
        .map(|l| format!("     {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}
