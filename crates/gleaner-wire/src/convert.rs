//! Explicit conversions from the application layer's data to the documents.

use gleaner_app::{
    CellView, Exploration, ExtraSortie, FieldView, MissionExport, MissionId, MissionKind,
    MissionRecord, NewMission, PlannedMission, Reconstruction, ReconstructionMap,
    ReconstructionSeries, Scoring, driver,
};
use gleaner_ingest::time::format_rfc3339;

use crate::docs::{
    CellRowDoc, CellScoresDoc, ConditionDoc, CorrelationDoc, ExplorationDoc, ReconstructionDoc,
    ReconstructionModelDoc, ScoreRowDoc, ScoringDoc, SensorEstimateDoc, SummaryDoc, VariogramDoc,
};
use crate::{
    BaselineDoc, CellDoc, EnergyDoc, FIELD_FORMAT, FieldDoc, MISSION_FORMAT, MissionDoc,
    ProfileDoc, RECONSTRUCTION_FORMAT, ScoresDoc, SensorDoc, StopDoc, UnreachableDoc, VERSION,
    ZoneDoc,
};

fn lon_lat(p: gleaner_field::LatLon) -> [f64; 2] {
    [p.lon(), p.lat()]
}

/// The zones of the project's settings, with the buffer the planner kept (m).
pub fn zones(zones: &[gleaner_app::airspace::ZoneView], buffer_m: f64) -> Vec<ZoneDoc> {
    zones
        .iter()
        .map(|z| ZoneDoc {
            kind: z.kind.name().into(),
            name: z.name.clone(),
            feature: z.feature,
            polygons_lon_lat: z.polygons.clone(),
            lines_lon_lat: z.lines.clone(),
            buffer_m,
        })
        .collect()
}

/// Cells the flight cannot reach.
pub fn unreachable(u: &[gleaner_app::airspace::Unreachable]) -> Vec<UnreachableDoc> {
    u.iter()
        .map(|u| UnreachableDoc {
            cell: u.cell.clone(),
            reason: u.reason.clone(),
        })
        .collect()
}

/// Sets the turn points of `doc`'s legs (one list per stop, then the return leg's; WGS84).
pub fn set_via(doc: &mut MissionDoc, via: &[Vec<gleaner_field::LatLon>]) {
    for (k, leg) in via.iter().enumerate() {
        let points: Vec<[f64; 2]> = leg.iter().map(|&p| lon_lat(p)).collect();
        match doc.stops.get_mut(k) {
            Some(s) => s.via_lon_lat = points,
            None => doc.return_via_lon_lat = points,
        }
    }
}

/// A mission document from a mission's fields.
pub fn mission_doc(
    id: Option<MissionId>,
    m: &NewMission,
    status: &str,
    flown_at: Option<i64>,
) -> MissionDoc {
    let e = &m.energy;
    MissionDoc {
        format: MISSION_FORMAT.into(),
        version: VERSION,
        mission_id: id.map(|i| i.0),
        kind: m.kind.as_str().into(),
        status: status.into(),
        planned_at: format_rfc3339(m.planned_at),
        planned_at_s: m.planned_at,
        flown_at: flown_at.map(format_rfc3339),
        planner: m.solver.clone(),
        seed: m.seed,
        weights: m.weights,
        anomaly_form: m.anomaly_form.clone(),
        profile: ProfileDoc {
            base_lon_lat: lon_lat(m.profile.base),
            base_alt_m: m.profile.base_alt_m,
            altitude_m: m.profile.altitude_m,
            cruise_speed_mps: m.profile.cruise_speed_mps,
            wind_mps: m.profile.wind_mps,
            wind_from_deg: m.profile.wind_from_deg,
        },
        stops: m
            .stops
            .iter()
            .map(|s| StopDoc {
                order: s.order + 1,
                cell: s.cell.to_string(),
                centre_lon_lat: lon_lat(s.centre),
                s: s.score,
                terms: s.terms,
                leg_distance_m: s.leg_distance_m,
                leg_energy_j: s.leg_energy_j,
                collection_s: s.collection_s,
                hover_s: s.hover_s,
                hover_j: s.hover_j,
                comm_j: s.comm_j,
                via_lon_lat: Vec::new(),
            })
            .collect(),
        return_distance_m: m.return_distance_m,
        return_via_lon_lat: Vec::new(),
        zones: Vec::new(),
        unreachable: Vec::new(),
        energy: EnergyDoc {
            travel_j: e.travel_j,
            hover_j: e.hover_j,
            comm_j: e.comm_j,
            return_j: e.return_j,
            total_j: e.total_j,
            budget_j: e.budget_j,
            utilisation: if e.budget_j > 0.0 {
                e.total_j / e.budget_j
            } else {
                0.0
            },
            distance_m: e.distance_m,
            flight_time_s: e.flight_time_s,
        },
        total_score: m.total_score,
        candidates: None,
        greedy_baseline: None,
        energy_model: None,
        continuation: None,
        wind: None,
    }
}

