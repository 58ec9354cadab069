//! [`SqliteStore`]: the [`Store`] on an SQLite file, and its write transaction [`SqliteTx`].
//!
//! Queries are written once, in [`read`], over a `&Connection`; the store runs each in its own
//! read snapshot, the transaction runs them inside itself (a use case reads its own writes).
//! The writes live in [`write`]; each write method but `insert_readings` runs in a savepoint of
//! the transaction, so a method that fails leaves the transaction as it was before the call.
//! `insert_readings` checks everything (names, values, conflicts) before its first write
//! instead: a savepoint around a bulk insert into a large table made SQLite copy every touched
//! page to the sub-journal and walk that journal at the end of every statement, which made a
//! second year of readings 76 times slower than the first (see `BENCHMARKS.md`).

mod dump;
mod read;
mod write;

use std::cell::{Cell, RefCell};
use std::ops::RangeInclusive;
use std::path::Path;
use std::time::Duration;

use gleaner_field::{Modality, SensorId, UnixSeconds};
use rusqlite::{Connection, OptionalExtension, Transaction, TransactionBehavior};

use crate::schema::{self, Migration};
use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    ModalityRecord, NewMission, ReadingBatch, ReplaceCellsStats, Result, SensorRecord, Store,
    StoreError, StoreRead, StoreWrite, UpsertStats, VisitRecord,
};

/// How long a writer waits for another connection's write lock before failing (the same as
/// PostgreSQL's [`crate::PG_LOCK_TIMEOUT`]).
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(60);

/// Page cache of a connection, KiB (negative `cache_size` in SQLite's terms).
const CACHE_KIB: i64 = 64 * 1024;

/// Prepared statements kept per connection (least recently used dropped first): more than
/// the store's distinct cached statements (26), so a use case that cycles through more than
/// rusqlite's default of 16 (a scoring's metadata write, a flight's record) does not parse
/// its SQL again each time.
const STATEMENT_CACHE: usize = 64;

/// Converts SQLite's errors into [`StoreError::Backend`], so that no rusqlite type appears in
/// the public interface (not even as a `From` impl).
pub(crate) trait Db<T> {
    /// The result with the engine's error as text.
    fn db(self) -> Result<T>;
}

impl<T> Db<T> for rusqlite::Result<T> {
    fn db(self) -> Result<T> {
        self.map_err(|e| StoreError::Backend(e.to_string()))
    }
}

/// A [`Store`] in an SQLite database (a file, or memory for tests).
///
/// The connection runs with `journal_mode=WAL` (files only), `synchronous=NORMAL`,
/// `foreign_keys=ON`, a 64 MiB page cache and a 60 s busy timeout ([`BUSY_TIMEOUT`]). Temporary files (statement
/// journals beyond 64 KiB) stay on disk (`temp_store` is left at its default): an in-memory
/// statement journal is truncated by walking it from the start, which is quadratic when a
/// savepoint holds many pages. Opening migrates the schema
/// to the latest version; a database written by a newer gleaner is refused with
/// [`StoreError::SchemaTooNew`], a database of another application with
/// [`StoreError::NotAGleanerDatabase`].
///
/// [`Store::write`] starts an `IMMEDIATE` transaction: it takes the write lock up front, so a
/// second writer (another process on the same file) waits for the first, up to the busy
/// timeout, instead of failing with "database is locked" half-way through its use case. Before
/// it, a write takes the project's exclusion ([`Store::lock_project`]: a lock on the file
/// `<database>-lock`), so it also waits for a use case of another connection that holds the
/// exclusion between its reads and its write (a plan).
#[derive(Debug)]
pub struct SqliteStore {
    conn: Connection,
    /// The number of stored readings as `(PRAGMA data_version, count)`: valid while the
    /// version is unchanged (no other connection has committed since) — this connection's
    /// own commits set it from their transaction's count. `COUNT(*)` scans the whole table,
    /// and use cases check the count at every scoring and write.
    count: Cell<Option<(i64, u64)>>,
    /// How long a writer waits for another connection's write lock ([`BUSY_TIMEOUT`]).
    busy_timeout: Duration,
    /// The project's exclusion ([`Store::lock_project`]) while held: the locked
    /// `<database>-lock` file (none for a database in memory) and the number of holds.
    exclusion: RefCell<Option<(Option<std::fs::File>, u32)>>,
}

