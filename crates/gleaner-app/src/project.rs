//! A project: its settings (`gleaner.toml`), its store, and the field built from them.

use std::path::{Path, PathBuf};

use gleaner_field::{Field, Sensor};
use gleaner_store::{SqliteStore, Store};

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

impl Project<SqliteStore> {
    /// Opens the project in `dir`: reads `gleaner.toml` and opens its SQLite database.
    pub fn open(dir: &Path) -> Result<Self> {
        let settings = Settings::load(dir)?;
        let db = dir.join(&settings.project.database);
        if !db.exists() {
            return Err(AppError::Io {
                path: db.display().to_string(),
                message: "database missing (run `gleaner init`)".into(),
            });
        }
        let store = SqliteStore::open(&db)?;
        Ok(Self::new(dir, settings, store))
    }
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

    /// The store, for a use case's writes.
    pub(crate) fn store_mut(&mut self) -> &mut S {
        &mut self.store
    }

    /// The sensors, sorted by id, as core values.
    pub fn sensors(&self) -> Result<Vec<Sensor>> {
        sensors_of(&self.store)
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
