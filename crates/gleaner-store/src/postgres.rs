//! [`PgStore`]: the [`Store`] on PostgreSQL, one schema per project, and its write
//! transaction [`PgTx`].
//!
//! - **Isolation of projects**: a project is a schema (namespace) of the database, named by
//!   the caller ([`PgStore::open`]); the connection's `search_path` is that schema only, so
//!   every statement names its tables unqualified and can reach no other project. Many
//!   projects (farms) share one database; `pg_dump --schema` backs one up.
//! - **Writers**: [`Store::write`] opens a `READ COMMITTED` transaction and first takes the
//!   project's transaction-scoped advisory lock (`pg_advisory_xact_lock`), so the writers of
//!   one project are serialised exactly like SQLite's `IMMEDIATE` transactions: a second
//!   writer waits (up to [`LOCK_TIMEOUT`]) and then sees everything the first committed.
//!   Readers never wait: each [`StoreRead`] call of the store runs in its own `REPEATABLE
//!   READ` read-only snapshot. Because the lock is taken before the transaction's first read,
//!   no two writers of a project ever overlap, so no serialization failure can arise and no
//!   retry loop is needed (a closure is never run twice); a writer that waited longer than
//!   [`LOCK_TIMEOUT`] fails with a message naming the project.
//! - **Methods**: every write method runs in a savepoint of the transaction (PostgreSQL
//!   aborts a whole transaction on a failed statement), after the same argument checks as
//!   SQLite's (`crate::checks`), so both backends refuse the same inputs the same way.
//! - **Bulk ingest**: new readings go in with one binary `COPY readings FROM STDIN`. A large
//!   insert into an empty `readings` table drops its primary key for the rest of the load and
//!   builds it once, before the next read or the commit (`write::BulkLoad`); the drop is
//!   transactional (a crash or rollback restores the key) but holds an exclusive lock on the
//!   table until commit, so other connections' reads of that project wait for a first load.
//! - **Migrations**: [`schema`], applied under the same advisory lock at open.

mod read;
mod schema;
mod write;

use std::cell::RefCell;
use std::ops::RangeInclusive;
use std::time::Duration;

use gleaner_field::{Modality, SensorId, UnixSeconds};
use postgres::{Client, IsolationLevel, NoTls, Transaction};

use crate::{
    CellMetadata, CellRecord, ConflictPolicy, IngestRecord, InsertStats, MissionId, MissionRecord,
    ModalityRecord, NewMission, ReadingBatch, ReplaceCellsStats, Result, SensorRecord, Store,
    StoreError, StoreRead, StoreWrite, UpsertStats, VisitRecord,
};

/// How long a writer waits for another writer of the same project before failing.
pub const LOCK_TIMEOUT: Duration = Duration::from_secs(60);

/// Converts the client's errors into [`StoreError::Backend`] (no `postgres` type appears in
/// the public interface), with the server's message, detail and SQLSTATE when there is one.
pub(crate) trait Db<T> {
    /// The result with the engine's error as text.
    fn db(self) -> Result<T>;
}

impl<T> Db<T> for std::result::Result<T, postgres::Error> {
    fn db(self) -> Result<T> {
        self.map_err(|e| StoreError::Backend(describe(&e)))
    }
}

/// The server's message of `e` with its SQLSTATE and detail, or the client's text.
fn describe(e: &postgres::Error) -> String {
    match e.as_db_error() {
        Some(d) => {
            let mut s = format!("{} (SQLSTATE {})", d.message(), d.code().code());
            if let Some(detail) = d.detail() {
                s.push_str(": ");
                s.push_str(detail);
            }
            s
        }
        None => e.to_string(),
    }
}

/// Whether `name` can name a project's schema: 1 to 63 bytes of `a-z`, `0-9`, `_`, starting
/// with a letter or `_`, and not starting with `pg_` (reserved by PostgreSQL).
pub fn valid_project_name(name: &str) -> bool {
    let b = name.as_bytes();
    !b.is_empty()
        && b.len() <= 63
        && (b[0].is_ascii_lowercase() || b[0] == b'_')
        && b.iter()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == b'_')
        && !name.starts_with("pg_")
}

/// Splits a database address `postgres://...#project` into the connection URL and the
/// project (schema) named after `#`, if any.
pub fn split_project(address: &str) -> (&str, Option<&str>) {
    match address.rsplit_once('#') {
        Some((url, project)) => (url, Some(project)),
        None => (address, None),
    }
}

/// Whether a database setting names a PostgreSQL server (`postgres://` or `postgresql://`)
/// rather than an SQLite file.
pub fn is_postgres_url(database: &str) -> bool {
    database.starts_with("postgres://") || database.starts_with("postgresql://")
}

