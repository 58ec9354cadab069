//! The dynamic field model on the CAF hourly data (32 sensors, VW 30 cm, Jan-Apr 2015):
//! fitting on the 1,001 training hours, reconstructing 500 hourly steps of every sensor (one
//! filter pass), and a flight's update (ten sensors' last day of hourly readings brought back,
//! then every sensor's estimate), and the calibrated interval's back-test (the last 500
//! training hours with 10 sensors read, the other 22 estimated at every hour). Needs the shared data directory (GLEANER_DATA_DIR, default
//! ../shared/data from the repository root).
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_eval::peer::{self, Dataset};
use gleaner_kriging::{SensorSeries, backtest_errors, fit_dynamic, interval_multiplier};

fn data_dir() -> PathBuf {
    std::env::var_os("GLEANER_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"))
        })
}

fn bench(c: &mut Criterion) {
    let (matrix, _, _, protocol) =
        peer::load(&data_dir(), Dataset::Hourly2015).expect("the CAF hourly data");
    let n = matrix.labels.len();
    let train = protocol.train.clone();
    let mut times = vec![Vec::new(); n];
    let mut values = vec![Vec::new(); n];
    for t in train.clone() {
        for i in 0..n {
            times[i].push(matrix.times[t]);
            values[i].push(matrix.values[t * n + i]);
        }
    }
    let series: Vec<SensorSeries<'_>> = (0..n)
        .map(|i| SensorSeries {
            position: [0.0, 0.0],
            times: &times[i],
            values: &values[i],
        })
        .collect();
    c.bench_function("dynamic fit, 32 sensors x 1001 hours", |b| {
        b.iter(|| fit_dynamic(&series, &protocol.fit).expect("fit"))
    });
    let model = fit_dynamic(&series, &protocol.fit).expect("fit");
    let test = protocol.test.clone();
    c.bench_function("reconstruct 500 hourly steps x 32 sensors (10 read)", |b| {
        b.iter(|| {
            let mut f = model.filter(matrix.times[test.start] as f64);
            let mut sum = 0.0;
            for t in test.clone() {
                f.advance(matrix.times[t] as f64);
                for i in 0..10 {
                    f.observe(i, matrix.values[t * n + i]);
                }
                for i in 0..n {
                    sum += f.estimate(i).0;
                }
            }
            sum
        })
    });
    c.bench_function(
        "flight update: 10 sensors x 24 hourly readings, then 32 estimates",
        |b| {
            let start = test.start;
            b.iter(|| {
                let mut f = model.filter(matrix.times[start] as f64);
                for t in start..start + 24 {
                    f.advance(matrix.times[t] as f64);
                    for i in 0..10 {
                        f.observe(i, matrix.values[t * n + i]);
                    }
                }
                (0..n).map(|i| f.estimate(i).1).sum::<f64>()
            })
        },
    );
    let half: Vec<SensorSeries<'_>> = series
        .iter()
        .map(|s| SensorSeries {
            times: &s.times[..train.len() / 2],
            values: &s.values[..train.len() / 2],
            ..*s
        })
        .collect();
    let early = fit_dynamic(&half, &protocol.fit).expect("fit on the first half");
    let read: Vec<bool> = (0..n).map(|i| i < 10).collect();
    let t = &matrix.times;
    let split = train.start + train.len() / 2;
    c.bench_function(
        "interval back-test: 500 hours, 10 of 32 sensors read, q from 11,000 errors",
        |b| {
            b.iter(|| {
                let z = backtest_errors(
                    &early,
                    &series,
                    t[train.start],
                    t[split],
                    t[train.end - 1],
                    &read,
                );
                interval_multiplier(&z)
            })
        },
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
