//! Managing the mission history: paging through it, cancelling a planned mission and deleting
//! one that brought nothing home. The lifecycle rules live here; the store only flags and
//! deletes.
//!
//! A mission is *planned* when created, *flown* once recorded, or *cancelled*: a cancelled
//! mission stays in the history (its id is never reused) but is never recorded, exported or
//! re-planned. A mission may be deleted while it has no recorded flight (planned or
//! cancelled); a flown one holds the provenance of stored readings and is kept.

use gleaner_ingest::time::format_rfc3339;
use gleaner_store::{MissionId, MissionRecord, MissionStatus, Store, StoreRead, StoreWrite};

use gleaner_scoring::Project;
use gleaner_scoring::{AppError, Result};

/// The most missions one page holds.
pub const MAX_PAGE: usize = 500;

/// One page of the mission history, newest first.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionPage {
    /// At most the requested number of missions, in descending id order.
    pub missions: Vec<MissionRecord>,
    /// The `before` of the next page (the last id of this one) when older missions exist.
    pub next: Option<MissionId>,
}

/// The use case behind `missions --limit --before`: at most `limit` (1..=[`MAX_PAGE`])
/// missions with an id below `before` (the newest when `None`), newest first. The order is
/// by id, so a mission planned while paging never shifts or repeats a page.
pub fn missions_page<S: Store>(
    project: &Project<S>,
    before: Option<MissionId>,
    limit: usize,
) -> Result<MissionPage> {
    if !(1..=MAX_PAGE).contains(&limit) {
        return Err(AppError::Invalid(format!(
            "limit = {limit}: a page holds 1 to {MAX_PAGE} missions"
        )));
    }
    if let Some(b) = before
        && b.0 < 1
    {
        return Err(AppError::Invalid(format!(
            "before = {b}: mission ids start at 1"
        )));
    }
    // One more than asked tells whether an older page exists.
    let mut missions = project.store().missions_page(before, limit + 1)?;
    let more = missions.len() > limit;
    missions.truncate(limit);
    let next = if more {
        missions.last().map(|m| m.id)
    } else {
        None
    };
    Ok(MissionPage { missions, next })
}

/// Refuses to `action` (`record`, `export`, `re-plan`) a cancelled mission.
pub(crate) fn refuse_cancelled(mission: &MissionRecord, action: &str) -> Result<()> {
    if mission.status == MissionStatus::Cancelled {
        return Err(AppError::Conflict(format!(
            "mission #{} was cancelled: a cancelled mission cannot be {action}; plan a new one",
            mission.id
        )));
    }
    Ok(())
}

fn stored<T: StoreRead + ?Sized>(store: &T, id: MissionId) -> Result<MissionRecord> {
    store.mission(id)?.ok_or_else(|| AppError::NotFound {
        what: "mission",
        id: format!("#{id}"),
    })
}

/// The use case behind `cancel`: flags planned mission `id` cancelled, under the project's
/// exclusion and in one transaction with the check. Refused ([`AppError::Conflict`]) when
/// it was already recorded as flown or already cancelled; [`AppError::NotFound`] when
/// unknown. Returns the mission as now stored.
pub fn cancel_mission<S: Store>(project: &mut Project<S>, id: MissionId) -> Result<MissionRecord> {
    project.exclusive(|project| {
        project.store_mut().write(|tx| {
            let m = stored(tx, id)?;
            match m.status {
                MissionStatus::Planned => {}
                MissionStatus::Flown => {
                    return Err(AppError::Conflict(format!(
                        "mission #{id} was already recorded as flown{}: only a planned \
                         mission can be cancelled",
                        flown_at(&m)
                    )));
                }
                MissionStatus::Cancelled => {
                    return Err(AppError::Conflict(format!(
                        "mission #{id} is already cancelled"
                    )));
                }
            }
            tx.cancel_mission(id)?;
            stored(tx, id)
        })
    })
}

/// The use case behind `delete`: removes mission `id` with its stops, when it has no
/// recorded flight (planned or cancelled). Refused ([`AppError::Conflict`]) for a flown
/// mission, whose record is the provenance of stored readings; [`AppError::NotFound`] when
/// unknown.
pub fn delete_mission<S: Store>(project: &mut Project<S>, id: MissionId) -> Result<()> {
    project.exclusive(|project| {
        project.store_mut().write(|tx| {
            let m = stored(tx, id)?;
            if m.status == MissionStatus::Flown {
                return Err(AppError::Conflict(format!(
                    "mission #{id} was recorded as flown{} with {} visit(s): a mission with a \
                     recorded flight and readings is kept; cancel or delete only a mission not \
                     yet flown",
                    flown_at(&m),
                    m.visits.len()
                )));
            }
            tx.delete_mission(id)?;
            Ok(())
        })
    })
}