/// The error of a writer that waited `timeout` for another connection's write lock on `path`.
pub(crate) fn busy_error(path: &str, timeout: Duration) -> StoreError {
    StoreError::Backend(format!(
        "another gleaner process has been writing to {path} for more than {} s; try again when \
         it has finished",
        timeout.as_secs_f64()
    ))
}

/// Brings `conn` to the latest schema, or fails with [`StoreError::SchemaTooNew`] if the
/// database is newer than this build ([`schema::MIGRATIONS`]). Returns the version found before migrating.
fn migrate(conn: &mut Connection) -> Result<i64> {
    migrate_with(conn, schema::MIGRATIONS)
}

/// [`migrate`] with an explicit list (tests use longer lists).
///
/// Each step runs in an IMMEDIATE transaction that re-reads the version first, so two
/// processes opening the same new database at once apply every step exactly once.
pub(crate) fn migrate_with(conn: &mut Connection, migrations: &[Migration]) -> Result<i64> {
    conn.execute_batch(
        "CREATE TABLE IF NOT EXISTS schema_migrations (
             version     INTEGER PRIMARY KEY,
             applied_at  INTEGER NOT NULL,
             description TEXT    NOT NULL
         );",
    )
    .db()?;
    let supported = migrations.len() as i64;
    let found = current_version(conn)?;
    if found == supported {
        // Up to date: no write transaction, so opening a project never waits for (or fails
        // on) another process's write.
        return Ok(found);
    }
    let path = conn.path().unwrap_or(":memory:").to_string();
    loop {
        let tx = conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(|e| {
                if e.sqlite_error_code() == Some(rusqlite::ErrorCode::DatabaseBusy) {
                    busy_error(&path, BUSY_TIMEOUT)
                } else {
                    StoreError::Backend(e.to_string())
                }
            })?;
        let version = current_version(&tx)?;
        if version > supported {
            return Err(StoreError::SchemaTooNew {
                found: version,
                supported,
            });
        }
        let Some(m) = usize::try_from(version)
            .ok()
            .and_then(|k| migrations.get(k))
        else {
            break;
        };
        let next = version + 1;
        tx.execute_batch(m.sql).db()?;
        tx.execute(
            "INSERT INTO schema_migrations (version, applied_at, description)
             VALUES (?1, CAST(strftime('%s', 'now') AS INTEGER), ?2)",
            rusqlite::params![next, m.description],
        )
        .db()?;
        tx.pragma_update(None, "user_version", next).db()?;
        tx.commit().db()?;
    }
    Ok(found)
}

/// The schema version recorded in `conn`: the later of `schema_migrations` and
/// `PRAGMA user_version`.
fn current_version(conn: &Connection) -> Result<i64> {
    let recorded: i64 = conn
        .query_row("SELECT MAX(version) FROM schema_migrations", [], |r| {
            r.get::<_, Option<i64>>(0)
        })
        .optional()
        .db()?
        .flatten()
        .unwrap_or(0);
    let user_version: i64 = conn
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .db()?;
    Ok(recorded.max(user_version))
}

/// An open write transaction of a [`SqliteStore`] (see [`Store::write`]).
///
/// Reads see the transaction's own writes. A write method that returns an error the store
/// detected itself (invalid values, unknown names, conflicts under [`ConflictPolicy::Fail`],
/// [`StoreError::UnitMismatch`], [`StoreError::AlreadyFlown`], ...) has written nothing, and the
/// transaction's earlier writes stay: the closure may handle the error and go on. A
/// [`StoreError::Backend`] error (I/O, disk full) may leave the transaction partly written, or
/// rolled back by SQLite itself: return it from the closure, which discards the whole use case.
#[derive(Debug)]
pub struct SqliteTx<'a> {
    tx: Transaction<'a>,
    /// The number of readings the transaction sees, when known (the store's valid count at
    /// its start plus what its inserts added).
    count: Cell<Option<u64>>,
}