/// The connection URL with any password replaced by `***`, for messages.
pub fn redact(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return url.to_string();
    };
    let (authority, tail) = rest.split_at(rest.find(['/', '?']).unwrap_or(rest.len()));
    match authority.rsplit_once('@') {
        Some((userinfo, host)) => match userinfo.split_once(':') {
            Some((user, _)) => format!("{scheme}://{user}:***@{host}{tail}"),
            None => url.to_string(),
        },
        None => url.to_string(),
    }
}

/// A [`Store`] in one schema (the project) of a PostgreSQL database. See the module docs.
pub struct PgStore {
    client: RefCell<Client>,
    project: String,
    lock_key: i64,
}

impl std::fmt::Debug for PgStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PgStore")
            .field("project", &self.project)
            .finish_non_exhaustive()
    }
}

/// An open write transaction of a [`PgStore`] (see [`Store::write`]). Reads see its own
/// writes. A write method that fails has written nothing (its savepoint is rolled back) and
/// the transaction's earlier writes stay.
pub struct PgTx<'a> {
    tx: RefCell<Transaction<'a>>,
    /// The bulk load in progress, if any: `readings` has no primary key until the next
    /// read or the commit builds it again (see `write::BulkLoad`).
    bulk: RefCell<Option<write::BulkLoad>>,
}

impl std::fmt::Debug for PgTx<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PgTx").finish_non_exhaustive()
    }
}

/// A stable 64-bit advisory-lock key of a project (FNV-1a of `gleaner:` and its name).
fn lock_key(project: &str) -> i64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in b"gleaner:".iter().chain(project.as_bytes()) {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h as i64
}

impl PgStore {
    /// Connects to `url` (`postgres://user:password@host:port/database`, or with
    /// `?host=/socket/dir`) and opens the project `project` (its schema, created and migrated
    /// as needed). A schema of that name that holds tables but no gleaner schema history is
    /// refused with [`StoreError::NotAGleanerDatabase`]; one of a newer gleaner with
    /// [`StoreError::SchemaTooNew`].
    pub fn open(url: &str, project: &str) -> Result<Self> {
        let open_err = |reason: String| StoreError::Open {
            path: format!("{}#{project}", redact(url)),
            reason,
        };
        if !valid_project_name(project) {
            return Err(open_err(format!(
                "project name {project:?} cannot name a PostgreSQL schema: use 1-63 characters \
                 a-z, 0-9 and _, starting with a letter or _, not with pg_"
            )));
        }
        let mut client = Client::connect(url, NoTls).map_err(|e| open_err(describe(&e)))?;
        let lock_key = lock_key(project);
        client
            .batch_execute(&format!(
                "SET search_path TO \"{project}\"; SET lock_timeout = '{}s'",
                LOCK_TIMEOUT.as_secs()
            ))
            .map_err(|e| open_err(describe(&e)))?;
        migrate(&mut client, project, lock_key)?;
        Ok(Self {
            client: RefCell::new(client),
            project: project.to_string(),
            lock_key,
        })
    }

    /// The project (schema) name.
    pub fn project(&self) -> &str {
        &self.project
    }

    /// How many sessions are waiting for this project's advisory lock (its exclusion, or a
    /// write transaction's lock) right now: what an operator asks when writes seem stuck,
    /// and how tests see that a writer of another process really waits.
    pub fn lock_waiters(&self) -> Result<i64> {
        // A bigint key shows in pg_locks as classid (high 32 bits), objid (low), objsubid 1.
        let row = self
            .client
            .borrow_mut()
            .query_one(
                "SELECT count(*) FROM pg_locks
                 WHERE locktype = 'advisory' AND NOT granted AND objsubid = 1
                   AND database = (SELECT oid FROM pg_database WHERE datname = current_database())
                   AND classid::bigint = ($1::bigint >> 32) & 4294967295
                   AND objid::bigint = $1::bigint & 4294967295",
                &[&self.lock_key],
            )
            .db()?;
        Ok(row.get(0))
    }

    /// Whether the database at `url` has a project (schema) `project`.
    pub fn project_exists(url: &str, project: &str) -> Result<bool> {
        let mut client = Client::connect(url, NoTls).map_err(|e| StoreError::Open {
            path: format!("{}#{project}", redact(url)),
            reason: describe(&e),
        })?;
        Ok(client
            .query_opt("SELECT 1 FROM pg_namespace WHERE nspname = $1", &[&project])
            .db()?
            .is_some())
    }

