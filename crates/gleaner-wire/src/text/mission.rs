//! Missions as text: a mission's table with its energy breakdown and wind, a day's sorties,
//! a continuation re-planned in the air, an exploration. Energies J, distances m, times s,
//! speeds m/s, positions WGS84 `[lon, lat]` degrees.

use crate::MissionDoc;
use crate::docs::ExplorationDoc;

/// Several sorties of one mission day: each sortie's table, then one line per sortie (id,
/// cells, S, energy in J) and the totals.
pub fn sorties_table(docs: &[MissionDoc]) -> String {
    let mut out = String::new();
    for (k, m) in docs.iter().enumerate() {
        out.push_str(&format!("== sortie {} of {}\n", k + 1, docs.len()));
        out.push_str(&mission_table(m));
        out.push('\n');
    }
    out.push_str(&format!("{} sorties:\n", docs.len()));
    for (k, m) in docs.iter().enumerate() {
        let cells: Vec<&str> = m.stops.iter().map(|s| s.cell.as_str()).collect();
        out.push_str(&format!(
            "  sortie {}{}: {} cells, S = {:.3}, {:.1} J of {:.1} J: {}\n",
            k + 1,
            m.mission_id
                .map_or(String::new(), |id| format!(" (mission #{id})")),
            m.stops.len(),
            m.total_score,
            m.energy.total_j,
            m.energy.budget_j,
            cells.join(" ")
        ));
    }
    out.push_str(&format!(
        "total: {} cells, S = {:.3}, {:.1} J",
        docs.iter().map(|m| m.stops.len()).sum::<usize>(),
        docs.iter().map(|m| m.total_score).sum::<f64>(),
        docs.iter().map(|m| m.energy.total_j).sum::<f64>()
    ));
    out
}

/// A mission summary (docs/method.md §6) as a readable table.
pub fn mission_table(m: &MissionDoc) -> String {
    let mut out = format!(
        "mission{} ({}) planned for {} with the {} planner: {}, total S = {:.3}\n",
        m.mission_id.map_or(String::new(), |id| format!(" #{id}")),
        m.status,
        m.planned_at,
        m.planner,
        match m.candidates {
            Some(c) => format!("{} of {c} candidate cells", m.stops.len()),
            // A stored mission does not keep how many cells it was chosen from.
            None => format!("{} cells", m.stops.len()),
        },
        m.total_score
    );
    out.push_str(&format!(
        "{:>3} {:<10} {:>7} {:>6} {:>6} {:>7} {:>6} {:>8} {:>9} {:>7} {:>9} {:>7}\n",
        "#", "cell", "S", "F", "R", "A", "U", "leg_m", "leg_J", "hover_s", "hover_J", "comm_J"
    ));
    for s in &m.stops {
        let t: [String; 4] = match s.terms {
            Some(t) => t.map(|x| format!("{x:.3}")),
            None => std::array::from_fn(|_| "-".to_string()),
        };
        out.push_str(&format!(
            "{:>3} {:<10} {:>7.3} {:>6} {:>6} {:>7} {:>6} {:>8.1} {:>9.1} {:>7.2} {:>9.1} {:>7.1}\n",
            s.order, s.cell, s.s, t[0], t[1], t[2], t[3], s.leg_distance_m, s.leg_energy_j, s.hover_s, s.hover_j, s.comm_j
        ));
    }
    let e = &m.energy;
    out.push_str(&format!(
        "return leg {:.1} m\n{}\n",
        m.return_distance_m,
        energy_line(m)
    ));
    out.push_str(&format!(
        "flight: {:.0} m, {:.0} s at {:.2} m/s, {:.2} m above the base",
        e.distance_m, e.flight_time_s, m.profile.cruise_speed_mps, m.profile.altitude_m
    ));
    if let Some(g) = &m.greedy_baseline {
        out.push_str(&format!(
            "; paper's greedy on the same cells: {} cells, total S = {:.3}, {:.1} J",
            g.cells, g.total_score, g.energy_j
        ));
    }
    out.push_str(&format!(
        "\nweights alpha,beta,gamma,delta = {:?}; anomaly {}\n",
        m.weights, m.anomaly_form
    ));
    let turns: usize =
        m.stops.iter().map(|s| s.via_lon_lat.len()).sum::<usize>() + m.return_via_lon_lat.len();
    if turns > 0 {
        let legs = m.stops.iter().filter(|s| !s.via_lon_lat.is_empty()).count()
            + usize::from(!m.return_via_lon_lat.is_empty());
        out.push_str(&format!(
            "around the no-fly zones: {legs} legs with {turns} turn points (in the files as \
             waypoints without a hold, at the same altitude and speed)\n"
        ));
    }
    out.push_str(&unreachable_lines(&m.unreachable));
    if let Some(w) = &m.wind {
        out.push_str(&wind_lines(w));
    }
    out
}