/// A stored mission.
pub fn stored_mission(m: &MissionRecord) -> MissionDoc {
    let status = m.status.as_str();
    mission_doc(Some(m.id), &m.mission, status, m.flown_at)
}

/// The documents of missions with their turn points ([`routed_mission`] each), e.g. the
/// app's `exploration_sorties` for the exploration map.
pub fn routed_missions(
    missions: &[(MissionRecord, Vec<Vec<gleaner_field::LatLon>>)],
) -> Vec<MissionDoc> {
    missions
        .iter()
        .map(|(m, via)| routed_mission(m, via))
        .collect()
}

/// A stored mission's document flying through `via`, the turn points of its legs around the
/// no-fly zones (WGS84; see [`set_via`]): the route as flown, for maps.
pub fn routed_mission(m: &MissionRecord, via: &[Vec<gleaner_field::LatLon>]) -> MissionDoc {
    let mut doc = stored_mission(m);
    set_via(&mut doc, via);
    doc
}

/// A stored mission ready for the flight-file writers: [`stored_mission`] with the energy
/// model the writers price what they write with.
pub fn export_mission(e: &MissionExport) -> MissionDoc {
    let mut doc = stored_mission(&e.mission);
    doc.energy_model = Some(e.energy.into());
    set_via(&mut doc, &e.via);
    doc.zones = zones(&e.field.zones, e.field.zone_buffer_m);
    doc
}

/// A continuation re-planned in the air, ready for the flight-file writers (status
/// `continuation`, the parent's id as `mission_id`).
pub fn replanned_mission(r: &gleaner_app::Replan) -> MissionDoc {
    let mut doc = mission_doc(Some(r.parent), &r.mission, "continuation", None);
    doc.energy_model = Some(r.energy.into());
    doc.continuation = Some(crate::ContinuationDoc {
        parent_mission_id: r.parent.0,
        after_stop: r.after_stop,
        start_lon_lat: lon_lat(r.start),
        energy_left_j: r.energy_left_j,
        reserve_j: r.reserve_j,
    });
    doc.wind = Some(wind(&r.wind));
    doc
}

/// The wind of a planned route.
pub fn wind(w: &gleaner_app::wind::RouteWind) -> crate::WindDoc {
    crate::WindDoc {
        forecast_mps: w.wind.forecast.speed_mps,
        from_deg: w.wind.forecast.from_deg,
        margin_mps: w.wind.margin_mps,
        planned_mps: w.wind.planned.speed_mps,
        strongest_feasible_mps: w.strongest.map(|s| s.speed_mps),
        strongest_capped: w.strongest.is_some_and(|s| s.capped),
        over_budget_in_still_air: w.strongest.is_some_and(|s| !s.still_air),
        legs: w
            .legs
            .iter()
            .map(|l| crate::LegWindDoc {
                distance_m: l.distance_m,
                headwind_mps: l.headwind_mps.max(0.0),
                tailwind_mps: (-l.headwind_mps).max(0.0),
                crosswind_mps: l.crosswind_mps,
                airspeed_mps: l.airspeed_mps,
                energy_j: l.energy_j,
            })
            .collect(),
    }
}