    /// Drops the project `project` (its schema with every table) from the database at `url`;
    /// `Ok(false)` when there was none. For tests and for `gleaner migrate`'s clean-up.
    pub fn drop_project(url: &str, project: &str) -> Result<bool> {
        if !valid_project_name(project) {
            return Err(StoreError::Invalid {
                what: "project name",
                detail: format!("{project:?}"),
            });
        }
        let mut client = Client::connect(url, NoTls).db()?;
        let existed = client
            .query_opt("SELECT 1 FROM pg_namespace WHERE nspname = $1", &[&project])
            .db()?
            .is_some();
        client
            .batch_execute(&format!("DROP SCHEMA IF EXISTS \"{project}\" CASCADE"))
            .db()?;
        Ok(existed)
    }

    /// Runs the query `f` in one read-only snapshot (`REPEATABLE READ`).
    fn read<T>(&self, f: impl FnOnce(&mut Transaction<'_>) -> Result<T>) -> Result<T> {
        let mut client = self.client.borrow_mut();
        let mut tx = client
            .build_transaction()
            .isolation_level(IsolationLevel::RepeatableRead)
            .read_only(true)
            .start()
            .db()?;
        let out = f(&mut tx)?;
        tx.commit().db()?;
        Ok(out)
    }

    /// Checks of the stored data that only the server can make: every foreign key and check
    /// constraint of the project's tables validated again from scratch. Returns the problems
    /// found (empty: consistent). For the crash-safety harness.
    pub fn integrity_check(&self) -> Result<Vec<String>> {
        self.read(read::integrity_check)
    }
}

/// Creates the project's schema if needed and applies the missing migrations, each in its
/// own transaction under the project's advisory lock.
///
/// A project already at the latest version is recognised without the lock, so opening never
/// waits for a running writer.
fn migrate(client: &mut Client, project: &str, lock_key: i64) -> Result<()> {
    let current: Option<i64> = client
        .query_one(
            "SELECT CASE WHEN to_regclass('schema_migrations') IS NULL THEN NULL
                    ELSE (SELECT 0::BIGINT) END",
            &[],
        )
        .db()?
        .get(0);
    if current.is_some() {
        let version: i64 = client
            .query_one(
                "SELECT COALESCE(MAX(version), 0)::BIGINT FROM schema_migrations",
                &[],
            )
            .db()?
            .get(0);
        if version == schema::latest_version() {
            return Ok(());
        }
    }
    loop {
        let mut tx = client.transaction().db()?;
        tx.execute("SELECT pg_advisory_xact_lock($1)", &[&lock_key])
            .db()?;
        let exists = tx
            .query_opt("SELECT 1 FROM pg_namespace WHERE nspname = $1", &[&project])
            .db()?
            .is_some();
        if !exists {
            tx.batch_execute(&format!("CREATE SCHEMA \"{project}\""))
                .db()?;
        }
        let tables: Vec<String> = tx
            .query(
                "SELECT tablename FROM pg_tables WHERE schemaname = $1 ORDER BY tablename",
                &[&project],
            )
            .db()?
            .iter()
            .map(|r| r.get(0))
            .collect();
        if !tables.is_empty() && !tables.iter().any(|t| t == "schema_migrations") {
            return Err(StoreError::NotAGleanerDatabase {
                path: format!("schema {project}"),
                tables: tables.into_iter().take(5).collect(),
            });
        }
        tx.batch_execute(
            "CREATE TABLE IF NOT EXISTS schema_migrations (
                 version     BIGINT PRIMARY KEY,
                 applied_at  BIGINT NOT NULL,
                 description TEXT   NOT NULL
             )",
        )
        .db()?;
        let version: i64 = tx
            .query_one(
                "SELECT COALESCE(MAX(version), 0)::BIGINT FROM schema_migrations",
                &[],
            )
            .db()?
            .get(0);
        let supported = schema::latest_version();
        if version > supported {
            return Err(StoreError::SchemaTooNew {
                found: version,
                supported,
            });
        }
        let Some(m) = schema::MIGRATIONS.iter().find(|m| m.version > version) else {
            tx.commit().db()?;
            return Ok(());
        };
        tx.batch_execute(m.sql).db()?;
        tx.execute(
            "INSERT INTO schema_migrations (version, applied_at, description)
             VALUES ($1, EXTRACT(EPOCH FROM now())::BIGINT, $2)",
            &[&m.version, &m.description],
        )
        .db()?;
        tx.commit().db()?;
    }
}