/// The wind a plan was made for, each leg's components when it is not still air, and the
/// strongest wind the route stands (from the forecast's direction).
pub fn wind_lines(w: &crate::WindDoc) -> String {
    let dir = format!("{:.0}°", w.from_deg);
    let mut out = if w.forecast_mps > 0.0 {
        format!(
            "wind: forecast {:.1} m/s from {dir} + {:.1} m/s margin: legs priced at {:.1} m/s from {dir} (airspeed holding each track at the planned ground speed)
",
            w.forecast_mps, w.margin_mps, w.planned_mps
        )
    } else {
        format!(
            "wind: planned in still air (no forecast: --wind SPEED@FROM or [flight] wind_mps); direction {dir} from [flight] wind_from_deg
"
        )
    };
    if w.planned_mps > 0.0 {
        out.push_str(&format!(
            "{:>3} {:>8} {:>9} {:>9} {:>9} {:>8} {:>9}
",
            "leg", "leg_m", "head_mps", "tail_mps", "cross_mps", "air_mps", "leg_J"
        ));
        let n = w.legs.len();
        for (k, l) in w.legs.iter().enumerate() {
            let name = if k + 1 == n {
                "ret".to_string()
            } else {
                (k + 1).to_string()
            };
            out.push_str(&format!(
                "{:>3} {:>8.1} {:>9.2} {:>9.2} {:>9.2} {:>8.2} {:>9.1}
",
                name,
                l.distance_m,
                l.headwind_mps,
                l.tailwind_mps,
                l.crosswind_mps,
                l.airspeed_mps,
                l.energy_j
            ));
        }
    }
    match (w.strongest_feasible_mps, w.strongest_capped) {
        (Some(v), false) => out.push_str(&format!(
            "strongest wind it stays within the battery in: {v:.1} m/s from {dir} (the forecast's direction)
"
        )),
        (Some(v), true) => out.push_str(&format!(
            "strongest wind it stays within the battery in: at least {v:.0} m/s from {dir} (the forecast's direction; the search stops there)
"
        )),
        (None, _) => {}
    }
    if w.over_budget_in_still_air {
        out.push_str(
            "over the battery in still air: hovering costs more without wind than in the planned wind\n",
        );
    }
    out
}

/// One line per unreachable cell (empty when none).
pub fn unreachable_lines(u: &[crate::UnreachableDoc]) -> String {
    let mut out = String::new();
    if !u.is_empty() {
        out.push_str(&format!(
            "unreachable cells ({}), never planned:\n",
            u.len()
        ));
        for c in u {
            out.push_str(&format!("  {}: {}\n", c.cell, c.reason));
        }
    }
    out
}

