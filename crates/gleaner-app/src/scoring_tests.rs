//! Tests of the scoring crate's reconstructions (`gleaner-scoring`) on projects made by this
//! crate's `init` and `ingest` from a synthetic farm.

use gleaner_field::{CellIndex, Modality, UnixSeconds};
use gleaner_kriging::{DynamicModel, FieldModel, IncrementModel, Mean};
use gleaner_scoring::{
    AppError, EstimateReads, Estimator, Project, ReconstructMapRequest, ReconstructRequest,
    ReconstructSeriesRequest, Result, SensorEstimate, estimate_with, fit_models, reconstruct,
    reconstruct_map, reconstruct_series,
};
use gleaner_store::Store;

const DAY: i64 = 86_400;

/// `estimate_with` without kept reads: every read from the store.
fn estimate<S: Store>(
    project: &Project<S>,
    modality: &Modality,
    models: (&FieldModel, &IncrementModel, Option<&DynamicModel>),
    at: UnixSeconds,
    lookback_s: i64,
    options: (usize, Estimator),
) -> Result<Vec<SensorEstimate>> {
    estimate_with(
        project,
        modality,
        models,
        (at, lookback_s),
        options,
        (&mut EstimateReads::default(), false),
    )
}

/// Estimates reusing the previous estimate's reads (nothing stored after its time, at
/// later times with the same look-back) equal, to the bit, estimates reading the store;
/// some sensors stop reporting, so their latest readings leave the look-back on the way.
#[test]
fn estimates_from_kept_reads_are_the_store_estimates() {
    use gleaner_store::StoreRead;
    let crate::test_farm::SynthProject {
        tmp: _tmp,
        farm,
        mut project,
        readings,
        ..
    } = crate::test_farm::synth_project(&gleaner_synth::SynthConfig {
        seed: 5,
        sensor_count: 18,
        days: 60,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![30],
        ..gleaner_synth::SynthConfig::default()
    });
    let mut known = gleaner_ingest::Readings::default();
    for (_, _, r, _) in crate::ingest::parse_files(
        &crate::ingest::IngestRequest {
            files: vec![readings],
            ..Default::default()
        },
        crate::ingest::known_sensors(project.store()).unwrap(),
        &project.settings().ingest.value_limits(),
        &crate::Silent,
    )
    .unwrap()
    .files
    {
        known.append(r);
    }
    let cut = farm.times()[0] + 45 * DAY;
    // What a daily log holds by the cut: a reading stamped t is available from t + 1 day.
    known.rows.retain(|r| r.t + DAY <= cut);
    // Every third sensor stops 10 days before the cut.
    known
        .rows
        .retain(|r| r.sensor % 3 != 0 || r.t <= cut - 10 * DAY);
    let report = gleaner_ingest::IngestReport {
        rows_read: known.rows.len() as u64,
        readings: known.rows.len() as u64,
        ..Default::default()
    };
    crate::ingest::ingest_parsed(
        &mut project,
        crate::ingest::Parsed {
            files: vec![(
                "known".into(),
                crate::ingest::Format::Long,
                known,
                report.clone(),
            )],
            report,
        },
        &crate::ingest::IngestRequest::default(),
        0,
        &crate::Silent,
    )
    .unwrap();
    let modality = Modality::new("vw@30cm").unwrap();
    let last = project
        .store()
        .latest_readings(&modality, 0..=cut)
        .unwrap()
        .into_iter()
        .map(|r| r.1)
        .max()
        .unwrap();
    let models = fit_models(&project, &modality, last).unwrap();
    let (model, changes) = (&models.levels, &models.changes);
    let dynamic = models.dynamic.as_ref();
    assert!(dynamic.is_some(), "the dynamic model fits a synthetic farm");
    let mut reads = EstimateReads::default();
    for day in 0..12 {
        let at = last + day * DAY;
        let options = (8, Estimator::Changes);
        let fresh = estimate(
            &project,
            &modality,
            (model, changes, dynamic),
            at,
            14 * DAY,
            options,
        )
        .unwrap();
        let kept = estimate_with(
            &project,
            &modality,
            (model, changes, dynamic),
            (at, 14 * DAY),
            options,
            (&mut reads, true),
        )
        .unwrap();
        assert_eq!(format!("{fresh:?}"), format!("{kept:?}"), "day {day}");
        if day == 6 {
            assert!(fresh.iter().any(|e| e.last_time.is_none()), "stale sensors");
        }
    }
    assert_eq!(reads.reused(), 11);
    // The dynamic estimator: a sensor read at the estimation time is known to the
    // reading noise; one not read lately has a larger variance, within the prior.
    let dyn_est = estimate(
        &project,
        &modality,
        (model, changes, dynamic),
        last,
        UnixSeconds::MAX / 4,
        (8, Estimator::Dynamic),
    )
    .unwrap();
    let m = dynamic.unwrap();
    let n = m.len();
    for (k, e) in dyn_est.iter().enumerate() {
        let prior = m.covariance()[k * n + k];
        assert!(e.kriged.is_finite() && e.variance >= 0.0 && e.variance <= prior * (1.0 + 1e-9));
        if e.last_time == Some(last) {
            assert!((e.kriged - e.carried).abs() < 0.1 * prior.sqrt(), "{e:?}");
            assert!(e.variance < 0.01 * prior, "{e:?}");
        }
    }
    assert!(dyn_est.iter().enumerate().any(|(k, e)| {
        e.last_time.is_some_and(|t| t < last - 5 * DAY)
            && e.variance > 0.01 * m.covariance()[k * n + k]
    }));
}

