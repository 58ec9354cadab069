//! A bounded run of the fuzzer on every target (a fixed number of executions, so the outcome
//! does not depend on the machine's speed): no reader may panic on any of them. The long runs
//! are `gleaner-fuzz` (see `BENCHMARKS.md`).

use std::path::Path;
use std::time::Duration;

use gleaner_benches::fuzz::{FuzzConfig, Target, fuzz, seeds};

#[test]
fn no_reader_panics_on_mutated_or_arbitrary_bytes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let crashes = tempfile::tempdir().expect("temp dir");
    for target in Target::ALL {
        // The corpus must be there: an empty seed pool would test almost nothing.
        assert!(
            seeds(target, &root).len() >= 10,
            "{}: corpus not found",
            target.name()
        );
        let config = FuzzConfig {
            target,
            seed: 7,
            duration: Duration::from_secs(3_600),
            max_execs: 250,
            root: root.clone(),
            crashes: crashes.path().to_path_buf(),
            max_len: 16_384,
            scratch: None,
        };
        let report = fuzz(&config, |_| {}).expect("fuzz");
        assert_eq!(report.execs, 250);
        assert_eq!(report.panics, 0, "{}: {:?}", target.name(), report.crashes);
        assert!(report.refused > 0, "{}: nothing refused", target.name());
    }
}