/// A mission just planned, not flown: `planned` when it was stored under `id`, `dry-run`
/// when it was not.
fn just_planned(id: Option<MissionId>, m: &NewMission) -> MissionDoc {
    let status = if id.is_some() { "planned" } else { "dry-run" };
    mission_doc(id, m, status, None)
}

/// A sortie after the first of a day's plan, with its wind. The greedy baseline belongs to
/// the day's first sortie ([`planned_mission`]); `candidates` is left unset (the sorties share
/// the first's candidates: the CLI sets them to print each sortie's count, the API does not).
pub fn extra_sortie(e: &ExtraSortie) -> MissionDoc {
    let mut doc = just_planned(e.id, &e.mission);
    doc.wind = Some(wind(&e.wind));
    doc
}

/// A mission just planned (with the candidates and the greedy baseline).
pub fn planned_mission(p: &PlannedMission) -> MissionDoc {
    let mut doc = just_planned(p.id, &p.mission);
    doc.candidates = Some(p.candidates);
    set_via(&mut doc, &p.via);
    doc.unreachable = unreachable(&p.unreachable);
    doc.greedy_baseline = Some(BaselineDoc {
        planner: p.greedy.planner.name().into(),
        cells: p.greedy.cells,
        total_score: p.greedy.total_score,
        energy_j: p.greedy.energy_j,
    });
    doc.wind = Some(wind(&p.wind));
    doc
}

/// An exploration plan.
pub fn exploration(e: &Exploration) -> ExplorationDoc {
    ExplorationDoc {
        planned_at: format_rfc3339(e.planned_at),
        cells: e.cells,
        budget_j: e.budget_j,
        lower_bound_sorties: e.lower_bound_sorties,
        total_energy_j: e.total_energy_j,
        sorties: e
            .sorties
            .iter()
            .enumerate()
            .map(|(k, (id, m))| {
                let mut doc = just_planned(*id, m);
                if let Some(via) = e.via.get(k) {
                    set_via(&mut doc, via);
                }
                doc
            })
            .collect(),
        unreachable: unreachable(&e.unreachable),
    }
}

/// The field for maps.
pub fn field(f: &FieldView) -> FieldDoc {
    FieldDoc {
        format: FIELD_FORMAT.into(),
        version: VERSION,
        project: f.project.clone(),
        cell_size_m: f.cell_size_m,
        base_lon_lat: lon_lat(f.base),
        cells: f
            .cells
            .iter()
            .map(|c| {
                let mut ring: Vec<[f64; 2]> = c.corners.iter().map(|&p| lon_lat(p)).collect();
                ring.push(lon_lat(c.corners[0]));
                CellDoc {
                    cell: c.index.to_string(),
                    centre_lon_lat: lon_lat(c.centre),
                    ring_lon_lat: ring,
                    sensors: c.sensors.len(),
                    scores: c.metadata.scores.as_ref().map(|s| ScoresDoc {
                        f: s.freshness,
                        r: s.redundancy,
                        a: s.anomaly,
                        u: s.uncertainty,
                        s: s.score,
                        computed_at_s: s.computed_at,
                    }),
                }
            })
            .collect(),
        sensors: f
            .sensors
            .iter()
            .map(|(id, p)| SensorDoc {
                id: id.to_string(),
                lon_lat: lon_lat(*p),
            })
            .collect(),
        zones: zones(&f.zones, f.zone_buffer_m),
    }
}

