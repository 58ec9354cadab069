//! Transactions, configuration, blobs and ingest records.

use super::*;

/// A write closure that returns `Err` leaves nothing of any of its writes: sensors,
/// modalities, readings, provenance, cells, metadata, collection times, missions, visits,
/// settings, blobs.
pub fn a_failed_write_closure_rolls_everything_back<S: Store>(store: &mut S) {
    network(store);
    let mission = w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"])])?;
        tx.create_mission(&new_mission(MissionKind::Exploration))
    })
    .unwrap();
    let before = snapshot(store);
    let out: Result<()> = w(store, |tx| {
        tx.upsert_sensors(&[sensor("d", 46.0, -117.1)])?;
        tx.upsert_modalities(&[modality("humidity", Some("%"))])?;
        tx.insert_readings(
            &batch(&[("d", "humidity", T0, 40.0), ("a", "vw@30cm", T0, 0.3)]),
            ConflictPolicy::Fail,
        )?;
        tx.record_ingest(&ingest_record("x.csv"))?;
        tx.replace_cells(&[cell(0, 0, &["a"]), cell(1, 0, &["b", "d"])])?;
        tx.upsert_cell_metadata(&[full_metadata(
            CellIndex { i: 0, j: 0 },
            CellIndex { i: 1, j: 0 },
        )])?;
        tx.set_sensors_collected(&[(sid("a"), T0)])?;
        tx.create_mission(&new_mission(MissionKind::Adaptive))?;
        tx.record_visits(mission, &visits(), T0 + 500, false)?;
        tx.config_set("k", "v")?;
        tx.blob_put("state", b"\x00\x01")?;
        // Everything is visible inside the transaction ...
        assert_eq!(tx.reading_count()?, 2);
        assert_eq!(tx.missions()?.len(), 2);
        Err(StoreError::Invalid {
            what: "test",
            detail: "the use case gives up".into(),
        })
    });
    assert!(matches!(out, Err(StoreError::Invalid { what: "test", .. })));
    // ... and nothing after the rollback.
    assert_eq!(snapshot(store), before);
    // A caller error type converts from StoreError and rolls back the same way.
    #[derive(Debug)]
    enum AppError {
        Store,
        Gave,
    }
    impl From<StoreError> for AppError {
        fn from(_: StoreError) -> Self {
            AppError::Store
        }
    }
    let out: Result<(), AppError> = store.write(|tx| {
        tx.config_set("k", "v")?;
        Err(AppError::Gave)
    });
    assert!(matches!(out, Err(AppError::Gave)));
    let out: Result<(), AppError> = store.write(|tx| {
        tx.config_set("k", "v")?;
        tx.insert_readings(&batch(&[("zz", "vw@30cm", T0, 1.0)]), ConflictPolicy::Fail)?;
        Ok(())
    });
    assert!(matches!(out, Err(AppError::Store)));
    assert_eq!(snapshot(store), before);
}

/// A write method that fails inside a transaction undoes its own writes only: the closure may
/// handle the error and commit the rest.
pub fn a_failed_method_undoes_only_itself<S: Store>(store: &mut S) {
    network(store);
    let failed = w(store, |tx| {
        tx.config_set("k", "kept")?;
        tx.insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)?;
        // Conflicts half-way through: the new reading of this batch must not stay.
        let err = tx
            .insert_readings(
                &batch(&[("b", "vw@30cm", T0, 0.5), ("a", "vw@30cm", T0, 0.4)]),
                ConflictPolicy::Fail,
            )
            .unwrap_err();
        // A unit mismatch after a new modality in the same list: the new one must not stay.
        tx.upsert_modalities(&[
            modality("ec@5cm", Some("dS/m")),
            modality("vw@30cm", Some("%")),
        ])
        .unwrap_err();
        Ok(err)
    })
    .unwrap();
    assert!(matches!(failed, StoreError::Conflicts(_)));
    assert_eq!(store.config_get("k").unwrap().as_deref(), Some("kept"));
    assert_eq!(
        dump(store).into_iter().collect::<Vec<_>>(),
        vec![(("a".into(), "vw@30cm".into(), T0), 0.3)]
    );
    assert_eq!(store.modalities().unwrap().len(), 2);
}

