//! Readings, sensors, modalities and their batches.

use super::*;

/// A fresh store is empty and reports a schema version.
pub fn empty_store_reads_empty<S: Store>(store: &mut S) {
    assert!(store.schema_version().unwrap() >= 1);
    assert_eq!(store.reading_count().unwrap(), 0);
    assert!(store.sensor_reading_counts().unwrap().is_empty());
    assert!(store.sensors().unwrap().is_empty());
    assert!(store.missions().unwrap().is_empty());
    assert_eq!(store.mission(MissionId(1)).unwrap(), None);
    assert_eq!(store.config_get("k").unwrap(), None);
    assert_eq!(store.blob_get("k").unwrap(), None);
    assert!(store.cell_metadata().unwrap().is_empty());
}

/// Sensor upserts are idempotent, report new, moved and unchanged sensors, and refuse a sensor
/// listed twice with different content without writing anything.
pub fn sensors_upsert_idempotently_and_report_moves<S: Store>(store: &mut S) {
    let two = [sensor("a", 46.0, -117.0), sensor("b", 46.1, -117.0)];
    let first = w(store, |tx| tx.upsert_sensors(&two)).unwrap();
    assert_eq!(first.added, vec!["a", "b"]);
    let again = w(store, |tx| tx.upsert_sensors(&two)).unwrap();
    assert_eq!(
        (again.added.len(), again.updated.len(), again.unchanged),
        (0, 0, 2)
    );
    let moved = w(store, |tx| {
        tx.upsert_sensors(&[sensor("a", 46.0, -117.0), sensor("b", 46.2, -117.0)])
    })
    .unwrap();
    assert_eq!(moved.updated, vec!["b"]);
    assert_eq!(store.sensors().unwrap()[1].position.lat(), 46.2);
    let err = w(store, |tx| {
        tx.upsert_sensors(&[sensor("c", 46.0, -117.0), sensor("c", 46.5, -117.0)])
    })
    .unwrap_err();
    assert!(err.to_string().contains("\"c\""), "{err}");
    let mut nan = sensor("d", 46.0, -117.0);
    nan.elevation_m = Some(f64::NAN);
    assert!(w(store, |tx| tx.upsert_sensors(&[nan])).is_err());
    assert_eq!(store.sensors().unwrap().len(), 2);
}

/// A modality keeps its unit: the same unit or none is unchanged, a unit for a unit-less
/// modality is recorded, a different unit is `UnitMismatch` naming both and writes nothing.
pub fn modalities_keep_their_unit<S: Store>(store: &mut S) {
    network(store);
    let stats = w(store, |tx| {
        tx.upsert_modalities(&[
            modality("vw@30cm", Some("m3/m3")),
            modality("t@30cm", None),
            modality("humidity", None),
        ])
    })
    .unwrap();
    assert_eq!(stats.added, vec!["humidity"]);
    assert_eq!(stats.unchanged, 2);
    let stats = w(store, |tx| {
        tx.upsert_modalities(&[modality("humidity", Some("%"))])
    })
    .unwrap();
    assert_eq!(stats.updated, vec!["humidity"]);
    let before = store.modalities().unwrap();
    assert_eq!(
        before,
        vec![
            modality("humidity", Some("%")),
            modality("t@30cm", Some("degC")),
            modality("vw@30cm", Some("m3/m3")),
        ]
    );
    let err = w(store, |tx| {
        tx.upsert_modalities(&[
            modality("ec@5cm", Some("dS/m")),
            modality("vw@30cm", Some("%")),
        ])
    })
    .unwrap_err();
    match &err {
        StoreError::UnitMismatch {
            modality,
            stored,
            incoming,
        } => {
            assert_eq!(
                (modality.as_str(), stored.as_str(), incoming.as_str()),
                ("vw@30cm", "m3/m3", "%")
            );
        }
        other => panic!("expected UnitMismatch, got {other:?}"),
    }
    assert!(
        err.to_string().contains("m3/m3") && err.to_string().contains('%'),
        "{err}"
    );
    assert_eq!(
        store.modalities().unwrap(),
        before,
        "nothing may be written"
    );
    let err = w(store, |tx| {
        tx.upsert_modalities(&[modality("x", Some("a")), modality("x", Some("b"))])
    })
    .unwrap_err();
    assert!(matches!(err, StoreError::Invalid { .. }), "{err:?}");
}

