//! A project: its settings (`gleaner.toml`), its store, and the field built from them.

use std::path::{Path, PathBuf};

use gleaner_field::{Field, Sensor};
use gleaner_store::{AnyStore, Database, Store};

use crate::error::{AppError, Result};
use crate::settings::Settings;

/// An open project over any [`Store`].
///
/// Every use case is a method-like function taking the project (see the crate docs); none of
/// them prints, reads the clock or knows the backend.
pub struct Project<S> {
    dir: PathBuf,
    settings: Settings,
    store: S,
}

impl Project<AnyStore> {
    /// Opens the project in `dir`: reads `gleaner.toml` and opens the database its
    /// `database` setting names (an SQLite file, or a PostgreSQL project; see [`database`]).
    pub fn open(dir: &Path) -> Result<Self> {
        Self::open_with(dir, None)
    }

    /// [`Project::open`] with the database given explicitly (the CLI's `--database`) instead
    /// of the `database` setting, when `database` is `Some`.
    pub fn open_with(dir: &Path, database: Option<&str>) -> Result<Self> {
        let settings = Settings::load(dir)?;
        let db = self::database(dir, &settings, database)?;
        if !db.exists()? {
            return Err(AppError::Io {
                path: db.to_string(),
                message: "database missing (run `gleaner init`, or `gleaner migrate` to copy \
                          a project there)"
                    .into(),
            });
        }
        let store = db.open()?;
        Ok(Self::new(dir, settings, store))
    }
}

/// Where the project in `dir` keeps its data: `database` when given, else the `database`
/// setting. A path is an SQLite file relative to `dir`; a `postgres://` (or
/// `postgresql://`) URL a PostgreSQL database, the project's schema named after `#` or, by
/// default, after the project's name (`gleaner_store::schema_for_name`).
pub fn database(dir: &Path, settings: &Settings, database: Option<&str>) -> Result<Database> {
    let setting = settings.project.database.to_string_lossy();
    let chosen = database.unwrap_or(&setting);
    Ok(Database::parse(chosen, dir, &settings.project.name)?)
}

impl<S: Store> Project<S> {
    /// A project from its parts: the directory its relative paths are resolved against, its
    /// settings and its store.
    pub fn new(dir: &Path, settings: Settings, store: S) -> Self {
        Self {
            dir: dir.to_path_buf(),
            settings,
            store,
        }
    }

    /// The project directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The store, for queries.
    pub fn store(&self) -> &S {
        &self.store
    }

    /// The directory, the settings and the store.
    pub fn into_parts(self) -> (PathBuf, Settings, S) {
        (self.dir, self.settings, self.store)
    }

    /// The store, for a use case's writes.
    pub fn store_mut(&mut self) -> &mut S {
        &mut self.store
    }

    /// Runs `f` holding the project's exclusion ([`Store::lock_project`]: PostgreSQL's
    /// session advisory lock of the project, or the SQLite file's lock file), so a use case
    /// that reads, computes and then writes — a plan's scoring, search and store, a
    /// recorded flight's checks and writes — runs whole before or after every other holder
    /// and writer of the project, in this process or another: a second server replica over
    /// the same PostgreSQL database, a CLI command. Re-entrant. Waits up to the store's lock
    /// timeout. If `f` panics the hold is given back when the store is dropped (the
    /// connection or the lock file closes).
    pub fn exclusive<T>(&mut self, f: impl FnOnce(&mut Self) -> Result<T>) -> Result<T> {
        self.store.lock_project()?;
        let out = f(self);
        self.store.unlock_project();
        out
    }

    /// The sensors, sorted by id, as core values.
    pub fn sensors(&self) -> Result<Vec<Sensor>> {
        sensors_of(&self.store)
    }

    /// Refuses a write when `field` (the grid the settings describe) is not the grid the store
    /// holds — `[field] cell_size_m` or the base edited in `gleaner.toml` after `init` — with
    /// the command that re-grids the project.
    pub fn check_stored_grid(&self, field: &Field) -> Result<()> {
        let stored: std::collections::BTreeSet<gleaner_field::CellIndex> =
            self.store.cells()?.into_iter().map(|c| c.index).collect();
        let missing = field
            .cells()
            .iter()
            .map(|c| c.index)
            .find(|i| !stored.contains(i));
        if missing.is_none() && stored.len() == field.cells().len() {
            return Ok(());
        }
        let f = &self.settings.field;
        Err(AppError::Invalid(format!(
            "{}: the grid of [field] (cell_size_m = {} m, base {}, {}) has {} cells{}, but the \
             project's stored grid has {}: the settings changed after `gleaner init`. Re-grid \
             with `gleaner init --dir {} --sensors {} --cell-size {} --force` (gleaner.toml is \
             rewritten from init's options; the readings are kept), or restore the setting; \
             nothing was written",
            self.dir.join(crate::settings::CONFIG_FILE).display(),
            gleaner_ingest::number(f.cell_size_m),
            gleaner_ingest::number(f.base_lat),
            gleaner_ingest::number(f.base_lon),
            field.cells().len(),
            missing.map_or(String::new(), |i| format!(" ({i} is not stored)")),
            stored.len(),
            self.dir.display(),
            self.dir.join(&self.settings.sensors.file).display(),
            gleaner_ingest::number(f.cell_size_m),
        )))
    }

    /// The field (grid and neighbours) built from the stored sensors and the settings.
    pub fn field(&self) -> Result<(Vec<Sensor>, Field)> {
        let sensors = self.sensors()?;
        if sensors.is_empty() {
            return Err(AppError::Invalid(
                "the project has no sensors (run `gleaner init`)".into(),
            ));
        }
        let field = Field::build(
            &sensors,
            self.settings.base()?,
            &self.settings.field_config(),
        )
        .map_err(|e| AppError::core("cell grid", e))?;
        Ok((sensors, field))
    }
}

/// A store's sensors, sorted by id, as core values.
pub(crate) fn sensors_of<R: gleaner_store::StoreRead>(store: &R) -> Result<Vec<Sensor>> {
    Ok(store
        .sensors()?
        .into_iter()
        .map(|r| Sensor {
            id: r.id,
            position: r.position,
            elevation_m: r.elevation_m,
        })
        .collect())
}
