//! The rolling-window data sets on the real CAF daily files.

use std::path::PathBuf;

use gleaner_eval::peer::{self, WINDOW_TEST_DAYS};

fn data_dir() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        })
}

#[test]
fn caf_windows_tile_2013_and_stop_at_the_end_of_the_data_in_2016() {
    let (m, layouts, peer_results, w2013) = peer::load_windows(&data_dir(), 2013).unwrap();
    assert_eq!(layouts.len(), 6);
    assert_eq!(m.labels.len(), 32);
    assert!(!peer_results.is_empty());
    // 2013: 17 windows of 21 days, each after a year of training, in order, not overlapping.
    assert_eq!(w2013.len(), 17);
    for pair in w2013.windows(2) {
        assert!(pair[0].test.end <= pair[1].test.start);
    }
    let day = 86_400;
    for p in &w2013 {
        let span = m.times[p.test.end - 1] - m.times[p.test.start];
        assert!(span < WINDOW_TEST_DAYS * day, "{span}");
        assert!(p.test.len() >= 10 && p.train.len() >= 40);
        assert_eq!(p.train.end, p.test.start);
        assert!(m.times[p.test.start] - m.times[p.train.start] <= 365 * day);
    }
    // 2016: the data end on 16 June (day 167 of the leap year): 8 whole windows, the last
    // from 27 May to 16 June.
    let (m16, _, _, w2016) = peer::load_windows(&data_dir(), 2016).unwrap();
    assert_eq!(w2016.len(), 8);
    let last = w2016.last().unwrap();
    assert_eq!(m16.times[last.test.start], 1_464_307_200); // 2016-05-27
    assert_eq!(m16.times[last.test.end - 1], 1_466_035_200); // 2016-06-16
    // No CAF data in 2030: a clear error, no panic.
    let e = peer::load_windows(&data_dir(), 2030)
        .unwrap_err()
        .to_string();
    assert!(e.contains("2030"), "{e}");
}
