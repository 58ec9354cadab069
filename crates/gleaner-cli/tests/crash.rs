//! The crash-safety harness in the test suite: one kill point (the commit) per use case on both
//! backends (the full sweep is `gleaner crash-test --kill-points 30`, see BENCHMARKS.md). Needs
//! the shared data and a PostgreSQL server (`GLEANER_TEST_PG_URL`; fails without one).

use std::process::Command;

#[test]
fn sigkill_at_write_steps_leaves_whole_use_cases_on_both_backends() {
    let url = std::env::var("GLEANER_TEST_PG_URL")
        .expect("GLEANER_TEST_PG_URL is not set: run scripts/test.sh (it starts a server)");
    let data = std::env::var("GLEANER_DATA_DIR")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data").into());
    let work = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_gleaner"))
        .args(["crash-test", "--kill-points", "1", "--backend", "both"])
        .arg("--postgres")
        .arg(&url)
        .arg("--data")
        .arg(&data)
        .arg("--work")
        .arg(work.path())
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{report}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // 1 kill point (just before the commit, everything written) x 4 use cases (first ingest,
    // ingest, plan, record) x 2 backends.
    assert!(report.contains("total: 8 kill points"), "{report}");
    assert!(report.contains(" 0 failures"), "{report}");
}
