//! An interrupt (SIGINT, as Ctrl-C sends) leaves no partial output: previous outputs stay
//! whole, new ones do not appear, and no staging or temporary file remains; exit status 130.

#[cfg(unix)]
#[test]
fn sigint_leaves_previous_outputs_whole_and_no_partial_files() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    // Outputs of an earlier run, which must survive unchanged.
    std::fs::write(out.join("tangential_loops.csv"), "previous run").unwrap();
    for delay_ms in [300u64, 900] {
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
        let pid = child.id().to_string();
        assert!(Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success());
        let t0 = Instant::now();
        let status = child.wait().unwrap();
        assert!(t0.elapsed() < Duration::from_secs(10), "slow to stop");
        assert_eq!(status.code(), Some(130), "after {delay_ms} ms");
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