/// Reads inside a transaction see its writes; the committed state is what the store reads.
pub fn a_transaction_reads_its_own_writes<S: Store>(store: &mut S) {
    network(store);
    let id = w(store, |tx| {
        tx.insert_readings(&batch(&[("a", "vw@30cm", T0, 0.3)]), ConflictPolicy::Fail)?;
        assert_eq!(tx.reading_count()?, 1);
        assert_eq!(rows_of(&tx.readings_for(None, T0..=T0)?).len(), 1);
        tx.config_set("k", "1")?;
        assert_eq!(tx.config_get("k")?.as_deref(), Some("1"));
        tx.blob_put("state", b"abc")?;
        assert_eq!(tx.blob_get("state")?.as_deref(), Some(&b"abc"[..]));
        let id = tx.create_mission(&new_mission(MissionKind::Adaptive))?;
        assert_eq!(
            tx.mission(id)?.map(|m| m.status),
            Some(MissionStatus::Planned)
        );
        Ok(id)
    })
    .unwrap();
    assert_eq!(store.reading_count().unwrap(), 1);
    assert!(store.mission(id).unwrap().is_some());
}

/// The read and write traits can be used as trait objects (callers can hold any backend's
/// transaction behind `&mut dyn StoreWrite`).
pub fn write_traits_are_dyn_compatible<S: Store>(store: &mut S) {
    network(store);
    fn collect(tx: &mut dyn StoreWrite) -> Result<()> {
        tx.set_sensors_collected(&[(sid("a"), T0)])
    }
    fn read(r: &dyn StoreRead) -> Vec<(SensorId, UnixSeconds)> {
        r.sensor_last_collected().unwrap()
    }
    w(store, |tx| collect(tx)).unwrap();
    assert_eq!(read(store), vec![(sid("a"), T0)]);
}

/// Ingest records come back oldest first with their ids increasing; settings are replaced.
pub fn ingests_and_config<S: Store>(store: &mut S) {
    let (r1, r2) = (ingest_record("one.csv"), ingest_record("two.csv"));
    let (id1, id2) = w(store, |tx| {
        Ok((tx.record_ingest(&r1)?, tx.record_ingest(&r2)?))
    })
    .unwrap();
    assert!(id2 > id1);
    assert_eq!(store.ingests().unwrap(), vec![r1, r2]);
    w(store, |tx| tx.config_set("k", "1")).unwrap();
    w(store, |tx| tx.config_set("k", "2")).unwrap();
    assert_eq!(store.config_get("k").unwrap().as_deref(), Some("2"));
    assert_eq!(store.config_get("other").unwrap(), None);
}

/// Blobs come back byte for byte (empty, NUL bytes, large), replaced by key.
pub fn blobs_round_trip<S: Store>(store: &mut S) {
    let big: Vec<u8> = (0..300_000u32).map(|k| (k * 7 % 251) as u8).collect();
    w(store, |tx| {
        tx.blob_put("empty", b"")?;
        tx.blob_put("nul", b"\x00a\x00\xff")?;
        tx.blob_put("big", &big)
    })
    .unwrap();
    assert_eq!(store.blob_get("empty").unwrap(), Some(Vec::new()));
    assert_eq!(
        store.blob_get("nul").unwrap(),
        Some(b"\x00a\x00\xff".to_vec())
    );
    assert_eq!(store.blob_get("big").unwrap(), Some(big));
    w(store, |tx| tx.blob_put("nul", b"second")).unwrap();
    assert_eq!(store.blob_get("nul").unwrap(), Some(b"second".to_vec()));
    assert_eq!(store.blob_get("missing").unwrap(), None);
}

/// Last collection times only move forward; unknown sensors are refused.
pub fn sensors_collected_never_move_back<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.set_sensors_collected(&[(sid("b"), T0), (sid("a"), T0 + DAY)])
    })
    .unwrap();
    w(store, |tx| {
        tx.set_sensors_collected(&[(sid("a"), T0), (sid("b"), T0 + 5)])
    })
    .unwrap();
    assert_eq!(
        store.sensor_last_collected().unwrap(),
        vec![(sid("a"), T0 + DAY), (sid("b"), T0 + 5)]
    );
    let err = w(store, |tx| {
        tx.set_sensors_collected(&[(sid("c"), T0), (sid("zz"), T0)])
    })
    .unwrap_err();
    assert!(matches!(err, StoreError::UnknownSensor(_)), "{err:?}");
    assert_eq!(store.sensor_last_collected().unwrap().len(), 2);
}
