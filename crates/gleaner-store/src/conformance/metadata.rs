//! The cell metadata table and cell replacement.

use super::*;

/// Cell metadata round-trips; scalars, scores and class probabilities are replaced, summaries,
/// correlations and anomalies upserted by key; unknown cells and out-of-range numbers write
/// nothing.
pub fn cell_metadata_round_trips_and_upserts_by_key<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
    })
    .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    assert_eq!(
        store.cell_metadata().unwrap(),
        vec![CellMetadata::new(x0), CellMetadata::new(x1)]
    );
    let full = full_metadata(x0, x1);
    w(store, |tx| {
        tx.upsert_cell_metadata(std::slice::from_ref(&full))
    })
    .unwrap();
    assert_eq!(store.cell_metadata().unwrap()[0], full);
    let mut next = CellMetadata::new(x0);
    next.anomalies.push(AnomalyRecord {
        modality: md("vw@30cm"),
        t: T0 + DAY,
        anomaly: 0.1,
        flagged: false,
    });
    let mut summary = full.summaries[0].clone();
    summary.stats.count = 3;
    next.summaries.push(summary.clone());
    w(store, |tx| tx.upsert_cell_metadata(&[next])).unwrap();
    let got = &store.cell_metadata().unwrap()[0];
    assert_eq!(got.scores, None);
    assert_eq!(got.class_probabilities, vec![]);
    assert_eq!(got.anomalies.len(), 2);
    assert_eq!(got.summaries, vec![summary]);
    assert_eq!(got.correlations, full.correlations);
    let before = store.cell_metadata().unwrap();
    let err = w(store, |tx| {
        tx.upsert_cell_metadata(&[
            full_metadata(x1, x0),
            CellMetadata::new(CellIndex { i: 9, j: 9 }),
        ])
    })
    .unwrap_err();
    assert!(err.to_string().contains("x9y9"), "{err}");
    for bad in [
        {
            let mut m = full_metadata(x0, x1);
            m.class_probabilities[0].probability = 1.5;
            m
        },
        {
            let mut m = full_metadata(x0, x1);
            m.correlations[0].correlation = -1.01;
            m
        },
        {
            let mut m = full_metadata(x0, x1);
            m.pending_bytes = Some(f64::NAN);
            m
        },
        {
            let mut m = full_metadata(x0, x1);
            m.summaries[0].modality = md("ec@5cm");
            m
        },
    ] {
        assert!(w(store, |tx| tx.upsert_cell_metadata(&[bad])).is_err());
    }
    let twice = [CellMetadata::new(x0), CellMetadata::new(x0)];
    assert!(w(store, |tx| tx.upsert_cell_metadata(&twice)).is_err());
    assert_eq!(store.cell_metadata().unwrap(), before);
}

/// Rewriting a cell's summaries and correlations with the same values leaves them as they
/// are; changed values replace them; a row listed twice in one write holds the last values
/// given, whether those equal the stored ones or not.
pub fn metadata_child_rows_hold_the_last_values_written<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])
    })
    .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    let full = full_metadata(x0, x1);
    let put = |store: &mut S, m: &CellMetadata| {
        w(store, |tx| tx.upsert_cell_metadata(std::slice::from_ref(m))).unwrap();
        store.cell_metadata().unwrap()[0].clone()
    };
    assert_eq!(put(store, &full), full);
    assert_eq!(put(store, &full), full);
    let mut changed = full.clone();
    changed.summaries[0].stats.count += 1;
    changed.summaries[0].stats.mean += 0.25;
    changed.correlations[0].correlation = -changed.correlations[0].correlation / 2.0;
    changed.correlations[0].overlap += 1;
    assert_eq!(put(store, &changed), changed);
    // Listed twice: stored values last (the first entry differs from them), then changed
    // values last (the first entry equals the stored ones).
    let mut twice = changed.clone();
    twice.summaries.push(full.summaries[0].clone());
    twice.correlations.push(full.correlations[0].clone());
    let got = put(store, &twice);
    assert_eq!(got.summaries, full.summaries);
    assert_eq!(got.correlations, full.correlations);
    let mut twice = full.clone();
    twice.summaries.push(changed.summaries[0].clone());
    twice.correlations.push(changed.correlations[0].clone());
    let got = put(store, &twice);
    assert_eq!(got.summaries, changed.summaries);
    assert_eq!(got.correlations, changed.correlations);
}

