//! Cost of the diagnosis's outlier filter (docs/gap.md, "Outliers"; BENCHMARKS.md): the
//! evidence of one channel gathered with and without it, side by side in one run, on 2^20
//! increments of a VOG4-like gyro at 250 Hz (70 minutes). `cargo bench --bench gap`.

use allanscope::gap::{GapConfig, GapEvidence};
use allanscope::sim::{SimModel, Simulator};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::path::Path;

const VOG4: &str = "tau0_s = 0.004\n[[channel]]\nname = \"g4\"\nunit = \"arcsec\"\nlsb = 0.004\n\
    N = 0.254\nB = 0.225\nK = 1.826e-2\n";

fn evidence(c: &mut Criterion) {
    let m = SimModel::from_toml_str(VOG4, Path::new("vog4")).expect("model");
    let mut sim = Simulator::new(&m, 1);
    let mut inc = vec![0.0; 1 << 20];
    sim.fill_channel(0, &mut inc);
    let mut g = c.benchmark_group("gap_evidence_2^20");
    g.sample_size(10);
    for filter in [true, false] {
        let name = if filter {
            "with_outlier_filter"
        } else {
            "without"
        };
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut cfg = GapConfig::new(0.004);
                cfg.expected_increments = Some(inc.len() as u64);
                let mut ev = GapEvidence::new(cfg);
                if !filter {
                    ev = ev.without_outlier_filter();
                }
                for &d in &inc {
                    ev.push_increment(d);
                }
                black_box(ev.snapshot().n_increments)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, evidence);
criterion_main!(benches);