/// A series over a range: one row per time, every sensor's mean close to its own
/// reading at a time it reported, variances within the prior; bad ranges refused.
#[test]
fn series_over_a_range() {
    use gleaner_store::StoreRead;
    let crate::test_farm::SynthProject {
        tmp: _tmp,
        farm,
        project,
        ..
    } = crate::test_farm::ingested_synth_project(&gleaner_synth::SynthConfig {
        seed: 7,
        sensor_count: 12,
        days: 50,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![],
        ..gleaner_synth::SynthConfig::default()
    });
    let t0 = farm.times()[0];
    let request = ReconstructSeriesRequest {
        from: t0 + 30 * DAY,
        to: t0 + 40 * DAY,
        every_s: DAY,
        modality: Some("vw@30cm".into()),
        estimator: Estimator::Dynamic,
        ..Default::default()
    };
    let series = reconstruct_series(&project, &request).unwrap();
    let n = series.sensors.len();
    assert_eq!(series.times.len(), 11);
    assert_eq!(series.mean.len(), 11 * n);
    assert_eq!(series.estimator, Estimator::Dynamic);
    assert_eq!(series.unit.as_deref(), Some("m3/m3"));
    let model = series.model.as_ref().unwrap();
    let batch = project
        .store()
        .readings_for(
            Some(&Modality::new("vw@30cm").unwrap()),
            request.from..=request.from,
        )
        .unwrap();
    assert!(!batch.rows.is_empty());
    for r in &batch.rows {
        let id = &batch.sensors[r.sensor as usize];
        let k = series.sensors.iter().position(|s| &s.0 == id).unwrap();
        let prior = model.covariance()[k * n + k];
        assert!((series.mean[k] - r.value).abs() < 0.2 * prior.sqrt());
        let (lo, hi) = series.interval90(0, k);
        assert!(lo <= r.value && r.value <= hi);
    }
    for (k, v) in series.variance.iter().enumerate() {
        let s = k % n;
        assert!(*v >= 0.0 && *v <= model.covariance()[s * n + s] * (1.0 + 1e-9));
    }
    for bad in [
        ReconstructSeriesRequest {
            to: request.from - 1,
            ..request.clone()
        },
        ReconstructSeriesRequest {
            every_s: 0,
            ..request.clone()
        },
        ReconstructSeriesRequest {
            every_s: 1,
            to: request.from + 10_000_000,
            ..request.clone()
        },
    ] {
        assert!(matches!(
            reconstruct_series(&project, &bad),
            Err(AppError::Invalid(_))
        ));
    }
    // The kriging estimators over a range: at each time what `reconstruct` gives then
    // with the models fitted up to the range's end; at the end exactly `reconstruct`.
    for estimator in [
        Estimator::Changes,
        Estimator::Levels(Mean::Unknown),
        Estimator::Levels(Mean::Known),
    ] {
        let request = ReconstructSeriesRequest {
            estimator,
            ..request.clone()
        };
        let series = reconstruct_series(&project, &request).unwrap();
        assert_eq!(series.estimator, estimator);
        assert!(series.model.is_none());
        let last = series.times.len() - 1;
        let at_end = reconstruct(
            &project,
            &ReconstructRequest {
                at: Some(request.to),
                modality: request.modality.clone(),
                neighbours: None,
                estimator,
            },
        )
        .unwrap();
        for (k, e) in at_end.sensors.iter().enumerate() {
            assert_eq!(series.mean[last * n + k], e.kriged, "{estimator:?} {k}");
            assert_eq!(series.variance[last * n + k], e.variance);
            let (lo, hi) = series.interval90(last, k);
            assert!((hi - lo - 2.0 * e.half90).abs() < 1e-12);
        }
        assert!(series.mean.iter().all(|m| m.is_finite()));
        assert!(series.variance.iter().all(|v| *v >= 0.0));
    }
    // One cell's sensors only: the same columns as in the whole field's series.
    let (_, field) = project.field().unwrap();
    let cell = &field.cells()[0];
    let one = reconstruct_series(
        &project,
        &ReconstructSeriesRequest {
            cell: Some(cell.index),
            ..request.clone()
        },
    )
    .unwrap();
    assert_eq!(one.sensors.len(), cell.sensors.len());
    for (j, &k) in cell.sensors.iter().enumerate() {
        assert_eq!(one.sensors[j], series.sensors[k]);
        for t in 0..series.times.len() {
            assert_eq!(one.mean[t * one.sensors.len() + j], series.mean[t * n + k]);
        }
    }
    assert!(matches!(
        reconstruct_series(
            &project,
            &ReconstructSeriesRequest {
                cell: Some(CellIndex { i: 9_999, j: 9_999 }),
                ..request.clone()
            }
        ),
        Err(AppError::NotFound { what: "cell", .. })
    ));
}

