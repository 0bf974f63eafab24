//! Simulator speed: one 30 s recording at 1 kHz (20 kHz internal rate),
//! good and sticking bearings. The issue asks for well under 100 ms.
//! There is no SciPy counterpart: the simulator has no reference
//! implementation to time against.

use ballpass::sim::{simulate, Condition, SimSettings};
use criterion::{criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("simulate_30s_1kHz");
    g.sample_size(20);
    for condition in [Condition::Good, Condition::Sticking] {
        let s = SimSettings {
            condition,
            ..Default::default()
        };
        g.bench_function(condition.name(), |b| {
            b.iter(|| simulate(std::hint::black_box(&s)).unwrap())
        });
    }
    g.finish();
}

/// The benchmark group (written out: `criterion_group!` makes an undocumented fn).
fn benches() {
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c);
}

criterion_main!(benches);
