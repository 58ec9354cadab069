use gleaner_synth::generate;

use crate::{all_csv, small};

fn csv_with_threads(threads: usize, seed: u64) -> [String; 4] {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| all_csv(&generate(&small(seed, 120, 90)).unwrap()))
}

#[test]
fn same_seed_gives_identical_bytes_whatever_the_thread_count() {
    let one = csv_with_threads(1, 5);
    let four = csv_with_threads(4, 5);
    assert_eq!(one, four);
    let again = all_csv(&generate(&small(5, 120, 90)).unwrap());
    assert_eq!(one, again);
}

#[test]
fn different_seeds_give_different_farms() {
    let a = all_csv(&generate(&small(1, 30, 30)).unwrap());
    let b = all_csv(&generate(&small(2, 30, 30)).unwrap());
    assert_ne!(a[0], b[0], "sensor positions");
    assert_ne!(a[1], b[1], "readings");
}