fn flown_at(m: &MissionRecord) -> String {
    m.flown_at
        .map_or(String::new(), |t| format!(" at {}", format_rfc3339(t)))
}

#[cfg(test)]
mod tests {
    use gleaner_store::conformance::new_mission;
    use gleaner_store::{MissionKind, SqliteStore, VisitRecord};

    use super::*;
    use gleaner_scoring::settings::Settings;

    fn project(n: usize) -> (tempfile::TempDir, Project<SqliteStore>, Vec<MissionId>) {
        let tmp = tempfile::tempdir().unwrap();
        let store = SqliteStore::open_in_memory().unwrap();
        let settings = Settings::parse(
            "[project]\nname = \"p\"\ndatabase = \"g.db\"\n[field]\nbase_lat = 38.7\n\
             base_lon = -117.1\ncell_size_m = 40.0\n[sensors]\nfile = \"s.csv\"\n",
        )
        .unwrap();
        let mut p = Project::new(tmp.path(), settings, store);
        let m = new_mission(MissionKind::Adaptive);
        let ids = p
            .store_mut()
            .write(|tx| (0..n).map(|_| tx.create_mission(&m)).collect())
            .unwrap();
        (tmp, p, ids)
    }

    fn fly(p: &mut Project<SqliteStore>, id: MissionId) {
        let cell = p.store().mission(id).unwrap().unwrap().mission.stops[0].cell;
        let v = [VisitRecord {
            order: 0,
            cell,
            arrived_at: None,
            energy_j: None,
        }];
        p.store_mut()
            .write(|tx| tx.record_visits(id, &v, 1_500_000_000, false))
            .unwrap();
    }

    #[test]
    fn pages_are_newest_first_with_a_next_cursor_until_the_oldest() {
        let (_t, p, ids) = project(5);
        let first = missions_page(&p, None, 2).unwrap();
        let got: Vec<_> = first.missions.iter().map(|m| m.id).collect();
        assert_eq!(got, [ids[4], ids[3]]);
        assert_eq!(first.next, Some(ids[3]));
        let second = missions_page(&p, first.next, 2).unwrap();
        assert_eq!(second.next, Some(ids[1]));
        let last = missions_page(&p, second.next, 2).unwrap();
        let got: Vec<_> = last.missions.iter().map(|m| m.id).collect();
        assert_eq!((got, last.next), (vec![ids[0]], None));
        // Exactly a page left: no cursor to an empty page.
        assert_eq!(missions_page(&p, Some(ids[2]), 2).unwrap().next, None);
        for bad in [0, MAX_PAGE + 1] {
            let err = missions_page(&p, None, bad).unwrap_err().to_string();
            assert!(err.contains(&format!("limit = {bad}")), "{err}");
        }
        assert!(missions_page(&p, Some(MissionId(0)), 2).is_err());
    }

    #[test]
    fn only_a_planned_mission_is_cancelled_and_it_stays_in_the_history() {
        let (_t, mut p, ids) = project(2);
        fly(&mut p, ids[1]);
        let m = cancel_mission(&mut p, ids[0]).unwrap();
        assert_eq!(m.status, MissionStatus::Cancelled);
        assert_eq!(p.store().missions().unwrap().len(), 2);
        let again = cancel_mission(&mut p, ids[0]).unwrap_err();
        assert!(matches!(again, AppError::Conflict(_)), "{again}");
        let flown = cancel_mission(&mut p, ids[1]).unwrap_err();
        assert!(
            matches!(&flown, AppError::Conflict(s) if s.contains("recorded as flown")),
            "{flown}"
        );
        let unknown = cancel_mission(&mut p, MissionId(99)).unwrap_err();
        assert!(matches!(unknown, AppError::NotFound { .. }), "{unknown}");
        let refused = refuse_cancelled(&m, "recorded").unwrap_err().to_string();
        assert!(refused.contains("was cancelled"), "{refused}");
    }

    #[test]
    fn a_flown_mission_is_never_deleted_a_planned_or_cancelled_one_is() {
        let (_t, mut p, ids) = project(3);
        fly(&mut p, ids[0]);
        cancel_mission(&mut p, ids[1]).unwrap();
        let err = delete_mission(&mut p, ids[0]).unwrap_err();
        assert!(matches!(err, AppError::Conflict(_)), "{err}");
        assert!(p.store().mission(ids[0]).unwrap().is_some());
        delete_mission(&mut p, ids[1]).unwrap();
        delete_mission(&mut p, ids[2]).unwrap();
        let left: Vec<_> = p.store().missions().unwrap().iter().map(|m| m.id).collect();
        assert_eq!(left, [ids[0]]);
        let gone = delete_mission(&mut p, ids[2]).unwrap_err();
        assert!(matches!(gone, AppError::NotFound { .. }), "{gone}");
    }
}