/// One row of the cell table.
pub fn cell_row(c: &CellView, cell_size_m: f64) -> CellRowDoc {
    let m = &c.metadata;
    CellRowDoc {
        cell: c.index.to_string(),
        i: c.index.i,
        j: c.index.j,
        centre_lon_lat: lon_lat(c.centre),
        cell_size_m,
        sensors: c.sensors.iter().map(ToString::to_string).collect(),
        last_collected: m.last_collected.map(format_rfc3339),
        pending_bytes: m.pending_bytes,
        expected_energy_j: m.expected_energy_j,
        scores: m.scores.as_ref().map(|s| CellScoresDoc {
            freshness: s.freshness,
            redundancy: s.redundancy,
            anomaly: s.anomaly,
            uncertainty: s.uncertainty,
            score: s.score,
            computed_at: format_rfc3339(s.computed_at),
        }),
        summaries: m
            .summaries
            .iter()
            .map(|s| SummaryDoc {
                modality: s.modality.to_string(),
                count: s.stats.count,
                mean: s.stats.mean,
                std: s.stats.std,
                min: s.stats.min,
                max: s.stats.max,
                latest_value: s.stats.latest_value,
                latest_t: format_rfc3339(s.stats.latest_t),
            })
            .collect(),
        correlations: m
            .correlations
            .iter()
            .map(|c| CorrelationDoc {
                neighbour: c.neighbour.to_string(),
                modality: c.modality.to_string(),
                correlation: c.correlation,
                overlap: c.overlap,
            })
            .collect(),
        class_probabilities: m
            .class_probabilities
            .iter()
            .map(|p| (p.class.clone(), p.probability))
            .collect(),
    }
}

/// A scoring, cells by descending S (ties by cell id).
pub fn scoring(s: &Scoring) -> ScoringDoc {
    let k = &s.knowledge;
    let mut cells: Vec<ScoreRowDoc> = s
        .terms
        .iter()
        .enumerate()
        .map(|(c, t)| {
            let cell = &k.field.cells()[c];
            let centre = k.field.frame().inverse(cell.centre);
            ScoreRowDoc {
                cell: cell.index.to_string(),
                centre_lon_lat: lon_lat(centre),
                sensors: cell.sensors.len(),
                f: t.f,
                r: t.r,
                a: t.a,
                a_raw: t.a_raw,
                u: t.u,
                s: t.s,
                driver: driver(t, s.weights).into(),
                r_by_modality: k
                    .modalities
                    .iter()
                    .cloned()
                    .zip(t.r_by_modality.iter().copied())
                    .collect(),
                a_by_modality: k
                    .modalities
                    .iter()
                    .cloned()
                    .zip(t.a_by_modality.iter().copied())
                    .collect(),
                probabilities: t.probabilities.clone(),
            }
        })
        .collect();
    cells.sort_by(|a, b| b.s.total_cmp(&a.s).then(a.cell.cmp(&b.cell)));
    ScoringDoc {
        t: format_rfc3339(s.t),
        weights: s.weights,
        anomaly_form: s.anomaly_form.clone(),
        condition: s.condition.as_ref().map(|c| ConditionDoc {
            modality: c.modality.clone(),
            classes: c.classes.clone(),
            thresholds: c.thresholds.clone(),
        }),
        warnings: s.warnings.clone(),
        cells,
    }
}

/// A reconstruction over a range: every sensor's mean, sd and 90% interval at each time.
pub fn reconstruction_series(r: &ReconstructionSeries) -> crate::docs::ReconstructionSeriesDoc {
    let n = r.sensors.len();
    let grid = |f: &dyn Fn(usize, usize) -> f64| -> Vec<Vec<f64>> {
        (0..r.times.len())
            .map(|t| (0..n).map(|s| f(t, s)).collect())
            .collect()
    };
    crate::docs::ReconstructionSeriesDoc {
        format: crate::RECONSTRUCTION_SERIES_FORMAT.into(),
        version: VERSION,
        modality: r.modality.clone(),
        unit: r.unit.clone(),
        estimator: r.estimator.name().into(),
        model: r.model.as_ref().map(|m| crate::docs::DynamicModelDoc {
            phi: m.phi(),
            step_s: m.step_s(),
            shrinkage: m.shrinkage(),
            noise: m.noise(),
        }),
        times: r.times.iter().map(|&t| format_rfc3339(t)).collect(),
        sensors: r
            .sensors
            .iter()
            .map(|(id, p)| crate::docs::SeriesSensorDoc {
                sensor: id.as_str().to_string(),
                lon_lat: lon_lat(*p),
            })
            .collect(),
        mean: grid(&|t, s| r.mean[t * n + s]),
        sd: grid(&|t, s| r.variance[t * n + s].max(0.0).sqrt()),
        lo90: grid(&|t, s| r.interval90(t, s).0),
        hi90: grid(&|t, s| r.interval90(t, s).1),
    }
}