/// Re-inserting stored readings inserts nothing and counts them unchanged (also within the
/// 1e-12 relative tolerance).
pub fn reinserting_readings_changes_nothing<S: Store>(store: &mut S) {
    network(store);
    let b = batch(&[
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0 + DAY, 0.31),
        ("b", "t@30cm", T0, 4.5),
    ]);
    let first = insert(store, &b, ConflictPolicy::Fail).unwrap();
    assert_eq!((first.inserted, first.unchanged), (3, 0));
    let before = dump(store);
    let second = insert(store, &b, ConflictPolicy::Fail).unwrap();
    assert_eq!((second.inserted, second.unchanged), (0, 3));
    assert!(second.conflicts.is_empty());
    assert_eq!(dump(store), before);
    let close = batch(&[("a", "vw@30cm", T0, 0.3 * (1.0 + 1e-14))]);
    let s = insert(store, &close, ConflictPolicy::Fail).unwrap();
    assert_eq!((s.inserted, s.unchanged), (0, 1));
    assert_eq!(store.reading_count().unwrap(), 3);
    assert_eq!(
        store.sensor_reading_counts().unwrap(),
        vec![(sid("a"), 2), (sid("b"), 1)]
    );
}

/// A conflicting reading under `Fail` writes nothing (not even the batch's new readings);
/// under `Skip` the stored value stays and the conflict is reported.
pub fn conflicts_fail_or_skip<S: Store>(store: &mut S) {
    network(store);
    insert(
        store,
        &batch(&[("a", "vw@30cm", T0, 0.3)]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let incoming = batch(&[("a", "vw@30cm", T0 + DAY, 0.2), ("a", "vw@30cm", T0, 0.4)]);
    let err = insert(store, &incoming, ConflictPolicy::Fail).unwrap_err();
    match &err {
        StoreError::Conflicts(c) => {
            assert_eq!(c.len(), 1);
            assert_eq!(
                (c[0].sensor.as_str(), c[0].modality.as_str()),
                ("a", "vw@30cm")
            );
            assert_eq!((c[0].stored, c[0].incoming, c[0].t), (0.3, 0.4, T0));
        }
        other => panic!("expected conflicts, got {other:?}"),
    }
    assert!(
        err.to_string().contains("stored 0.3 vs incoming 0.4"),
        "{err}"
    );
    assert_eq!(store.reading_count().unwrap(), 1, "fail must write nothing");
    let stats = insert(store, &incoming, ConflictPolicy::Skip).unwrap();
    assert_eq!(
        (stats.inserted, stats.unchanged, stats.conflicts.len()),
        (1, 0, 1)
    );
    assert_eq!(dump(store)[&("a".into(), "vw@30cm".into(), T0)], 0.3);
}

/// Duplicates within one batch: identical ones are unchanged, differing ones conflict, the
/// first occurrence wins.
pub fn duplicates_within_a_batch<S: Store>(store: &mut S) {
    network(store);
    let b = batch(&[
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0, 0.3),
        ("a", "vw@30cm", T0 + DAY, 0.1),
        ("a", "vw@30cm", T0 + DAY, 0.2),
    ]);
    assert!(matches!(
        insert(store, &b, ConflictPolicy::Fail),
        Err(StoreError::Conflicts(_))
    ));
    assert_eq!(store.reading_count().unwrap(), 0);
    let s = insert(store, &b, ConflictPolicy::Skip).unwrap();
    assert_eq!((s.inserted, s.unchanged, s.conflicts.len()), (2, 1, 1));
    assert_eq!(dump(store)[&("a".into(), "vw@30cm".into(), T0 + DAY)], 0.1);
}

/// Unknown sensors or modalities, bad indices and non-finite values reject the whole batch.
pub fn bad_batches_are_rejected_whole<S: Store>(store: &mut S) {
    network(store);
    let mut check = |b: ReadingBatch, expected: &str| {
        let err = insert(store, &b, ConflictPolicy::Skip).unwrap_err();
        assert!(
            err.to_string().contains(expected),
            "{err} lacks {expected:?}"
        );
        assert_eq!(store.reading_count().unwrap(), 0);
    };
    check(
        batch(&[("a", "vw@30cm", T0, 0.3), ("zz9", "vw@30cm", T0, 0.3)]),
        "unknown sensor \"zz9\"",
    );
    check(
        batch(&[("a", "vw@30cm", T0, 0.3), ("a", "ec@5cm", T0, 0.3)]),
        "unknown modality \"ec@5cm\"",
    );
    check(
        batch(&[("a", "vw@30cm", T0, 0.3), ("b", "vw@30cm", T0, f64::NAN)]),
        "value NaN is not finite",
    );
    check(
        batch(&[
            ("a", "vw@30cm", T0, 0.3),
            ("b", "vw@30cm", T0, f64::INFINITY),
        ]),
        "not finite",
    );
    let mut b = batch(&[("a", "vw@30cm", T0, 0.3)]);
    b.rows.push(Reading {
        sensor: 3,
        modality: 0,
        t: T0,
        value: 1.0,
    });
    check(b, "sensor index 3 out of range");
    let mut b = batch(&[("a", "vw@30cm", T0, 0.3)]);
    b.rows.push(Reading {
        sensor: 0,
        modality: 7,
        t: T0,
        value: 1.0,
    });
    check(b, "modality index 7 out of range");
}

/// A conflict in the middle of a 30 000-reading insert leaves exactly the previous readings.
pub fn a_failure_deep_in_a_big_insert_leaves_the_exact_pre_state<S: Store>(store: &mut S) {
    network(store);
    let seed = batch(&[
        ("b", "t@30cm", T0 + 5_000 * 60, 1.0),
        ("c", "vw@30cm", T0, 0.2),
    ]);
    insert(store, &seed, ConflictPolicy::Fail).unwrap();
    let before = dump(store);
    let mut b = ReadingBatchBuilder::new();
    for k in 0..10_000 {
        for (s, m) in [("a", "vw@30cm"), ("b", "t@30cm"), ("c", "t@30cm")] {
            b.push(&sid(s), &md(m), T0 + k * 60, k as f64);
        }
    }
    let err = insert(store, &b.finish(), ConflictPolicy::Fail).unwrap_err();
    assert!(matches!(err, StoreError::Conflicts(_)), "{err}");
    assert_eq!(dump(store), before);
    assert_eq!(store.reading_count().unwrap(), 2);
}

/// `latest_readings` gives, per sensor with a reading of the modality in the range, the last
/// row of `readings_for` over the same range, sorted by sensor id; also inside a transaction.
pub fn latest_readings_are_the_last_rows_of_readings_for<S: Store>(store: &mut S) {
    network(store);
    assert!(
        store
            .latest_readings(&md("vw@30cm"), i64::MIN..=i64::MAX)
            .unwrap()
            .is_empty()
    );
    insert(
        store,
        &batch(&[
            ("c", "vw@30cm", T0, 3.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "t@30cm", T0 + 5 * DAY, 9.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ("b", "vw@30cm", T0 + 3 * DAY, 6.0),
        ]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let naive = |store: &S, m: &str, range: std::ops::RangeInclusive<i64>| {
        let got = store.readings_for(Some(&md(m)), range).unwrap();
        let mut last: Vec<(SensorId, i64, f64)> = Vec::new();
        for r in &got.rows {
            let s = got.sensors[r.sensor as usize].clone();
            match last.last_mut() {
                Some(l) if l.0 == s => *l = (s, r.t, r.value),
                _ => last.push((s, r.t, r.value)),
            }
        }
        last
    };
    let ranges = [
        i64::MIN..=i64::MAX,
        T0..=T0,
        T0..=T0 + 2 * DAY,
        T0 + DAY..=T0 + 2 * DAY,
        T0 + 4 * DAY..=T0 + 9 * DAY,
        std::ops::RangeInclusive::new(T0 + 9 * DAY, T0), // empty: starts after it ends
    ];
    for m in ["vw@30cm", "t@30cm", "vw@60cm"] {
        for range in &ranges {
            let want = naive(store, m, range.clone());
            assert_eq!(
                store.latest_readings(&md(m), range.clone()).unwrap(),
                want,
                "{m} {range:?}"
            );
        }
    }
    assert_eq!(
        store
            .latest_readings(&md("vw@30cm"), T0..=T0 + 2 * DAY)
            .unwrap(),
        vec![
            (sid("a"), T0 + DAY, 2.0),
            (sid("b"), T0 + 2 * DAY, 5.0),
            (sid("c"), T0, 3.0)
        ]
    );
    let in_tx = w(store, |tx| tx.latest_readings(&md("vw@30cm"), T0..=T0)).unwrap();
    assert_eq!(in_tx, vec![(sid("a"), T0, 1.0), (sid("c"), T0, 3.0)]);
}

/// `readings_for` filters by modality and inclusive time range and orders by sensor, modality,
/// time; the batch lists only the sensors and modalities it uses.
pub fn readings_for_filters_and_orders<S: Store>(store: &mut S) {
    network(store);
    insert(
        store,
        &batch(&[
            ("c", "vw@30cm", T0, 3.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "t@30cm", T0, 9.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
        ]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let check = |modality: Option<&str>,
                 range: std::ops::RangeInclusive<i64>,
                 expected: &[(&str, &str, i64, f64)]| {
        let m = modality.map(md);
        let got = store.readings_for(m.as_ref(), range).unwrap();
        let expected: Vec<(String, String, i64, f64)> = expected
            .iter()
            .map(|(s, m, t, v)| (s.to_string(), m.to_string(), *t, *v))
            .collect();
        assert_eq!(rows_of(&got), expected);
        let used: HashSet<&str> = expected.iter().map(|r| r.0.as_str()).collect();
        assert_eq!(got.sensors.len(), used.len());
    };
    check(
        None,
        i64::MIN..=i64::MAX,
        &[
            ("a", "t@30cm", T0, 9.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ("c", "vw@30cm", T0, 3.0),
        ],
    );
    check(
        Some("vw@30cm"),
        T0 + DAY..=T0 + 2 * DAY,
        &[
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
        ],
    );
    check(Some("t@30cm"), T0 + 1..=T0 + DAY, &[]);
    check(Some("ec@5cm"), i64::MIN..=i64::MAX, &[]);
}

/// `readings_of_sensors` returns the given sensors' readings only (all modalities, in range),
/// ordered by sensor, modality, time whatever the order asked in; duplicates are ignored and
/// an unknown sensor is an error.
pub fn readings_of_sensors_selects_and_orders<S: Store>(store: &mut S) {
    network(store);
    insert(
        store,
        &batch(&[
            ("c", "vw@30cm", T0, 3.0),
            ("a", "vw@30cm", T0 + DAY, 2.0),
            ("a", "vw@30cm", T0, 1.0),
            ("a", "t@30cm", T0 + 3 * DAY, 9.0),
            ("b", "vw@30cm", T0 + 2 * DAY, 5.0),
            ("c", "t@30cm", T0 - DAY, 7.0),
        ]),
        ConflictPolicy::Fail,
    )
    .unwrap();
    let got = store
        .readings_of_sensors(&[sid("c"), sid("a"), sid("c")], T0..=T0 + 2 * DAY)
        .unwrap();
    let expected = vec![
        ("a".to_string(), "vw@30cm".to_string(), T0, 1.0),
        ("a".into(), "vw@30cm".into(), T0 + DAY, 2.0),
        ("c".into(), "vw@30cm".into(), T0, 3.0),
    ];
    assert_eq!(rows_of(&got), expected);
    assert_eq!(got.sensors, vec![sid("a"), sid("c")]);
    let all = store
        .readings_of_sensors(&[sid("c")], i64::MIN..=i64::MAX)
        .unwrap();
    assert_eq!(
        rows_of(&all),
        vec![
            ("c".to_string(), "t@30cm".to_string(), T0 - DAY, 7.0),
            ("c".into(), "vw@30cm".into(), T0, 3.0),
        ]
    );
    assert!(
        store
            .readings_of_sensors(&[], i64::MIN..=i64::MAX)
            .unwrap()
            .is_empty()
    );
    let err = store
        .readings_of_sensors(&[sid("a"), sid("nope")], i64::MIN..=i64::MAX)
        .unwrap_err();
    assert!(
        matches!(err, StoreError::UnknownSensor(ref s) if s.as_str() == "nope"),
        "{err:?}"
    );
    // The same answer inside a transaction.
    let inside = w(store, |tx| {
        tx.readings_of_sensors(&[sid("c"), sid("a")], T0..=T0 + 2 * DAY)
    })
    .unwrap();
    assert_eq!(rows_of(&inside), expected);
}