/// On a synthetic farm: one map cell per field cell holding its sensors, each cell's
/// mean and sd from its sensors' estimates, "read" exactly for the sensors read within
/// the tolerance, an outline that closes.
#[test]
fn a_map_lays_the_estimates_on_the_cells() {
    let crate::test_farm::SynthProject {
        tmp: _tmp,
        farm,
        project,
        ..
    } = crate::test_farm::ingested_synth_project(&gleaner_synth::SynthConfig {
        seed: 3,
        sensor_count: 14,
        days: 40,
        vw_depths_cm: vec![30],
        t_depths_cm: vec![],
        ..gleaner_synth::SynthConfig::default()
    });
    let at = farm.times()[0] + 30 * 86_400;
    let request = ReconstructMapRequest {
        reconstruct: ReconstructRequest {
            at: Some(at),
            modality: Some("vw@30cm".into()),
            ..Default::default()
        },
        read_within_s: None,
    };
    let map = reconstruct_map(&project, &request).unwrap();
    let (_, field) = project.field().unwrap();
    assert_eq!(map.cells.len(), field.cells().len());
    assert_eq!(map.unit.as_deref(), Some("m3/m3"));
    assert_eq!(map.read_within_s, map.reconstruction.step_s);
    let r = &map.reconstruction;
    let mut seen = vec![0; r.sensors.len()];
    for c in &map.cells {
        assert!(!c.sensors.is_empty());
        let n = c.sensors.len() as f64;
        let mean: f64 = c.sensors.iter().map(|&k| r.sensors[k].kriged).sum::<f64>() / n;
        assert!((c.mean - mean).abs() < 1e-12);
        assert!(c.sd.is_finite() && c.sd >= 0.0);
        for &k in &c.sensors {
            seen[k] += 1;
        }
    }
    assert!(seen.iter().all(|&n| n == 1), "every sensor in one cell");
    for (s, &read) in r.sensors.iter().zip(&map.read) {
        assert_eq!(
            read,
            s.last_time.is_some_and(|t| at - t <= map.read_within_s),
            "{s:?}"
        );
    }
    assert!(
        map.read.iter().any(|&r| r),
        "a synthetic farm reports daily"
    );
    assert!(!map.outline.is_empty());
    assert!(map.outline.iter().all(|r| r.first() == r.last()));
    // A tolerance of 0 with a time between readings: nothing is read then.
    let between = reconstruct_map(
        &project,
        &ReconstructMapRequest {
            reconstruct: ReconstructRequest {
                at: Some(at + 3_600),
                ..request.reconstruct.clone()
            },
            read_within_s: Some(0),
        },
    )
    .unwrap();
    assert!(between.read.iter().all(|&r| !r));
    assert!(matches!(
        reconstruct_map(
            &project,
            &ReconstructMapRequest {
                read_within_s: Some(-1),
                ..request.clone()
            }
        ),
        Err(AppError::Invalid(_))
    ));
}
