use gleaner_synth::generate;

use crate::{all_csv, small};

fn head(text: &str, lines: usize) -> String {
    text.lines().take(lines).collect::<Vec<_>>().join("\n")
}

#[test]
fn first_lines_of_the_csv_files() {
    let farm = generate(&small(1, 3, 30)).unwrap();
    let [sensors, readings, truth, faults] = all_csv(&farm);
    insta::assert_snapshot!("sensors", head(&sensors, 4));
    insta::assert_snapshot!("readings", head(&readings, 9));
    insta::assert_snapshot!("ground_truth", head(&truth, 4));
    insta::assert_snapshot!("faults", head(&faults, 4));
}
