//! `plot` and `report` as a user runs them: a missing input is a usage error (exit 2), an
//! existing -o is never overwritten without --force, and the files written parse.

use crate::common::{exe, fixtures, tmp_in};

#[test]
fn plot_and_report_refuse_a_missing_input_and_keep_an_existing_output() {
    let results = tmp_in("plotreport", "r.jsonl");
    let out = exe()
        .args(["analyze", "--format", "siu8", "--every", "100", "--out"])
        .arg(&results)
        .arg(fixtures().join("captures/siu8_stand_5min_seed1.siu8"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (cmd, name) in [("plot", "f.svg"), ("report", "p.html")] {
        let target = tmp_in("plotreport", name);
        let missing = exe()
            .args([cmd, "/nonexistent/none.jsonl", "-o"])
            .arg(&target)
            .output()
            .unwrap();
        assert_eq!(missing.status.code(), Some(2), "{cmd}: missing input");
        assert!(String::from_utf8_lossy(&missing.stderr).contains("/nonexistent/none.jsonl"));
        std::fs::write(&target, "keep me").unwrap();
        let refused = exe()
            .arg(cmd)
            .arg(&results)
            .arg("-o")
            .arg(&target)
            .output()
            .unwrap();
        assert_eq!(refused.status.code(), Some(2), "{cmd}: existing -o");
        assert!(String::from_utf8_lossy(&refused.stderr).contains("--force"));
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep me");
        let forced = exe()
            .arg(cmd)
            .arg(&results)
            .arg("-o")
            .arg(&target)
            .arg("--force")
            .output()
            .unwrap();
        assert!(
            forced.status.success(),
            "{}",
            String::from_utf8_lossy(&forced.stderr)
        );
        let text = std::fs::read_to_string(&target).unwrap();
        if cmd == "plot" {
            // Gyros and accelerometers of the stand unit: two panels.
            assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
            assert_eq!(text.matches("class=\"panel\"").count(), 2);
            assert_eq!(text.matches("class=\"curve\"").count(), 8);
        } else {
            assert!(text.contains("data-verdict=\"NO LIMITS JUDGED\""));
            assert!(
                text.contains("Where in the run"),
                "interim curves give the dynamic view"
            );
        }
    }
}
