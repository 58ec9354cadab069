//! Missions: stops, visits, cancel, delete, paging, validation.

use super::*;

/// A mission comes back exactly as created (profile, energies, seed above `i64::MAX`, stops
/// with and without terms), planned; `mission(id)` agrees with `missions()`.
pub fn missions_round_trip_with_stops<S: Store>(store: &mut S) {
    let adaptive = new_mission(MissionKind::Adaptive);
    let exploration = new_mission(MissionKind::Exploration);
    let mut empty = new_mission(MissionKind::Exploration);
    empty.stops.clear();
    let ids = w(store, |tx| {
        Ok([
            tx.create_mission(&adaptive)?,
            tx.create_mission(&exploration)?,
            tx.create_mission(&empty)?,
        ])
    })
    .unwrap();
    assert!(ids[0] < ids[1] && ids[1] < ids[2]);
    let all = store.missions().unwrap();
    assert_eq!(all.len(), 3);
    for ((record, id), new) in all.iter().zip(ids).zip([&adaptive, &exploration, &empty]) {
        assert_eq!(record.id, id);
        assert_eq!(&record.mission, new);
        assert_eq!(record.status, MissionStatus::Planned);
        assert_eq!(record.flown_at, None);
        assert!(record.visits.is_empty());
        assert_eq!(store.mission(id).unwrap().as_ref(), Some(record));
    }
    assert_eq!(store.mission(MissionId(ids[2].0 + 100)).unwrap(), None);
}

/// Recording visits marks a mission flown at the given time; recording again is
/// `AlreadyFlown` (naming the mission and the first time) unless `amend`, which replaces the
/// visits and the time. Unknown missions and bad visit lists are refused without writing.
pub fn record_visits_refuses_a_flown_mission_unless_amend<S: Store>(store: &mut S) {
    let new = new_mission(MissionKind::Adaptive);
    let (id, other) = w(store, |tx| {
        Ok((tx.create_mission(&new)?, tx.create_mission(&new)?))
    })
    .unwrap();
    let v = visits();
    w(store, |tx| tx.record_visits(id, &v, T0 + 900, false)).unwrap();
    let flown = store.mission(id).unwrap().unwrap();
    assert_eq!(
        flown,
        crate::MissionRecord {
            id,
            mission: new.clone(),
            status: MissionStatus::Flown,
            flown_at: Some(T0 + 900),
            visits: v.clone(),
        }
    );
    let err = w(store, |tx| tx.record_visits(id, &v[..1], T0 + 2_000, false)).unwrap_err();
    match &err {
        StoreError::AlreadyFlown { mission, flown_at } => {
            assert_eq!((*mission, *flown_at), (id.0, T0 + 900));
        }
        other => panic!("expected AlreadyFlown, got {other:?}"),
    }
    assert_eq!(store.mission(id).unwrap().unwrap(), flown);
    w(store, |tx| tx.record_visits(id, &v[..1], T0 + 2_000, true)).unwrap();
    let amended = store.mission(id).unwrap().unwrap();
    assert_eq!(
        (amended.flown_at, amended.visits.as_slice()),
        (Some(T0 + 2_000), &v[..1])
    );
    // amend on a planned mission simply records it.
    w(store, |tx| tx.record_visits(other, &[], T0 + 50, true)).unwrap();
    assert_eq!(
        store.mission(other).unwrap().unwrap().flown_at,
        Some(T0 + 50)
    );
    let err = w(store, |tx| tx.record_visits(MissionId(777), &[], T0, false)).unwrap_err();
    assert!(err.to_string().contains("777"), "{err}");
    let mut twice = visits();
    twice[1].order = 0;
    let before = store.missions().unwrap();
    assert!(w(store, |tx| tx.record_visits(id, &twice, T0, true)).is_err());
    let mut nan = visits();
    nan[0].energy_j = Some(f64::NAN);
    assert!(w(store, |tx| tx.record_visits(id, &nan, T0, true)).is_err());
    assert_eq!(store.missions().unwrap(), before);
}