impl SqliteStore {
    /// Opens (creating if needed) the database file at `path` and migrates it.
    pub fn open(path: &Path) -> Result<Self> {
        let wrap = |e: rusqlite::Error| StoreError::Open {
            path: path.display().to_string(),
            reason: e.to_string(),
        };
        let conn = Connection::open(path).map_err(wrap)?;
        // The first statement is where SQLite notices a file that is not a database.
        conn.query_row("SELECT COUNT(*) FROM sqlite_master", [], |r| {
            r.get::<_, i64>(0)
        })
        .map_err(wrap)?;
        Self::setup(conn)
    }

    /// A fresh database in memory (for tests and dry runs).
    pub fn open_in_memory() -> Result<Self> {
        Self::setup(Connection::open_in_memory().db()?)
    }

    /// An independent copy of this database in memory (SQLite's online backup of every page),
    /// e.g. to start several simulated runs from one prepared project instead of preparing
    /// each. Later writes to either store do not show in the other.
    pub fn copy_in_memory(&self) -> Result<Self> {
        let mut conn = Connection::open_in_memory().db()?;
        rusqlite::backup::Backup::new(&self.conn, &mut conn)
            .db()?
            .run_to_completion(i32::MAX, Duration::ZERO, None)
            .db()?;
        Self::setup(conn)
    }

    fn setup(mut conn: Connection) -> Result<Self> {
        conn.busy_timeout(BUSY_TIMEOUT).db()?;
        conn.set_prepared_statement_cache_capacity(STATEMENT_CACHE);
        let foreign: Vec<String> = conn
            .prepare(
                "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'
                 AND NOT EXISTS (SELECT 1 FROM sqlite_master WHERE name = 'schema_migrations')
                 ORDER BY name LIMIT 5",
            )
            .db()?
            .query_map([], |r| r.get(0))
            .db()?
            .collect::<rusqlite::Result<_>>()
            .db()?;
        if !foreign.is_empty() {
            return Err(StoreError::NotAGleanerDatabase {
                path: conn.path().unwrap_or(":memory:").to_string(),
                tables: foreign,
            });
        }
        // journal_mode answers with the mode in force ("memory" for in-memory databases).
        let _mode: String = conn
            .query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))
            .db()?;
        conn.execute_batch(&format!(
            "PRAGMA synchronous = NORMAL;
             PRAGMA foreign_keys = ON;
             PRAGMA cache_size = -{CACHE_KIB};"
        ))
        .db()?;
        migrate(&mut conn)?;
        Ok(Self {
            conn,
            count: Cell::new(None),
            busy_timeout: BUSY_TIMEOUT,
            exclusion: RefCell::new(None),
        })
    }

    /// Sets how long a writer waits for another connection's write lock before failing with
    /// "another gleaner process has been writing to ..." [default: [`BUSY_TIMEOUT`]].
    pub fn set_busy_timeout(&mut self, timeout: Duration) -> Result<()> {
        self.conn.busy_timeout(timeout).db()?;
        self.busy_timeout = timeout;
        Ok(())
    }

    /// SQLite's own checks of the file: `PRAGMA integrity_check` (b-trees, indexes, pages)
    /// and `PRAGMA foreign_key_check` (every declared reference). Returns the problems found
    /// (empty: consistent). For the crash-safety harness and `gleaner check`.
    pub fn integrity_check(&self) -> Result<Vec<String>> {
        let mut problems: Vec<String> = self
            .conn
            .prepare("PRAGMA integrity_check")
            .db()?
            .query_map([], |r| r.get::<_, String>(0))
            .db()?
            .collect::<rusqlite::Result<Vec<_>>>()
            .db()?
            .into_iter()
            .filter(|m| m != "ok")
            .collect();
        let dangling: Vec<String> = self
            .conn
            .prepare("PRAGMA foreign_key_check")
            .db()?
            .query_map([], |r| {
                Ok(format!(
                    "{} row {} references a missing {} row",
                    r.get::<_, String>(0)?,
                    r.get::<_, Option<i64>>(1)?.unwrap_or(-1),
                    r.get::<_, String>(2)?
                ))
            })
            .db()?
            .collect::<rusqlite::Result<_>>()
            .db()?;
        problems.extend(dangling);
        for (what, sql) in [
            (
                "readings of unknown sensors",
                "SELECT COUNT(*) FROM readings r WHERE NOT EXISTS (SELECT 1 FROM sensors s WHERE s.id = r.sensor)",
            ),
            (
                "readings of unknown modalities",
                "SELECT COUNT(*) FROM readings r WHERE NOT EXISTS (SELECT 1 FROM modalities m WHERE m.id = r.modality)",
            ),
        ] {
            let n: i64 = self.conn.query_row(sql, [], |r| r.get(0)).db()?;
            if n != 0 {
                problems.push(format!("{n} {what}"));
            }
        }
        Ok(problems)
    }

    /// The connection, for SQLite-specific tests.
    #[cfg(test)]
    pub(crate) fn raw(&self) -> &Connection {
        &self.conn
    }

    /// Runs the query `f` in one read snapshot (a deferred transaction), so that a query made
    /// of several statements sees one state of the database even while another process writes.
    fn read<T>(&self, f: impl FnOnce(&Connection) -> Result<T>) -> Result<T> {
        let snapshot = self.conn.unchecked_transaction().db()?;
        let out = f(&snapshot)?;
        snapshot.commit().db()?;
        Ok(out)
    }
}

