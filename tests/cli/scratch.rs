//! The tests' own scratch folders: a later run removes those of test processes that have ended
//! (`common::sweep_stale_scratch`), and nothing else in the temporary folder.

use crate::common::{fresh_dir, scratch_owner, sweep_stale_scratch};

#[test]
fn a_scratch_folder_name_gives_its_process_and_nothing_else_does() {
    assert_eq!(
        scratch_owner("allanscope-odd-long-line-26758-1796539929639626817"),
        Some(26758)
    );
    assert_eq!(
        scratch_owner("allanscope-diag-7-1796539929639626817"),
        Some(7)
    );
    // Session 54's own folder names before this sweep (process id alone), other programs' names
    // and a short second number are not the tests' scratch folders.
    assert_eq!(scratch_owner("allanscope-arbck-15591"), None);
    assert_eq!(scratch_owner("allanscope-26758-1796539929639626817"), None);
    assert_eq!(scratch_owner("other-diag-26758-1796539929639626817"), None);
    assert_eq!(scratch_owner("allanscope-diag-26758-17965"), None);
    assert_eq!(
        scratch_owner("allanscope-diag-2a758-1796539929639626817"),
        None
    );
}

#[test]
fn the_sweep_removes_only_the_folders_of_ended_test_processes() {
    let temp = fresh_dir("sweep");
    // A process that has ended: its id names no running process (until the system reuses it).
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .arg("--version")
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let gone = child.id();
    child.wait().unwrap();
    let me = std::process::id();
    let ns = "1796539929639626817";
    let ended = temp.join(format!("allanscope-diag-{gone}-{ns}"));
    let running = temp.join(format!("allanscope-diag-{me}-{ns}"));
    let untagged = temp.join(format!("allanscope-arbck-{gone}"));
    let foreign = temp.join(format!("other-diag-{gone}-{ns}"));
    let file = temp.join(format!("allanscope-file-{gone}-{ns}"));
    for d in [&ended, &running, &untagged, &foreign] {
        std::fs::create_dir_all(d.join("inner")).unwrap();
        std::fs::write(d.join("inner/run.csv"), "1\n").unwrap();
    }
    std::fs::write(&file, "kept\n").unwrap();
    sweep_stale_scratch(&temp);
    if std::path::Path::new("/proc/self").exists() {
        assert!(!ended.exists(), "the ended process's folder was left");
    } else {
        // Without /proc only folders untouched for a day go.
        assert!(ended.exists());
    }
    for kept in [&running, &untagged, &foreign, &file] {
        assert!(kept.exists(), "{} was removed", kept.display());
    }
}
