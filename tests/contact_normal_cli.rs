//! `asperity contact normal` end to end: outputs and error paths (non-zero exit, message naming
//! the parameter, no output left behind). Units: SI.

use std::path::Path;
use std::process::Command;

fn asperity(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn assert_no_output(dir: &Path) {
    if dir.exists() {
        let left: Vec<_> = std::fs::read_dir(dir).unwrap().collect();
        assert!(left.is_empty(), "output left behind: {left:?}");
    }
}

#[test]
fn bad_parameters_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_s = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["--pressures-pa", "0"], "--pressures-pa"),
        (vec!["--pressures-pa", "1e6,-2e6"], "--pressures-pa"),
        (vec!["--pressures-pa", "NaN"], "--pressures-pa"),
        (vec!["--pressures-pa", "1e6,1e6"], "twice"),
        (vec!["--poisson-ratio", "0.7"], "--poisson-ratio"),
        (vec!["--youngs-modulus-pa=-2e11"], "--youngs-modulus-pa"),
        (vec!["--tolerance", "0"], "--tolerance"),
        (vec!["--derivative-step", "0.9"], "--derivative-step"),
    ] {
        let mut full = vec!["contact", "normal", "--out-dir", out_s];
        full.extend(args.iter());
        let (ok, _, err) = asperity(&full);
        assert!(!ok, "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_no_output(&out);
    }
}

#[test]
fn non_convergence_is_an_error_without_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (ok, _, err) = asperity(&[
        "contact",
        "normal",
        "--out-dir",
        out.to_str().unwrap(),
        "--pressures-pa",
        "1e6",
        "--max-iterations",
        "2",
    ]);
    assert!(!ok);
    assert!(err.contains("did not converge"), "{err}");
    assert_no_output(&out);
}
