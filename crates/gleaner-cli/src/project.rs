//! A gleaner project on disk: a directory with `gleaner.toml` and the SQLite database.

use std::path::Path;

use anyhow::{Context, Result, bail};
use gleaner_field::{Field, Sensor};
use gleaner_store::{SqliteStore, Store};

use crate::config::ProjectFile;

/// An open project.
pub struct Project {
    /// Its configuration.
    pub config: ProjectFile,
    /// Its database.
    pub store: SqliteStore,
}

impl Project {
    /// Opens the project in `dir`.
    pub fn open(dir: &Path) -> Result<Self> {
        let config = ProjectFile::load(dir)?;
        let db = dir.join(&config.project.database);
        if !db.exists() {
            bail!("{}: database missing (run `gleaner init`)", db.display());
        }
        let store = SqliteStore::open(&db)
            .with_context(|| format!("{}: cannot open database", db.display()))?;
        Ok(Self { config, store })
    }

    /// The sensors, sorted by id, as core values.
    pub fn sensors(&self) -> Result<Vec<Sensor>> {
        Ok(self
            .store
            .sensors()?
            .into_iter()
            .map(|r| Sensor {
                id: r.id,
                position: r.position,
                elevation_m: r.elevation_m,
            })
            .collect())
    }

    /// The field (grid and neighbours) built from the stored sensors and the configuration.
    pub fn field(&self) -> Result<(Vec<Sensor>, Field)> {
        let sensors = self.sensors()?;
        let field = Field::build(&sensors, self.config.base()?, &self.config.field_config())
            .context("cannot build the cell grid")?;
        Ok((sensors, field))
    }
}