impl SqliteTx<'_> {
    /// Runs the query `f` inside the transaction.
    fn read<T>(&self, f: impl FnOnce(&Connection) -> Result<T>) -> Result<T> {
        f(&self.tx)
    }

    /// Runs the writes `f` in a savepoint: all of them or, on error, none.
    fn atomically<T>(&mut self, f: impl FnOnce(&Connection) -> Result<T>) -> Result<T> {
        crate::failpoint::step();
        let sp = self.tx.savepoint().db()?;
        let out = f(&sp)?;
        sp.commit().db()?;
        Ok(out)
    }
}

/// `PRAGMA data_version`: changes when another connection commits to the database.
fn data_version(c: &Connection) -> Result<i64> {
    c.prepare_cached("PRAGMA data_version")
        .db()?
        .query_row([], |r| r.get(0))
        .db()
}

impl StoreRead for SqliteStore {
    store_read_methods!();
    fn reading_count(&self) -> Result<u64> {
        self.read(|c| {
            let version = data_version(c)?;
            if let Some((v, n)) = self.count.get()
                && v == version
            {
                return Ok(n);
            }
            let n = read::reading_count(c)?;
            self.count.set(Some((version, n)));
            Ok(n)
        })
    }
}

impl StoreRead for SqliteTx<'_> {
    store_read_methods!();
    fn reading_count(&self) -> Result<u64> {
        if let Some(n) = self.count.get() {
            return Ok(n);
        }
        let n = read::reading_count(&self.tx)?;
        self.count.set(Some(n));
        Ok(n)
    }
}

impl StoreWrite for SqliteTx<'_> {
    for_each_store_write!(store_write_methods);

    fn insert_readings(
        &mut self,
        batch: &ReadingBatch,
        policy: ConflictPolicy,
    ) -> Result<InsertStats> {
        // No savepoint: the insert refuses a batch before its first write (see the module doc).
        let before = self.count.take();
        let stats = write::insert_readings(&self.tx, batch, policy)?;
        self.count.set(before.map(|n| n + stats.inserted));
        Ok(stats)
    }
}

impl Store for SqliteStore {
    type Tx<'a>
        = SqliteTx<'a>
    where
        Self: 'a;

