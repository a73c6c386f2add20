//! An interrupt (SIGINT, as Ctrl-C sends) reports what actually happened. Before the outputs are
//! moved into place: previous outputs stay whole, new ones do not appear, no staging or
//! temporary file remains, "interrupted before writing: previous files untouched", exit 130.
//! After the new set is complete: "interrupted after the new set was complete: new files in
//! place", exit 3. Never a message about a staged file.

#[cfg(unix)]
fn interrupt(child: &std::process::Child) {
    let pid = child.id().to_string();
    assert!(std::process::Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap()
        .success());
}

/// Staged-file names and I/O errors must not reach the user after an interrupt.
#[cfg(unix)]
fn no_staging_talk(err: &str) {
    for bad in [".asperity-", "No such file", "error:"] {
        assert!(!err.contains(bad), "`{bad}` in: {err}");
    }
}

#[cfg(unix)]
#[test]
fn sigint_before_writing_leaves_previous_outputs_whole_and_says_so() {
    use std::io::Read;
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    // Outputs of an earlier run, which must survive unchanged.
    std::fs::write(out.join("tangential_loops.csv"), "previous run").unwrap();
    for delay_ms in [100u64, 300, 600, 900] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args([
                "contact",
                "tangential",
                "--grid",
                "128",
                "--cycles",
                "200",
                "--steps-per-cycle",
                "40",
                "--out-dir",
            ])
            .arg(&out)
            .stderr(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(delay_ms));
        interrupt(&child);
        let t0 = Instant::now();
        let status = child.wait().unwrap();
        assert!(t0.elapsed() < Duration::from_secs(10), "slow to stop");
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        assert_eq!(status.code(), Some(130), "after {delay_ms} ms: {err}");
        assert!(
            err.contains("interrupted before writing: previous files untouched"),
            "after {delay_ms} ms: {err}"
        );
        no_staging_talk(&err);
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .chain(std::fs::read_dir(&out).unwrap())
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            vec!["out", "tangential_loops.csv"],
            "after {delay_ms} ms"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("tangential_loops.csv")).unwrap(),
            "previous run"
        );
    }
}

#[cfg(unix)]
#[test]
fn sigint_after_the_new_set_is_complete_says_the_new_files_are_in_place() {
    use std::io::Read;
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.npy"), "previous run").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args([
            "surface", "generate", "--n", "32", "--size-m", "3.2e-5", "--cl-m", "3e-6", "-o",
            "s.npy", "-o", "s.png",
        ])
        .current_dir(d)
        .env("ASPERITY_TEST_PAUSE_BEFORE_EXIT_MS", "30000")
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the new set is in place (the command then pauses before exiting).
    let t0 = Instant::now();
    while !d.join("s.png").exists() {
        assert!(t0.elapsed() < Duration::from_secs(30), "no output");
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(100));
    interrupt(&child);
    let status = child.wait().unwrap();
    assert!(t0.elapsed() < Duration::from_secs(20), "slow to stop");
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    assert_eq!(status.code(), Some(3), "{err}");
    assert!(
        err.contains("interrupted after the new set was complete: new files in place"),
        "{err}"
    );
    no_staging_talk(&err);
    assert!(std::fs::read(d.join("s.npy"))
        .unwrap()
        .starts_with(b"\x93NUMPY"));
    assert!(d.join("s.npy.json").exists());
}
