//! PostgreSQL test helpers and the cross-connection exclusion check.

use super::*;

/// The PostgreSQL server the tests use: `GLEANER_TEST_PG_URL` (`scripts/test.sh` starts a
/// throwaway cluster and sets it; `scripts/pg-cluster.sh` does it by hand).
///
/// # Panics
/// When the variable is not set: a PostgreSQL test fails rather than skips without a server.
pub fn pg_test_url() -> String {
    std::env::var("GLEANER_TEST_PG_URL").unwrap_or_else(|_| {
        panic!(
            "GLEANER_TEST_PG_URL is not set: the PostgreSQL tests need a server. Run \
             scripts/test.sh (which starts one), or `d=$(scripts/pg-cluster.sh start) && \
             eval \"$(scripts/pg-cluster.sh env $d)\"` first"
        )
    })
}

/// A project (schema) name no other test uses: `t_<tag>_<pid>_<n>`, for tests that run in
/// parallel against one server. `tag` must be lower-case letters, digits or `_`.
pub fn pg_fresh_project(tag: &str) -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    format!("t_{tag}_{}_{n}", std::process::id())
}

/// The project's exclusion ([`Store::lock_project`]) across two connections to one project
/// (`first` and `second`, e.g. two server replicas): re-entrant for its holder, which may
/// write inside it; the other connection's `lock_project` and its plain writes wait until
/// every hold is given back, then see what the holder wrote. Synchronised by channels and a
/// flag, never by sleeps: `second` can only pass its lock after `first` set the flag just
/// before its last unlock.
///
/// # Panics
/// When the exclusion does not exclude.
pub fn exclusion_holds_across_connections<S: Store + Send + 'static>(
    first: &mut S,
    second: S,
    third: S,
) {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::{Arc, mpsc};
    first.lock_project().unwrap();
    first.lock_project().unwrap();
    first.write(|tx| tx.config_set("holder", "first")).unwrap();
    let released = Arc::new(AtomicBool::new(false));
    let (waiting_tx, waiting_rx) = mpsc::channel::<()>();
    let spawn = |store: S, key: &'static str, lock: bool| {
        let released = Arc::clone(&released);
        let waiting = waiting_tx.clone();
        std::thread::spawn(move || {
            let mut store = store;
            waiting.send(()).unwrap();
            // Once the hold (or the write transaction) is had, the first holder must be gone.
            let locked_after = !lock || {
                store.lock_project().unwrap();
                released.load(Ordering::SeqCst)
            };
            let out = store.write(|tx| {
                let seen = locked_after && released.load(Ordering::SeqCst);
                let holder = tx.config_get("holder")?;
                tx.config_set(key, "done")?;
                Ok::<_, StoreError>((seen, holder))
            });
            if lock {
                store.unlock_project();
            }
            out.unwrap()
        })
    };
    let locker = spawn(second, "second", true);
    let writer = spawn(third, "third", false);
    waiting_rx.recv().unwrap();
    waiting_rx.recv().unwrap();
    // Still held once after this; the holder's own writes go on.
    first.unlock_project();
    first
        .write(|tx| tx.config_set("holder", "first, again"))
        .unwrap();
    released.store(true, Ordering::SeqCst);
    first.unlock_project();
    for (name, t) in [("lock_project", locker), ("a write", writer)] {
        let (seen, holder) = t.join().unwrap();
        assert!(
            seen,
            "{name} of another connection ran while the exclusion was held"
        );
        assert_eq!(holder.as_deref(), Some("first, again"), "{name}");
    }
    assert_eq!(first.config_get("second").unwrap().as_deref(), Some("done"));
    assert_eq!(first.config_get("third").unwrap().as_deref(), Some("done"));
    // Given back: the first takes it again at once.
    first.lock_project().unwrap();
    first.unlock_project();
}