    fn write<R, E>(&mut self, f: impl FnOnce(&mut SqliteTx<'_>) -> Result<R, E>) -> Result<R, E>
    where
        E: From<StoreError>,
    {
        let path = self.conn.path().unwrap_or(":memory:").to_string();
        // The project's exclusion first, as PostgreSQL's writers take its advisory lock: a
        // writer waits for a holder of `lock_project` on another connection (a plan in
        // another process), not only for another write transaction.
        hold(&self.exclusion, self.conn.path(), self.busy_timeout)?;
        let _held = Held(&self.exclusion);
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(|e| {
                if e.sqlite_error_code() == Some(rusqlite::ErrorCode::DatabaseBusy) {
                    busy_error(&path, self.busy_timeout)
                } else {
                    StoreError::Backend(e.to_string())
                }
            })?;
        // The write lock is held: no other connection commits until this one ends.
        let version = data_version(&tx)?;
        let count = self
            .count
            .get()
            .filter(|(v, _)| *v == version)
            .map(|(_, n)| n);
        let mut tx = SqliteTx {
            tx,
            count: Cell::new(count),
        };
        // On an error (or a panic) `tx` is dropped unfinished, which rolls it back.
        let out = f(&mut tx)?;
        crate::failpoint::step();
        let SqliteTx { tx, count } = tx;
        let count = count.get();
        // Until the commit is known to have succeeded the kept count may be wrong.
        self.count.set(None);
        tx.commit().db()?;
        crate::failpoint::committed();
        // This connection's own commit leaves its data_version as it was at the start.
        self.count.set(count.map(|n| (version, n)));
        Ok(out)
    }

    fn lock_project(&self) -> Result<()> {
        hold(&self.exclusion, self.conn.path(), self.busy_timeout)
    }

    fn unlock_project(&self) {
        release(&self.exclusion);
    }
}

type Exclusion = RefCell<Option<(Option<std::fs::File>, u32)>>;

/// One more hold of the exclusion of the database at `db` (none or empty: in memory).
fn hold(exclusion: &Exclusion, db: Option<&str>, timeout: Duration) -> Result<()> {
    let mut held = exclusion.borrow_mut();
    if let Some((_, n)) = held.as_mut() {
        *n += 1;
        return Ok(());
    }
    let file = match db.filter(|p| !p.is_empty()) {
        None => None,
        Some(db) => Some(lock_file(db, timeout)?),
    };
    *held = Some((file, 1));
    Ok(())
}

/// One hold less; the last closes the file, which releases its lock.
fn release(exclusion: &Exclusion) {
    let mut held = exclusion.borrow_mut();
    if let Some((_, n)) = held.as_mut() {
        *n -= 1;
        if *n == 0 {
            *held = None;
        }
    }
}

/// Gives back a hold taken by a write transaction, however it ends.
struct Held<'a>(&'a Exclusion);

impl Drop for Held<'_> {
    fn drop(&mut self) {
        release(self.0);
    }
}

/// Opens `<db>-lock` and takes its exclusive lock, waiting up to `timeout` for another
/// process (or connection) that holds it.
fn lock_file(db: &str, timeout: Duration) -> Result<std::fs::File> {
    let path = format!("{db}-lock");
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|e| StoreError::Backend(format!("{path}: cannot open the lock file: {e}")))?;
    let start = std::time::Instant::now();
    let mut pause = Duration::from_millis(1);
    loop {
        match file.try_lock() {
            Ok(()) => return Ok(file),
            Err(std::fs::TryLockError::WouldBlock) if start.elapsed() < timeout => {
                // A lock wait, not a test's synchronisation: the holder's use case may take
                // seconds (a plan), so the polling backs off to 50 ms.
                std::thread::sleep(pause);
                pause = (pause * 2).min(Duration::from_millis(50));
            }
            Err(std::fs::TryLockError::WouldBlock) => return Err(busy_error(db, timeout)),
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(StoreError::Backend(format!("{path}: cannot lock: {e}")));
            }
        }
    }
}
