//! Target: a 100 km² field with 10,000 sensors gridded, with neighbours, in <= 100 ms.

use criterion::{Criterion, criterion_group, criterion_main};
use gleaner_benches::{base, random_sensors};
use gleaner_field::{Field, FieldConfig};

fn grid(c: &mut Criterion) {
    let sensors = random_sensors(10_000, 10_000.0, 7);
    let config = FieldConfig::with_cell_size(40.0);
    c.bench_function("field/grid_10k_sensors_100km2", |b| {
        b.iter(|| Field::build(&sensors, base(), &config).expect("valid field"))
    });
}

criterion_group!(benches, grid);
criterion_main!(benches);