/// A planned mission can be cancelled once (status `Cancelled`, nothing else changes) and a
/// cancelled one never recorded; a flown one cannot be cancelled. Deleting removes a mission
/// with its stops and visits; an unknown id is refused. A cancelled mission survives an
/// import. Pages are newest first, below `before`, at most `limit` long.
pub fn missions_cancel_delete_and_page<S: Store>(store: &mut S) {
    let new = new_mission(MissionKind::Adaptive);
    let ids = w(store, |tx| {
        (0..5)
            .map(|_| tx.create_mission(&new))
            .collect::<Result<Vec<_>>>()
    })
    .unwrap();
    let v = visits();
    w(store, |tx| tx.record_visits(ids[1], &v, T0 + 900, false)).unwrap();

    w(store, |tx| tx.cancel_mission(ids[0])).unwrap();
    let cancelled = store.mission(ids[0]).unwrap().unwrap();
    assert_eq!(cancelled.status, MissionStatus::Cancelled);
    assert_eq!((cancelled.flown_at, cancelled.visits.len()), (None, 0));
    assert_eq!(cancelled.mission, new);
    // Not twice, not a flown one, not an unknown one; and never recorded once cancelled.
    assert!(w(store, |tx| tx.cancel_mission(ids[0])).is_err());
    assert!(w(store, |tx| tx.cancel_mission(ids[1])).is_err());
    assert!(w(store, |tx| tx.cancel_mission(MissionId(777))).is_err());
    assert!(w(store, |tx| tx.record_visits(ids[0], &v, T0, true)).is_err());
    assert_eq!(store.mission(ids[0]).unwrap().unwrap(), cancelled);
    assert_eq!(
        store.mission(ids[1]).unwrap().unwrap().status,
        MissionStatus::Flown
    );

    // Delete a flown one (the store does not judge) and a cancelled one, then import it back.
    w(store, |tx| tx.delete_mission(ids[1])).unwrap();
    assert_eq!(store.mission(ids[1]).unwrap(), None);
    let err = w(store, |tx| tx.delete_mission(ids[1])).unwrap_err();
    assert!(err.to_string().contains(&ids[1].to_string()), "{err}");
    w(store, |tx| tx.delete_mission(ids[0])).unwrap();
    w(store, |tx| tx.import_mission(&cancelled)).unwrap();
    assert_eq!(store.mission(ids[0]).unwrap().unwrap(), cancelled);

    // Pages: newest first, no gap and no repeat.
    let left: Vec<MissionId> = [ids[4], ids[3], ids[2], ids[0]].into();
    let page = |before, limit| -> Vec<MissionId> {
        store
            .missions_page(before, limit)
            .unwrap()
            .iter()
            .map(|m| m.id)
            .collect()
    };
    assert_eq!(page(None, 10), left);
    assert_eq!(page(None, 2), left[..2]);
    assert_eq!(page(Some(ids[3]), 2), left[2..]);
    assert_eq!(page(Some(ids[0]), 2), Vec::<MissionId>::new());
    assert_eq!(page(None, 0), Vec::<MissionId>::new());
}

/// Missions with a non-finite number or a stop order used twice are refused, nothing written.
pub fn invalid_missions_write_nothing<S: Store>(store: &mut S) {
    let mut bad = Vec::new();
    let mut m = new_mission(MissionKind::Adaptive);
    m.energy.total_j = f64::NAN;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.weights[2] = f64::INFINITY;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.stops[1].terms = Some([0.0, f64::NAN, 0.0, 0.0]);
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.stops[1].order = 0;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.profile.cruise_speed_mps = f64::NEG_INFINITY;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.profile.wind_mps = -1.0;
    bad.push(m);
    let mut m = new_mission(MissionKind::Adaptive);
    m.profile.wind_from_deg = f64::NAN;
    bad.push(m);
    for m in &bad {
        let err = w(store, |tx| tx.create_mission(m)).unwrap_err();
        assert!(matches!(err, StoreError::Invalid { .. }), "{err:?}");
    }
    assert!(store.missions().unwrap().is_empty());
}