/// A continuation re-planned in the air: where it starts, the energy left and the reserve,
/// the stops kept (the mission table) and those dropped.
pub fn replan_table(m: &MissionDoc, dropped: &[gleaner_field::CellIndex]) -> String {
    let mut out = String::new();
    if let Some(c) = &m.continuation {
        out.push_str(&format!(
            "continuation of mission #{} after stop {} from [lon, lat] [{:.7}, {:.7}]: {:.1} J \
             left, {:.1} J reserve kept\n",
            c.parent_mission_id,
            c.after_stop,
            c.start_lon_lat[0],
            c.start_lon_lat[1],
            c.energy_left_j,
            c.reserve_j
        ));
    }
    out.push_str(&mission_table(m));
    let names: Vec<String> = dropped.iter().map(|c| c.to_string()).collect();
    out.push_str(&format!(
        "dropped: {}\n",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(" ")
        }
    ));
    out
}

/// The paper's line: "selected 8 cells; 55,309.8 J of 66,500 J, 83.2%" with the breakdown.
pub fn energy_line(m: &MissionDoc) -> String {
    let e = &m.energy;
    format!(
        "energy: E_t {:.1} J + E_h {:.1} J + E_c {:.1} J + E_r {:.1} J = {:.1} J of {:.1} J usable ({:.1}%)",
        e.travel_j,
        e.hover_j,
        e.comm_j,
        e.return_j,
        e.total_j,
        e.budget_j,
        100.0 * e.utilisation
    )
}

/// The exploration plan as text.
pub fn exploration_table(e: &ExplorationDoc) -> String {
    let mut out = format!(
        "exploration of {} cells: {} sorties (lower bound {}), {:.1} J in all, {:.1} J usable per sortie\n",
        e.cells,
        e.sorties.len(),
        e.lower_bound_sorties,
        e.total_energy_j,
        e.budget_j
    );
    for (n, s) in e.sorties.iter().enumerate() {
        let cells: Vec<&str> = s.stops.iter().map(|s| s.cell.as_str()).collect();
        out.push_str(&format!(
            "{:>3}{} {:>3} cells {:>8.0} m {:>9.1} J ({:>5.1}%): {}\n",
            n + 1,
            s.mission_id
                .map_or(String::new(), |id| format!(" (mission #{id})")),
            s.stops.len(),
            s.energy.distance_m,
            s.energy.total_j,
            100.0 * s.energy.utilisation,
            cells.join(" ")
        ));
    }
    out.push_str(&unreachable_lines(&e.unreachable));
    out
}

/// The paper's line: "selected 8 cells; 55,309.8 J of 66,500.0 J, 83.2%".
pub fn paper_line(m: &MissionDoc) -> String {
    format!(
        "selected {} cells; {} J of {} J, {:.1}%",
        m.stops.len(),
        thousands(m.energy.total_j),
        thousands(m.energy.budget_j),
        100.0 * m.energy.utilisation
    )
}

/// `x` to one decimal with thousands separators: 55309.8 -> "55,309.8".
pub fn thousands(x: f64) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;

    #[test]
    fn thousands_groups_the_integer_part() {
        assert_eq!(thousands(55_309.84), "55,309.8");
        assert_eq!(thousands(-1_234_567.0), "-1,234,567.0");
        assert_eq!(thousands(12.0), "12.0");
    }

    #[test]
    fn a_mission_table_has_a_row_per_stop_and_the_energy_line() {
        let m = samples::adaptive_mission();
        let t = mission_table(&m);
        assert!(t.starts_with("mission"), "{t}");
        assert!(t.contains(&energy_line(&m)), "{t}");
        for s in &m.stops {
            assert!(t.contains(&s.cell), "{t}");
        }
        let day = sorties_table(&[m.clone(), m.clone()]);
        assert!(
            day.contains("== sortie 2 of 2") && day.contains("2 sorties:"),
            "{day}"
        );
    }

    #[test]
    fn a_continuation_names_where_it_starts_and_what_it_dropped() {
        let m = samples::continuation();
        let t = replan_table(&m, &[]);
        assert!(t.starts_with("continuation of mission #"), "{t}");
        assert!(t.ends_with("dropped: none\n"), "{t}");
    }

    #[test]
    fn no_unreachable_cells_no_lines() {
        assert_eq!(unreachable_lines(&[]), "");
    }
}