/// `cell_metadata_scalars` gives what `cell_metadata` gives with the child lists emptied, in
/// a transaction and outside one, for described and undescribed cells.
pub fn cell_metadata_scalars_are_the_rows_without_children<S: Store>(store: &mut S) {
    network(store);
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"]), cell(2, 0, &[])])
    })
    .unwrap();
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    let mut second = full_metadata(x1, x0);
    second.class_probabilities.reverse();
    second.scores = None;
    w(store, |tx| {
        tx.upsert_cell_metadata(&[full_metadata(x0, x1), second])
    })
    .unwrap();
    let stripped = |rows: Vec<CellMetadata>| -> Vec<CellMetadata> {
        rows.into_iter()
            .map(|mut m| {
                m.summaries.clear();
                m.correlations.clear();
                m.anomalies.clear();
                m
            })
            .collect()
    };
    let want = stripped(store.cell_metadata().unwrap());
    assert_eq!(want.len(), 3);
    assert!(!want[0].class_probabilities.is_empty());
    assert_eq!(store.cell_metadata_scalars().unwrap(), want);
    let in_tx = w(store, |tx| tx.cell_metadata_scalars()).unwrap();
    assert_eq!(in_tx, want);
}

/// `replace_cells` keeps identical cells with their metadata and deletes every other stored
/// cell with all its metadata, including correlations pointing at it.
pub fn replace_cells_keeps_or_deletes_metadata<S: Store>(store: &mut S) {
    network(store);
    let (x0, x1) = (CellIndex { i: 0, j: 0 }, CellIndex { i: 1, j: 0 });
    w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(1, 0, &["c"])])?;
        tx.upsert_cell_metadata(&[full_metadata(x0, x1), full_metadata(x1, x0)])
    })
    .unwrap();
    let same = w(store, |tx| {
        tx.replace_cells(&[cell(1, 0, &["c"]), cell(0, 0, &["b", "a"])])
    })
    .unwrap();
    assert_eq!((same.kept, same.removed, same.added), (2, 0, 0));
    assert_eq!(store.cell_metadata().unwrap()[0], full_metadata(x0, x1));
    let stats = w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a", "b"]), cell(2, 0, &["c"])])
    })
    .unwrap();
    assert_eq!((stats.kept, stats.removed, stats.added), (1, 1, 1));
    let mdata = store.cell_metadata().unwrap();
    assert_eq!(mdata.len(), 2);
    assert!(
        mdata[0].correlations.is_empty(),
        "correlation with x1 must go"
    );
    assert_eq!(mdata[0].anomalies.len(), 1);
    assert_eq!(mdata[0].summaries.len(), 1);
    assert_eq!(mdata[0].class_probabilities.len(), 3);
    assert_eq!(mdata[1], CellMetadata::new(CellIndex { i: 2, j: 0 }));
    // A cell whose side changes is a new cell.
    let mut wider = cell(0, 0, &["a", "b"]);
    wider.cell_size_m = 50.0;
    let stats = w(store, |tx| {
        tx.replace_cells(&[wider.clone(), cell(2, 0, &["c"])])
    })
    .unwrap();
    assert_eq!((stats.kept, stats.removed, stats.added), (1, 1, 1));
    assert_eq!(store.cell_metadata().unwrap()[0], CellMetadata::new(x0));
    // Invalid grids are refused whole.
    let before = store.cells().unwrap();
    let err = w(store, |tx| {
        tx.replace_cells(&[cell(0, 0, &["a"]), cell(1, 0, &["a"])])
    })
    .unwrap_err();
    assert!(err.to_string().contains("sensor a is in cells"), "{err}");
    assert!(w(store, |tx| tx.replace_cells(&[cell(5, 5, &["nope"])])).is_err());
    assert!(
        w(store, |tx| tx
            .replace_cells(&[cell(5, 5, &["a"]), cell(5, 5, &["b"])]))
        .is_err()
    );
    let mut zero = cell(5, 5, &["a"]);
    zero.cell_size_m = 0.0;
    assert!(w(store, |tx| tx.replace_cells(&[zero])).is_err());
    assert_eq!(store.cells().unwrap(), before);
    assert_eq!(before[0], wider);
}
