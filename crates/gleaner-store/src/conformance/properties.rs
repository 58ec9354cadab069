//! Order and idempotence, and a property check against a naive model.

use super::*;

/// Lists come sorted by name or index whatever the insertion order, missions oldest first.
pub fn results_come_in_a_deterministic_order<S: Store>(store: &mut S) {
    w(store, |tx| {
        tx.upsert_sensors(&[
            sensor("z1", 46.0, -117.0),
            sensor("B", 46.0, -117.0),
            sensor("a10", 46.0, -117.0),
            sensor("a9", 46.0, -117.0),
        ])?;
        tx.upsert_modalities(&[modality("vw@90cm", None), modality("t@30cm", None)])?;
        tx.replace_cells(&[
            cell(1, 0, &["z1"]),
            cell(-1, 2, &["B"]),
            cell(0, 5, &["a10"]),
            cell(0, -1, &["a9"]),
        ])?;
        tx.set_sensors_collected(&[(sid("z1"), T0), (sid("B"), T0)])
    })
    .unwrap();
    let names: Vec<String> = store
        .sensors()
        .unwrap()
        .iter()
        .map(|s| s.id.to_string())
        .collect();
    assert_eq!(names, ["B", "a10", "a9", "z1"]);
    let mods: Vec<String> = store
        .modalities()
        .unwrap()
        .iter()
        .map(|m| m.modality.to_string())
        .collect();
    assert_eq!(mods, ["t@30cm", "vw@90cm"]);
    let cells: Vec<String> = store
        .cells()
        .unwrap()
        .iter()
        .map(|c| c.index.to_string())
        .collect();
    let mut sorted = vec![
        CellIndex { i: 1, j: 0 },
        CellIndex { i: -1, j: 2 },
        CellIndex { i: 0, j: 5 },
        CellIndex { i: 0, j: -1 },
    ];
    sorted.sort();
    let expected: Vec<String> = sorted.iter().map(ToString::to_string).collect();
    assert_eq!(cells, expected);
    let md_cells: Vec<CellIndex> = store
        .cell_metadata()
        .unwrap()
        .iter()
        .map(|m| m.cell)
        .collect();
    assert_eq!(md_cells, sorted);
    let collected: Vec<String> = store
        .sensor_last_collected()
        .unwrap()
        .iter()
        .map(|(s, _)| s.to_string())
        .collect();
    assert_eq!(collected, ["B", "z1"]);
    // The same reads twice give the same answer.
    assert_eq!(snapshot(store), snapshot(store));
}

/// Randomised (seeded): inserting any batch twice inserts nothing the second time, and the
/// counts add up.
pub fn inserting_twice_inserts_nothing_the_second_time<S: Store>(store: &mut S) {
    network(store);
    let sensors = ["a", "b", "c"];
    let modalities = ["vw@30cm", "t@30cm"];
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut stored: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
    for round in 0..24 {
        let n = rng.below(300) as usize;
        let mut b = ReadingBatchBuilder::new();
        let mut distinct_new = HashSet::new();
        let mut first_in_batch: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
        for _ in 0..n {
            let (s, m) = (rng.below(3) as usize, rng.below(2) as usize);
            let t = (rng.below(40) + 40 * round) as i64;
            let v = (rng.below(6) as f64 - 3.0) * 0.5;
            b.push(&sid(sensors[s]), &md(modalities[m]), T0 + t * 60, v);
            if !stored.contains_key(&(s, m, t)) {
                distinct_new.insert((s, m, t));
            }
            first_in_batch.entry((s, m, t)).or_insert(v);
        }
        let b = b.finish();
        let first = insert(store, &b, ConflictPolicy::Skip).unwrap();
        assert_eq!(first.inserted as usize, distinct_new.len());
        assert_eq!(
            first.inserted as usize + first.unchanged as usize + first.conflicts.len(),
            n
        );
        for (k, v) in first_in_batch {
            stored.entry(k).or_insert(v);
        }
        let second = insert(store, &b, ConflictPolicy::Skip).unwrap();
        assert_eq!(second.inserted, 0);
        assert_eq!(second.unchanged as usize + second.conflicts.len(), n);
        assert_eq!(store.reading_count().unwrap() as usize, stored.len());
    }
}

/// Randomised (seeded): what comes back is exactly the first value inserted for each key, in
/// key order, over the whole range and over sub-ranges.
pub fn stored_readings_match_a_naive_model<S: Store>(store: &mut S) {
    network(store);
    let sensors = ["a", "b", "c"];
    let modalities = ["t@30cm", "vw@30cm"];
    let mut rng = Rng(0x0123_4567_89AB_CDEF);
    let mut model: BTreeMap<(usize, usize, i64), f64> = BTreeMap::new();
    for _ in 0..8 {
        let mut b = ReadingBatchBuilder::new();
        for _ in 0..rng.below(200) + 1 {
            let (s, m, t) = (
                rng.below(3) as usize,
                rng.below(2) as usize,
                rng.below(30) as i64,
            );
            let v = (rng.next() >> 11) as f64 / (1u64 << 53) as f64 * 2e3 - 1e3;
            model.entry((s, m, t)).or_insert(v);
            b.push(&sid(sensors[s]), &md(modalities[m]), T0 + t * DAY, v);
        }
        insert(store, &b.finish(), ConflictPolicy::Skip).unwrap();
    }
    let expected: Vec<(String, String, i64, f64)> = model
        .iter()
        .map(|(&(s, m, t), &v)| {
            (
                sensors[s].to_string(),
                modalities[m].to_string(),
                T0 + t * DAY,
                v,
            )
        })
        .collect();
    let all = store.readings_for(None, i64::MIN..=i64::MAX).unwrap();
    assert_eq!(rows_of(&all), expected);
    let (lo, hi) = (T0 + 7 * DAY, T0 + 19 * DAY);
    let part: Vec<_> = expected
        .iter()
        .filter(|r| (lo..=hi).contains(&r.2) && r.0 != "b")
        .cloned()
        .collect();
    let got = store
        .readings_of_sensors(&[sid("c"), sid("a")], lo..=hi)
        .unwrap();
    assert_eq!(rows_of(&got), part);
}
