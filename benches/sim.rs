//! Simulator throughput (BENCHMARKS.md, "Simulator"). `cargo bench --bench sim`
use allanscope::sim::{SimModel, Simulator};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

/// One accelerometer channel with the seed paper's MA4 terms, its LSB, and every effect on.
const EVERYTHING: &str = "rate_hz = 250\n[stand]\nlatitude_deg = 56.8\n\
    [temperature]\nstart_c = 20\nfinal_c = 30\ntime_constant_s = 600\nsine_amplitude_c = 0.5\nsine_period_s = 3600\n\
    [[channel]]\nname = \"a\"\nunit = \"m/s\"\naxis = \"up\"\nlsb = 2.104e-4\nQ = 6.84e-4\nN = 2.811e-4\n\
    B = 0.403e-4\nK = 2.228e-6\nR = 6.020e-8\ntemperature_coefficient = 1e-5\n\
    gauss_markov = { sigma = 1e-4, tau_c = 3.0 }\nsinusoid = { amplitude = 1e-4, frequency = 2.5 }\n\
    output_filter = { time_constant = 0.008 }\nwarmup = { amplitude = 1e-3, time_constant = 300 }\n\
    bias_jumps = { mean_interval = 600, rms_size = 1e-5 }\n";

const FIVE_TERMS: &str =
    "rate_hz = 250\n[[channel]]\nname = \"a\"\nunit = \"m/s\"\nlsb = 2.104e-4\n\
    Q = 6.84e-4\nN = 2.811e-4\nB = 0.403e-4\nK = 2.228e-6\nR = 6.020e-8\n";

fn one_channel(c: &mut Criterion) {
    let n = 2_000_000u64;
    let mut g = c.benchmark_group("simulator, one channel, 2e6 steps");
    g.throughput(Throughput::Elements(n));
    g.sample_size(10);
    for (name, text) in [
        ("every term and effect", EVERYTHING),
        ("five terms + lsb", FIVE_TERMS),
    ] {
        let model = SimModel::from_toml_str(text, std::path::Path::new("bench.toml")).unwrap();
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut sim = Simulator::new(&model, 1);
                let mut acc = 0.0;
                for _ in 0..n {
                    acc += sim.next_step().increments[0];
                }
                acc
            })
        });
    }
    g.finish();
}

criterion_group!(benches, one_channel);
criterion_main!(benches);
