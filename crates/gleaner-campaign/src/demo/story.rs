//! The demo told as text: the farm, the project, the exploration and its sorties, the
//! adaptive missions (the first with its table) and the first mission's cells rescored.
//! Energies J (kJ where said), times RFC 3339 (UTC).

use std::fmt::Write as _;

use gleaner_wire::{convert, text};

use super::{Demo, DemoFarm, DemoRequest, MISSIONS};

/// The demo's report, a numbered step per line (and the first adaptive mission's table).
pub fn story(d: &Demo, r: &DemoRequest) -> String {
    let mut out = String::new();
    let _ = farm_lines(&mut out, d, r);
    let _ = flight_lines(&mut out, d);
    let _ = rescored_lines(&mut out, d);
    out
}

/// Steps 1 and 2: the farm and the project.
fn farm_lines(out: &mut String, d: &Demo, r: &DemoRequest) -> std::fmt::Result {
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
                r.seed,
                r.sensors,
                r.days,
                dir.display()
            )?;
            writeln!(
                out,
                "2. {project_line}; the sensors log {} readings, none collected yet",
                d.truth_readings
            )
        }
        DemoFarm::Caf { files } => {
            writeln!(
                out,
                "1. CAF network (doi:10.15482/USDA.ADC/1349683): {files} daily files, {} readings",
                d.truth_readings
            )?;
            let preset = &d.init.settings.energy.preset;
            writeln!(out, "2. {project_line}, energy preset {preset}")
        }
    }
}

/// Steps 3 and 4: the exploration with its sorties, then the adaptive missions.
fn flight_lines(out: &mut String, d: &Demo) -> std::fmt::Result {
    let doc = convert::exploration(&d.exploration);
    writeln!(
        out,
        "3. exploration at {}: {} cells in {} sorties (lower bound {}), {:.1} kJ in all",
        doc.planned_at,
        doc.cells,
        doc.sorties.len(),
        doc.lower_bound_sorties,
        doc.total_energy_j / 1000.0
    )?;
    for s in &d.sorties {
        writeln!(
            out,
            "   sortie #{}: {}; brought back {} readings from {} sensors ({} files)",
            s.id,
            text::paper_line(&convert::stored_mission(&s.export.mission)),
            s.record.readings_inserted,
            s.record.sensors_collected,
            s.files.len()
        )?;
    }
    let names: Vec<String> = d.overview.iter().map(|f| f.display().to_string()).collect();
    writeln!(out, "   overview map: {}", names.join(", "))?;
    writeln!(
        out,
        "4. {MISSIONS} adaptive missions, one a day, each planned from what was collected, flown in simulation and recorded:"
    )?;
    for (k, (planned, m)) in d.missions.iter().enumerate() {
        let doc = convert::planned_mission(planned);
        writeln!(
            out,
            "   mission #{} at {}: {}; total S = {:.3} (paper's greedy {:.3}); brought back {} readings; files in {}",
            m.id,
            doc.planned_at,
            text::paper_line(&doc),
            doc.total_score,
            doc.greedy_baseline.as_ref().map_or(0.0, |g| g.total_score),
            m.record.readings_inserted,
            m.files
                .first()
                .and_then(|f| f.parent())
                .map_or(String::new(), |p| p.display().to_string())
        )?;
        if k == 0 {
            writeln!(out, "{}", indent(&text::mission_table(&doc)))?;
        }
    }
    Ok(())
}

/// Step 5: the first mission's cells, scored before it and after the campaign.
fn rescored_lines(out: &mut String, d: &Demo) -> std::fmt::Result {
    let Some((k, after, m)) = &d.rescored else {
        return Ok(());
    };
    let Some(before) = d.missions[*k].0.scoring.as_ref() else {
        return Ok(());
    };
    let before = convert::scoring(before);
    let after = convert::scoring(after);
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
    Ok(())
}

/// `s` with every line indented by five spaces.
fn indent(s: &str) -> String {
    s.lines()
        .map(|l| format!("     {l}"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::indent;

    #[test]
    fn every_line_is_indented() {
        assert_eq!(indent("a\nb"), "     a\n     b");
        assert_eq!(indent(""), "");
    }
}
