//! Done-when 3 and 4: generate → write each format → read → identical statistics; bad input gets
//! a clear error naming the file and line or parameter, a non-zero exit and no output file.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn asperity(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_asperity"))
        .args(args)
        .output()
        .expect("run asperity")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `stats --json` without the fields that name files or times.
fn stats_json(file: &Path, psd: &Path) -> serde_json::Value {
    let o = asperity(&["surface", "stats", "--json", "--psd-out", s(psd), s(file)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in ["file", "psd_csv", "psd_png", "read_time_s", "stats_time_s"] {
        v.as_object_mut().unwrap().remove(k);
    }
    v
}

#[test]
fn every_format_round_trips_to_identical_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Anisotropic, rectangular, non-square grid: catches swapped axes in any format.
    let outs: Vec<PathBuf> = ["p.npy", "p.x3p", "p.csv", "p.txt", "p.png"]
        .iter()
        .map(|n| d.join(n))
        .collect();
    let mut args = vec![
        "surface", "generate", "--rq-m", "3e-7", "--clx-m", "8e-6", "--cly-m", "4e-6", "--lx-m",
        "1.6e-4", "--ly-m", "1e-4", "--nx", "80", "--ny", "64", "--seed", "42",
    ];
    for o in &outs {
        args.push("--out");
        args.push(s(o));
    }
    let o = asperity(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for o in &outs {
        assert!(o.exists(), "{} missing", o.display());
    }
    assert!(image::open(&outs[4]).is_ok(), "PNG unreadable");

    let reference = asperity::surface::generate(&asperity::surface::GaussianSurfaceSpec {
        rq_m: 3e-7,
        clx_m: 8e-6,
        cly_m: 4e-6,
        lx_m: 1.6e-4,
        ly_m: 1e-4,
        nx: 80,
        ny: 64,
        seed: 42,
    })
    .unwrap();
    let want = stats_json(&outs[0], &d.join("psd0.csv"));
    let psd0 = std::fs::read_to_string(d.join("psd0.csv")).unwrap();
    assert_eq!(want["periodic"], true);
    assert_eq!(want["nx"], 80);
    assert_eq!(want["ny"], 64);
    for (k, o) in outs[..4].iter().enumerate() {
        // Heights and spacing bit for bit through the library reader ...
        let g = asperity::surface::io::read(o)
            .unwrap()
            .into_area("test")
            .unwrap();
        assert_eq!(
            g,
            reference,
            "{} differs from the generated grid",
            o.display()
        );
        // ... and identical statistics and PSD through the binary.
        let psd = d.join(format!("psd{}.csv", k + 10));
        let got = stats_json(o, &psd);
        assert_eq!(got, want, "{}", o.display());
        let text = std::fs::read_to_string(&psd).unwrap();
        let body = |t: &str| t.lines().skip(1).collect::<Vec<_>>().join("\n");
        assert_eq!(body(&text), body(&psd0), "PSD of {}", o.display());
    }
}

#[test]
fn profile_text_with_units_reads_as_a_uniform_profile() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("prof.csv");
    // x in µm, heights in nm: a 4-point ramp with known statistics.
    std::fs::write(
        &f,
        "# a test profile\nx_um, height_nm\n0, 10\n0.5, 20\n1.0, 30\n1.5, 40\n",
    )
    .unwrap();
    let t = asperity::surface::io::read(&f).unwrap();
    let asperity::surface::Topography::Profile(p) = t else {
        panic!("expected a profile")
    };
    assert!(p.is_uniform());
    assert!((p.dx - 0.5e-6).abs() < 1e-18);
    for (h, want) in p.heights.iter().zip([10e-9, 20e-9, 30e-9, 40e-9]) {
        assert!((h / want - 1.0).abs() < 1e-15, "{h} vs {want}");
    }
    let st = asperity::surface::stats(
        &asperity::surface::Topography::Profile(p),
        Default::default(),
    );
    // Rq of 4 equally spaced values about their mean: 10 nm · √(5/4); slope 10 nm / 0.5 µm.
    let st = st.unwrap();
    assert!((st.rq_m / (10e-9 * 1.25f64.sqrt()) - 1.0).abs() < 1e-12);
    assert!((st.rms_slope / 0.02 - 1.0).abs() < 1e-12);
}

/// Run `surface stats` on `file` and check it fails with every `want` in the message and
/// writes no PSD.
fn assert_stats_fails(file: &Path, want: &[&str]) {
    let psd = file.with_file_name("out-psd.csv");
    let o = asperity(&["surface", "stats", "--psd-out", s(&psd), s(file)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{} should fail", file.display());
    assert_eq!(o.status.code(), Some(1));
    for w in want {
        assert!(err.contains(w), "`{err}` should mention `{w}`");
    }
    assert!(
        !psd.exists() && !psd.with_extension("png").exists(),
        "output left behind"
    );
}

#[test]
fn bad_text_input_names_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let write = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let f = write("empty.csv", "");
    assert_stats_fails(&f, &["empty.csv", "empty file"]);
    let f = write("blank.txt", "\n\n  \n");
    assert_stats_fails(&f, &["blank.txt", "empty file"]);
    let f = write("letters.csv", "x_um,height_um\n0,1\n1,2\n2,abc\n3,4\n");
    assert_stats_fails(&f, &["letters.csv:4", "column 2", "`abc` is not a number"]);
    let f = write("inf.csv", "x_um,height_um\n0,1\n1,inf\n2,3\n");
    assert_stats_fails(&f, &["inf.csv:3", "non-finite"]);
    // A missing height (nan) is a missing point, but the PSD needs every point.
    let f = write("nan.csv", "x_um,height_um\n0,1\n1,NaN\n2,3\n3,1\n");
    assert_stats_fails(&f, &["--psd-out", "nan.csv", "missing", "--fill"]);
    let f = write("nounits.csv", "x,height\n0,1\n1,2\n");
    assert_stats_fails(&f, &["nounits.csv:1", "unit"]);
    let f = write("noheader.csv", "0,1\n1,2\n");
    assert_stats_fails(&f, &["noheader.csv:1", "header"]);
    let f = write("backwards.csv", "x_um,height_um\n0,1\n2,2\n1,3\n");
    assert_stats_fails(&f, &["backwards.csv", "increase"]);
    let f = write("short.csv", "x_um,height_um\n0,1\n1\n");
    assert_stats_fails(&f, &["short.csv:3", "columns"]);
    let f = write(
        "matrix.txt",
        "# unit: m, dx_m: 1e-6, dy_m: 1e-6\n1,2,3\n4,5\n",
    );
    assert_stats_fails(&f, &["matrix.txt:3", "row has 2 values"]);
    let f = write(
        "matrixinf.txt",
        "# unit: m, dx_m: 1e-6, dy_m: 1e-6\n1,2,3\n4,-inf,6\n",
    );
    assert_stats_fails(&f, &["matrixinf.txt:3", "non-finite"]);
    let f = write(
        "matrixdx.txt",
        "# unit: m, dx_m: -1e-6, dy_m: 1e-6\n1,2,3\n4,5,6\n",
    );
    assert_stats_fails(&f, &["matrixdx.txt", "dx"]);
    let f = write(
        "dektak.csv",
        "Scan Parameters\nStylus,Radius: 2.5 um\n\nScan Data\n\nLateral um,Raw Micrometer,\n0.0,1.0,,\n0.2,x2,,\n",
    );
    assert_stats_fails(&f, &["dektak.csv:8", "`x2` is not a number"]);
    let f = write(
        "dektak-nodata.csv",
        "Scan Parameters\nStylus,Radius: 2.5 um\n",
    );
    assert_stats_fails(&f, &["dektak-nodata.csv", "Scan Data"]);
    // A missing file and a bad detrend name.
    assert_stats_fails(&d.join("missing.csv"), &["missing.csv"]);
    let g = write("ok.csv", "x_um,height_um\n0,1\n1,2\n2,0\n");
    let o = asperity(&["surface", "stats", "--detrend", "quadratic", s(&g)]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("detrend"));
}

/// Copy the entries of x3p `src` into `dst`, letting `edit` change (name, bytes).
fn rewrite_x3p(src: &Path, dst: &Path, edit: impl Fn(&str, Vec<u8>) -> Vec<u8>) {
    let mut zin = zip::ZipArchive::new(std::fs::File::open(src).unwrap()).unwrap();
    let mut zout = zip::ZipWriter::new(std::fs::File::create(dst).unwrap());
    for k in 0..zin.len() {
        let mut e = zin.by_index(k).unwrap();
        let name = e.name().to_string();
        let mut buf = Vec::new();
        e.read_to_end(&mut buf).unwrap();
        zout.start_file(name.as_str(), zip::write::SimpleFileOptions::default())
            .unwrap();
        zout.write_all(&edit(&name, buf)).unwrap();
    }
    zout.finish().unwrap();
}

#[test]
fn bad_x3p_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = d.join("good.x3p");
    let o = asperity(&[
        "surface",
        "generate",
        "--n",
        "32",
        "--size-m",
        "3.2e-5",
        "--cl-m",
        "3e-6",
        "--out",
        s(&good),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let truncated = d.join("truncated.x3p");
    rewrite_x3p(&good, &truncated, |n, b| {
        if n == "bindata/data.bin" {
            b[..b.len() - 8].to_vec()
        } else {
            b
        }
    });
    assert_stats_fails(&truncated, &["truncated.x3p", "truncated or inconsistent"]);

    let inconsistent = d.join("inconsistent.x3p");
    rewrite_x3p(&good, &inconsistent, |n, b| {
        if n == "main.xml" {
            String::from_utf8(b)
                .unwrap()
                .replace("<SizeX>32</SizeX>", "<SizeX>33</SizeX>")
                .into_bytes()
        } else {
            b
        }
    });
    assert_stats_fails(&inconsistent, &["inconsistent.x3p", "main.xml promises"]);

    let corrupted = d.join("corrupted.x3p");
    rewrite_x3p(&good, &corrupted, |n, mut b| {
        if n == "bindata/data.bin" {
            b[100] ^= 0x55;
        }
        b
    });
    assert_stats_fails(&corrupted, &["corrupted.x3p", "MD5"]);

    let nan = d.join("nan.x3p");
    rewrite_x3p(&good, &nan, |n, mut b| {
        if n == "main.xml" {
            // Drop the checksum so the NaN itself is what is read.
            let x = String::from_utf8(b).unwrap();
            let start = x.find("<MD5ChecksumPointData>").unwrap();
            let end = x.find("</MD5ChecksumPointData>").unwrap() + "</MD5ChecksumPointData>".len();
            return format!("{}{}", &x[..start], &x[end..]).into_bytes();
        }
        if n == "bindata/data.bin" {
            b[8..16].copy_from_slice(&f64::NAN.to_le_bytes());
        }
        b
    });
    // A NaN height is a missing point: the statistics exclude it, the PSD needs it filled.
    assert_stats_fails(
        &nan,
        &["--psd-out", "nan.x3p", "1 missing points", "--fill"],
    );

    let noxml = d.join("noxml.x3p");
    rewrite_x3p(&good, &noxml, |n, b| {
        if n == "main.xml" {
            b"<p:ISO5436_2><Record1>".to_vec()
        } else {
            b
        }
    });
    assert_stats_fails(&noxml, &["noxml.x3p", "main.xml"]);

    let notzip = d.join("notzip.x3p");
    std::fs::write(&notzip, b"this is not a zip archive").unwrap();
    assert_stats_fails(&notzip, &["notzip.x3p", "zip"]);

    let empty = d.join("empty.x3p");
    std::fs::write(&empty, b"").unwrap();
    assert_stats_fails(&empty, &["empty.x3p"]);
}