impl PgTx<'_> {
    /// Whether a bulk load has the primary key of `readings` dropped (for tests).
    #[cfg(test)]
    pub(crate) fn bulk_loading(&self) -> bool {
        self.bulk.borrow().is_some()
    }

    /// Runs the query `f` inside the transaction, after building again the primary key a
    /// bulk load dropped (so every read sees an indexed table).
    fn read<T>(&self, f: impl FnOnce(&mut Transaction<'_>) -> Result<T>) -> Result<T> {
        let mut tx = self.tx.borrow_mut();
        write::restore_primary_key(&mut tx, &mut self.bulk.borrow_mut())?;
        f(&mut tx)
    }

    /// Runs the writes `f` in a savepoint: all of them or, on error, none.
    fn atomically<T>(&mut self, f: impl FnOnce(&mut Transaction<'_>) -> Result<T>) -> Result<T> {
        crate::failpoint::step();
        let tx = self.tx.get_mut();
        let mut sp = tx.transaction().db()?;
        let out = f(&mut sp)?;
        sp.commit().db()?;
        Ok(out)
    }
}

impl StoreRead for PgStore {
    store_read_methods!();
    fn reading_count(&self) -> Result<u64> {
        self.read(read::reading_count)
    }
}

impl StoreRead for PgTx<'_> {
    store_read_methods!();
    fn reading_count(&self) -> Result<u64> {
        self.read(read::reading_count)
    }
}

impl StoreWrite for PgTx<'_> {
    for_each_store_write!(store_write_methods);

    fn insert_readings(
        &mut self,
        batch: &ReadingBatch,
        policy: ConflictPolicy,
    ) -> Result<InsertStats> {
        // The bulk-load state changes only if the savepoint commits: a failed insert rolls
        // back its own drop or rebuild of the primary key with everything else.
        let mut bulk = self.bulk.get_mut().clone();
        let stats = self.atomically(|c| write::insert_readings(c, batch, policy, &mut bulk))?;
        *self.bulk.get_mut() = bulk;
        Ok(stats)
    }
}

/// Whether `e` is a lock timeout (SQLSTATE 55P03) from waiting for another writer.
fn is_lock_timeout(e: &postgres::Error) -> bool {
    e.code() == Some(&postgres::error::SqlState::LOCK_NOT_AVAILABLE)
}

impl Store for PgStore {
    type Tx<'a>
        = PgTx<'a>
    where
        Self: 'a;

    fn write<R, E>(&mut self, f: impl FnOnce(&mut PgTx<'_>) -> Result<R, E>) -> Result<R, E>
    where
        E: From<StoreError>,
    {
        let project = self.project.clone();
        let lock_key = self.lock_key;
        let client = self.client.get_mut();
        let mut tx = client.transaction().db()?;
        if let Err(e) = tx.execute("SELECT pg_advisory_xact_lock($1)", &[&lock_key]) {
            return Err(if is_lock_timeout(&e) {
                StoreError::Backend(format!(
                    "another gleaner process has been writing to project {project} for more \
                     than {} s; try again when it has finished",
                    LOCK_TIMEOUT.as_secs()
                ))
            } else {
                StoreError::Backend(describe(&e))
            }
            .into());
        }
        let mut tx = PgTx {
            tx: RefCell::new(tx),
            bulk: RefCell::new(None),
        };
        // On an error (or a panic) `tx` is dropped unfinished, which rolls it back.
        let out = f(&mut tx)?;
        write::restore_primary_key(tx.tx.get_mut(), tx.bulk.get_mut())?;
        crate::failpoint::step();
        tx.tx.into_inner().commit().db()?;
        crate::failpoint::committed();
        Ok(out)
    }

    fn lock_project(&self) -> Result<()> {
        // Outside any transaction: a session-level lock, kept until unlocked or the
        // connection ends. The session's `lock_timeout` bounds the wait.
        let mut client = self.client.borrow_mut();
        match client.execute("SELECT pg_advisory_lock($1)", &[&self.lock_key]) {
            Ok(_) => Ok(()),
            Err(e) if is_lock_timeout(&e) => Err(StoreError::Backend(format!(
                "another gleaner process has been writing to project {} for more than {} s; \
                 try again when it has finished",
                self.project,
                LOCK_TIMEOUT.as_secs()
            ))),
            Err(e) => Err(StoreError::Backend(describe(&e))),
        }
    }

    fn unlock_project(&self) {
        let mut client = self.client.borrow_mut();
        let released = client
            .query_one("SELECT pg_advisory_unlock($1)", &[&self.lock_key])
            .map(|r| r.get::<_, bool>(0));
        if !matches!(released, Ok(true)) {
            // Never leave a hold behind on a connection that stays open: another replica
            // would wait for it until its timeout.
            let _ = client.batch_execute("SELECT pg_advisory_unlock_all()");
        }
    }
}
