//! Test support: a project made from a synthetic farm's files (unit tests only).

use std::path::PathBuf;

use gleaner_store::AnyStore;
use gleaner_synth::{SynthConfig, SynthFarm, generate, write_readings_csv, write_sensors_csv};

use crate::init::{InitRequest, init};
use gleaner_scoring::Project;

/// A synthetic farm written to a temporary directory and a new project on its sensors (no
/// readings ingested yet).
pub(crate) struct SynthProject {
    /// Holds the files; dropped last.
    pub tmp: tempfile::TempDir,
    pub farm: SynthFarm,
    pub project: Project<AnyStore>,
    /// The farm's readings file.
    pub readings: PathBuf,
}

/// The farm of `config`, its sensors and readings files, and a project initialised on them.
pub(crate) fn synth_project(config: &SynthConfig) -> SynthProject {
    let farm = generate(config).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let sensors = tmp.path().join("sensors.csv");
    write_sensors_csv(&farm, &mut std::fs::File::create(&sensors).unwrap()).unwrap();
    let readings = tmp.path().join("readings.csv");
    write_readings_csv(&farm, &mut std::fs::File::create(&readings).unwrap()).unwrap();
    let (project, _) = init(&InitRequest {
        dir: tmp.path().join("farm"),
        sensors,
        base: Some(farm.base()),
        ..Default::default()
    })
    .unwrap();
    SynthProject {
        tmp,
        farm,
        project,
        readings,
    }
}

/// [`synth_project`] with every reading ingested.
pub(crate) fn ingested_synth_project(config: &SynthConfig) -> SynthProject {
    let mut p = synth_project(config);
    crate::ingest::ingest(
        &mut p.project,
        &crate::ingest::IngestRequest {
            files: vec![p.readings.clone()],
            ..Default::default()
        },
        gleaner_field::UnixSeconds::MAX / 4,
        &crate::Silent,
    )
    .unwrap();
    p
}
