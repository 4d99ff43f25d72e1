//! The one-line status of a live run (`listen`, `run`), which the binary redraws in place.

use super::*;

/// The status line of a live run: time running, frames per second, frames lost and the newest
/// N of each channel (`latest`: `(channel, N, unit)`), the unit written once when all share it.
pub fn status_line(
    elapsed_s: f64,
    frames: u64,
    frames_per_s: f64,
    lost: Option<u64>,
    latest: &[(String, f64, String)],
) -> String {
    let running = if elapsed_s < 120.0 {
        format!("{elapsed_s:.0} s")
    } else {
        duration_text(elapsed_s)
    };
    let mut s = format!(
        "{running} running, {frames} frames, {} frames/s",
        sig3(frames_per_s.round())
    );
    if let Some(l) = lost {
        let _ = write!(s, ", {l} lost");
    }
    if !latest.is_empty() {
        let same = latest.iter().all(|x| x.2 == latest[0].2);
        let parts: Vec<String> = latest
            .iter()
            .map(|(c, v, u)| {
                if same {
                    format!("{c} {}", sig3(*v))
                } else {
                    format!("{c} {} {u}", sig3(*v))
                }
            })
            .collect();
        let _ = write!(s, " | N: {}", parts.join("  "));
        if same {
            let _ = write!(s, " {}", latest[0].2);
        }
    }
    s
}
