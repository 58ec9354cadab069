//! Target (issue 20): with 20 no-fly polygons on CAF, planning within 2x of the time without.
//!
//! Two CAF projects (42 stations, `CAF_sensor_locations.csv` in UTM 11N, found through
//! `GLEANER_DATA_DIR`, default `../shared/data`), one without zones and one with a geofence
//! (the cells' box grown by 60 m) and 20 seeded no-fly polygons (seed 20, 8-25 m from their
//! centre, none within 60 m of the base, `gleaner_app::airspace::seeded_no_fly_geojson`),
//! planned by the `plan` use case as `gleaner plan --dry-run` does: given per-cell scores
//! (1 to 5), the default planner capped at 2,000 iterations (seed 1), the paper's greedy
//! baseline, the energy re-check — and with zones reading and projecting the zone files,
//! buffering them, the visibility graph and the all-pairs shortest paths.
//!
//! ```sh
//! GLEANER_DATA_DIR=../shared/data cargo bench -p gleaner-benches --bench zones
//! ```

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_app::{self as app, AnyStore, PlanRequest, Project};
use gleaner_field::LocalPoint;

fn data() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

/// The CAF project in `dir`, with the seeded zones when `zones`.
fn caf(dir: &std::path::Path, zones: bool) -> Project<AnyStore> {
    let sensors = data().join("caf/sensors/CAF_sensor_locations.csv");
    let init = |no_fly: Option<PathBuf>, geofence: Option<PathBuf>| {
        app::init(&app::InitRequest {
            dir: dir.join("caf"),
            sensors: sensors.clone(),
            utm_zone: Some("11N".into()),
            force: true,
            no_fly,
            geofence,
            ..Default::default()
        })
        .expect("init CAF")
        .0
    };
    let p = init(None, None);
    if !zones {
        return p;
    }
    let (_, field) = p.field().expect("field");
    let centres: Vec<LocalPoint> = field.cells().iter().map(|c| c.centre).collect();
    let no_fly = dir.join("no_fly.geojson");
    std::fs::write(
        &no_fly,
        app::airspace::seeded_no_fly_geojson(
            field.frame(),
            20,
            20,
            &centres,
            LocalPoint::new(0.0, 0.0),
        ),
    )
    .expect("write zones");
    let (mut lo, mut hi) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for c in &centres {
        lo = (lo.0.min(c.e), lo.1.min(c.n));
        hi = (hi.0.max(c.e), hi.1.max(c.n));
    }
    let fence =
        gleaner_app::airspace::rectangle(lo.0 - 60.0, lo.1 - 60.0, hi.0 + 60.0, hi.1 + 60.0);
    let geofence = dir.join("fence.geojson");
    std::fs::write(
        &geofence,
        app::airspace::polygons_geojson(field.frame(), &[fence]),
    )
    .expect("write fence");
    drop(p);
    init(Some(no_fly), Some(geofence))
}

fn request(cells: usize) -> PlanRequest {
    PlanRequest {
        at: Some(1_393_632_000),
        cell_scores: Some((0..cells).map(|k| 1.0 + (k % 5) as f64).collect()),
        seed: Some(1),
        max_iterations: Some(2_000),
        time_limit_s: Some(600.0),
        dry_run: true,
        ..Default::default()
    }
}

fn plan(c: &mut Criterion) {
    let mut group = c.benchmark_group("plan_caf");
    group.sample_size(10);
    for (name, zones) in [("no_zones", false), ("20_no_fly_zones", true)] {
        let tmp = tempfile::tempdir().expect("temp dir");
        let mut p = caf(tmp.path(), zones);
        let cells = p.field().expect("field").1.cells().len();
        let req = request(cells);
        let first = app::plan(&mut p, &req, 0).expect("plan");
        let turns: usize = first.via.iter().map(Vec::len).sum();
        eprintln!(
            "{name}: {} stops, {turns} turn points, {} unreachable cells, {:.1} J",
            first.mission.stops.len(),
            first.unreachable.len(),
            first.mission.energy.total_j
        );
        group.bench_function(name, |b| {
            b.iter(|| app::plan(&mut p, &req, 0).expect("plan"));
        });
    }
    group.finish();
}

criterion_group!(benches, plan);
criterion_main!(benches);
