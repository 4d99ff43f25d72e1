//! One channel with every term and effect for 1e6 steps, for callgrind:
//! `valgrind --tool=callgrind target/release/examples/sim_probe`
use allanscope::sim::{SimModel, Simulator};

fn main() {
    let text = "rate_hz = 250\n[stand]\nlatitude_deg = 56.8\n\
    [temperature]\nstart_c = 20\nfinal_c = 30\ntime_constant_s = 600\nsine_amplitude_c = 0.5\nsine_period_s = 3600\n\
    [[channel]]\nname = \"a\"\nunit = \"m/s\"\naxis = \"up\"\nlsb = 2.104e-4\nQ = 6.84e-4\nN = 2.811e-4\n\
    B = 0.403e-4\nK = 2.228e-6\nR = 6.020e-8\ntemperature_coefficient = 1e-5\n\
    gauss_markov = { sigma = 1e-4, tau_c = 3.0 }\nsinusoid = { amplitude = 1e-4, frequency = 2.5 }\n\
    output_filter = { time_constant = 0.008 }\nwarmup = { amplitude = 1e-3, time_constant = 300 }\n\
    bias_jumps = { mean_interval = 600, rms_size = 1e-5 }\n";
    let model = SimModel::from_toml_str(text, std::path::Path::new("probe.toml")).unwrap();
    let mut sim = Simulator::new(&model, 1);
    let mut acc = 0.0;
    for _ in 0..1_000_000 {
        acc += sim.next_step().increments[0];
    }
    println!("{acc}");
}
