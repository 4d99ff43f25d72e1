//! The degrees of freedom bounded mode keeps against full overlap, by Greenhall's edf with the
//! stride factor S = m / stride (the measurement behind `DEFAULT_L`).
//! `cargo run --release --example choose_l`
use allanscope::allan::edf::edf;
use allanscope::allan::Stat;

fn main() {
    // A 3-hour 250 Hz run.
    let n: u64 = 2_700_001;
    let ms: Vec<u64> = (5..=19).map(|j| 1u64 << j).collect();
    println!("phase points N = {n}; worst ratio edf(L)/edf(full) over m = 32 .. 2^19");
    println!("| L | stat | alpha=+2 | +1 | 0 | -1 | -2 |");
    println!("|---|---|---|---|---|---|---|");
    for l in [4u64, 8, 16, 32, 64] {
        for stat in Stat::ALL {
            let mut row = format!("| {l} | {} |", stat.name());
            for alpha in [2, 1, 0, -1, -2] {
                let mut worst = f64::INFINITY;
                for &m in &ms {
                    let stride = (m / l).max(1);
                    let (Some(b), Some(f)) =
                        (edf(stat, alpha, m, stride, n), edf(stat, alpha, m, 1, n))
                    else {
                        continue;
                    };
                    worst = worst.min(b / f);
                }
                row += &format!(" {worst:.3} |");
            }
            println!("{row}");
        }
    }
}