/// A reconstruction's map: cells with their mean and sd, sensors with their estimate and
/// whether they were read at the time, the outline.
pub fn reconstruction_map(m: &ReconstructionMap) -> crate::docs::ReconstructionMapDoc {
    let r = &m.reconstruction;
    crate::docs::ReconstructionMapDoc {
        format: crate::RECONSTRUCTION_MAP_FORMAT.into(),
        version: VERSION,
        project: m.project.clone(),
        at: format_rfc3339(r.at),
        modality: r.modality.clone(),
        unit: m.unit.clone(),
        estimator: r.estimator.name().into(),
        base_lon_lat: lon_lat(m.base),
        cell_size_m: m.cell_size_m,
        read_within_s: m.read_within_s,
        cells: m
            .cells
            .iter()
            .map(|c| {
                let mut ring: Vec<[f64; 2]> = c.corners.iter().map(|&p| lon_lat(p)).collect();
                ring.push(lon_lat(c.corners[0]));
                crate::docs::MapCellDoc {
                    cell: c.index.to_string(),
                    ring_lon_lat: ring,
                    sensors: c
                        .sensors
                        .iter()
                        .map(|&k| r.sensors[k].sensor.as_str().to_string())
                        .collect(),
                    mean: c.mean,
                    sd: c.sd,
                }
            })
            .collect(),
        sensors: r
            .sensors
            .iter()
            .zip(&m.read)
            .map(|(s, &read)| crate::docs::MapSensorDoc {
                sensor: s.sensor.as_str().to_string(),
                lon_lat: lon_lat(s.position),
                estimate: s.kriged,
                sd: s.variance.max(0.0).sqrt(),
                last_reading: s.last_time.map(format_rfc3339),
                read,
            })
            .collect(),
        outline_lon_lat: m
            .outline
            .iter()
            .map(|ring| ring.iter().map(|&p| lon_lat(p)).collect())
            .collect(),
    }
}

/// A reconstruction: every sensor's estimate (sd = √variance), sensors by id.
pub fn reconstruction(r: &Reconstruction) -> ReconstructionDoc {
    let variogram = |v: gleaner_kriging::Variogram| VariogramDoc {
        nugget: v.nugget,
        partial: v.partial,
        scale_s: v.scale_s,
    };
    let c = r.model.covariance;
    ReconstructionDoc {
        format: RECONSTRUCTION_FORMAT.into(),
        version: VERSION,
        at: format_rfc3339(r.at),
        modality: r.modality.clone(),
        estimator: r.estimator.name().into(),
        step_s: r.step_s,
        model: ReconstructionModelDoc {
            levels_sill: c.sill,
            levels_nugget: c.nugget,
            levels_range_m: c.range_m,
            levels_time_scale_s: c.time_scale_s,
            changes_shared: variogram(r.changes.shared),
            changes_range_m: r.changes.range_m,
            changes_own: variogram(r.changes.own),
        },
        sensors: r
            .sensors
            .iter()
            .map(|s| SensorEstimateDoc {
                sensor: s.sensor.as_str().to_string(),
                lon_lat: lon_lat(s.position),
                last_reading: s.last_time.map(format_rfc3339),
                carried: s.carried,
                estimate: s.kriged,
                sd: s.variance.max(0.0).sqrt(),
                lo90: Some(s.kriged - s.half90),
                hi90: Some(s.kriged + s.half90),
            })
            .collect(),
    }
}

/// Whether a mission is an exploration sortie.
pub fn is_exploration(m: &MissionRecord) -> bool {
    m.mission.kind == MissionKind::Exploration
}
