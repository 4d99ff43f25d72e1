//! Size and cost of a checkpoint file: decode, encode, and the atomic write (temporary file,
//! fsync, rename), each timed over several repetitions.
//!
//! ```text
//! cargo run --release --example checkpoint_cost -- FILE.ckpt [REPEATS]
//! ```
//! (BENCHMARKS.md, "Checkpoints", has the figures for a 3-hour 8-channel siu8 run.)

use std::time::Instant;

use allanscope::pipeline::checkpoint::Checkpoint;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let path = std::path::PathBuf::from(
        args.next()
            .ok_or_else(|| anyhow::anyhow!("usage: checkpoint_cost FILE.ckpt [REPEATS]"))?,
    );
    let reps: usize = args.next().map_or(Ok(20), |s| s.parse())?;
    let bytes = std::fs::read(&path)?;
    let ck = Checkpoint::decode(&bytes).map_err(anyhow::Error::msg)?;
    let t_data = ck
        .analysis
        .channels
        .iter()
        .map(|c| c.acc.t_data_s())
        .fold(0.0, f64::max);
    println!(
        "{}: {} bytes, {} channels, {:.0} s of data, overlap {}, complete {}",
        path.display(),
        bytes.len(),
        ck.analysis.channels.len(),
        t_data,
        ck.header.overlap,
        ck.complete
    );
    for c in &ck.analysis.channels {
        println!(
            "  {:4} stream bytes in memory {:>8}",
            c.setup.name,
            c.acc.stream_bytes()
        );
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[v.len() - 1])
    };
    let mut dec = Vec::new();
    let mut enc = Vec::new();
    let mut wr = Vec::new();
    let out = std::env::temp_dir().join(format!("checkpoint_cost_{}.ckpt", std::process::id()));
    for _ in 0..reps {
        let t = Instant::now();
        let c = Checkpoint::decode(&bytes).map_err(anyhow::Error::msg)?;
        dec.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        let b = c.encode()?;
        enc.push(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        allanscope::pipeline::checkpoint::write_atomic(&out, &b)?;
        wr.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let _ = std::fs::remove_file(&out);
    for (name, v) in [("decode", dec), ("encode", enc), ("atomic write", wr)] {
        let (m, max) = median(v);
        println!("{name:>13}: median {m:.2} ms, max {max:.2} ms over {reps}");
    }
    Ok(())
}
