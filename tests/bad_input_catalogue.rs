//! The bad-input catalogue: every case reported by users and more, for every reader, configuration
//! key and flag, run through the binary. Each case must end with a non-zero exit that is an
//! error, not a crash (exit 1, or 2 for clap's own argument errors; never 0, 101 = panic or
//! 134 = abort), an error message naming the file, line or flag (the expected fragments), and
//! no output left behind (neither the requested outputs nor staging or temporary files).

#[path = "support/png_density.rs"]
mod png_density;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One catalogue case: a name, the files it needs (written into its own directory; `{d}` in
/// the text is that directory), the arguments (`{d}` substituted) and the fragments the error
/// message must contain.
struct Case {
    name: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    args: Vec<String>,
    want: Vec<&'static str>,
}

fn case(name: &'static str, args: &str, want: &[&'static str]) -> Case {
    Case {
        name,
        files: Vec::new(),
        args: args.split_whitespace().map(str::to_string).collect(),
        want: want.to_vec(),
    }
}

impl Case {
    fn file(mut self, name: &'static str, content: impl Into<Vec<u8>>) -> Self {
        self.files.push((name, content.into()));
        self
    }
}

/// A `.npy` file (float64, C order) with the given header shape and raw data.
fn npy(shape: &str, descr: &str, data: &[u8]) -> Vec<u8> {
    let mut h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (h.len() + 11) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut v = b"\x93NUMPY\x01\x00".to_vec();
    v.extend_from_slice(&(h.len() as u16).to_le_bytes());
    v.extend_from_slice(h.as_bytes());
    v.extend_from_slice(data);
    v
}

fn f64s(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter().flat_map(f64::to_le_bytes).collect()
}

/// A rough `nx × ny` height matrix (heights in m, 1 µm spacing, non-periodic).
fn matrix_text(nx: usize, ny: usize) -> Vec<u8> {
    let mut t = String::from("# unit: m, dx_m: 1e-6, dy_m: 1e-6\n");
    for j in 0..ny {
        let row: Vec<String> = (0..nx)
            .map(|i| format!("{:e}", 1e-8 * (((i * 37 + j * 11) % 17) as f64 - 8.0)))
            .collect();
        t += &row.join(",");
        t.push('\n');
    }
    t.into()
}

fn sidecar(dx: f64) -> Vec<u8> {
    format!("{{\"unit\": \"m\", \"dx_m\": {dx:e}, \"dy_m\": {dx:e}, \"periodic\": false}}").into()
}

/// A 16 × 16 rough height map of the given height scale (m).
fn rough(scale: f64) -> Vec<u8> {
    npy(
        "(16, 16)",
        "<f8",
        &f64s((0..256).map(|k| scale * (((k * 37) % 17) as f64 - 8.0))),
    )
}

/// An x3p archive with the given SizeX, SizeY and data bytes.
fn x3p(
    nx: usize,
    ny: usize,
    data: &[u8],
    extra_entry: Option<(&str, &[u8])>,
    valid_link: bool,
) -> Vec<u8> {
    let valid = if valid_link {
        "<ValidPointsLink>bindata/valid.bin</ValidPointsLink>"
    } else {
        ""
    };
    let xml = format!(
        "<?xml version=\"1.0\"?><p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">\
         <Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType><Axes>\
         <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment></CX>\
         <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment></CY>\
         <CZ><AxisType>A</AxisType><DataType>D</DataType></CZ></Axes></Record1>\
         <Record3><MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ>\
         </MatrixDimension><DataLink><PointDataLink>bindata/data.bin</PointDataLink>{valid}\
         </DataLink></Record3></p:ISO5436_2>"
    );
    let mut buf = std::io::Cursor::new(Vec::new());
    {
        let mut z = zip::ZipWriter::new(&mut buf);
        let o = zip::write::SimpleFileOptions::default();
        z.start_file("main.xml", o).unwrap();
        z.write_all(xml.as_bytes()).unwrap();
        z.start_file("bindata/data.bin", o).unwrap();
        z.write_all(data).unwrap();
        if let Some((name, bytes)) = extra_entry {
            z.start_file(name, o).unwrap();
            z.write_all(bytes).unwrap();
        }
        z.finish().unwrap();
    }
    buf.into_inner()
}

/// A PNG claiming `w × h` pixels with (almost) no image data.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    fn chunk(v: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        v.extend_from_slice(&(data.len() as u32).to_be_bytes());
        v.extend_from_slice(&body);
        // CRC-32 of the chunk type and data.
        let mut crc = 0xFFFF_FFFFu32;
        for &b in &body {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 == 1 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        v.extend_from_slice(&(!crc).to_be_bytes());
    }
    let mut v = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    chunk(&mut v, b"IHDR", &ihdr);
    chunk(
        &mut v,
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    );
    chunk(&mut v, b"IEND", &[]);
    v
}

fn record(force_scale: f64) -> Vec<u8> {
    let mut s = String::from("time_s,displacement_m,friction_force_N\n");
    for k in 0..400 {
        let t = k as f64 * 0.01;
        let x = 1e-3 * (2.0 * std::f64::consts::PI * t).sin();
        let f = force_scale
            * (2.0 * std::f64::consts::PI * t + 0.3)
                .sin()
                .clamp(-0.8, 0.8);
        s += &format!("{t},{x:e},{f:e}\n");
    }
    s.into_bytes()
}

/// [`record`] (scale 100 N) without the data rows `rows` (0-based): a gap in time.
fn record_without_rows(rows: std::ops::Range<usize>) -> String {
    let text = String::from_utf8(record(100.0)).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.drain(rows.start + 1..rows.end + 1);
    lines.join("\n") + "\n"
}

const TABLE: &str = "pressure_Pa,contact_area_ratio,kn_N_per_m3,E0_N_per_m3,k,mu,Et_N_per_m3,fit_R2,energy_per_cycle_J_per_m2\n\
1e6,0.001,1e13,6e12,0.5,0.6,0,0.99,0.01\n2e6,0.002,2e13,1e13,0.3,0.6,0,0.99,0.02\n";

const PRELOAD: &str =
    "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n1,0,0,1e-6,1.5e6,1.5\n2,1e-3,0,1e-6,1.5e6,1.5\n";

fn config(replace: (&str, &str)) -> Vec<u8> {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("calib/reference.toml"))
            .unwrap();
    assert!(text.contains(replace.0), "{}", replace.0);
    text.replacen(replace.0, replace.1, 1).into_bytes()
}

fn catalogue() -> Vec<Case> {
    let dektak_head = "Scan Parameters\nLength,1500.0 um\nResolution,0.156 um/sample\n\nScan Data\nLateral um,Raw Micrometer,\n";
    let mut truncated_dektak = dektak_head.to_string();
    for k in 0..24 {
        truncated_dektak += &format!("{:.1},{:.5},,\n", k as f64 * 0.15625, 0.01 * k as f64);
    }
    vec![
        // --- Out-of-memory aborts: resource limits, named.
        case("npy header claims 1e6 x 1e6", "surface stats {d}/big.npy", &["big.npy", "truncated or corrupt"])
            .file("big.npy", npy("(1000000, 1000000)", "<f8", &[0u8; 32768]))
            .file("big.npy.json", sidecar(1e-6)),
        case("generate --nx 10000000", "surface generate --nx 10000000 -o {d}/s.npy", &["resource limit", "--nx"]),
        case("generate --n 65536", "surface generate --n 65536 -o {d}/s.npy", &["resource limit", "--n"]),
        case("calibrate --grid 100000", "calibrate --grid 100000 --out-dir {d}/out", &["--grid", "resource limit"]),
        case("x3p declaring 24000^2 points", "surface stats {d}/huge.x3p", &["huge.x3p", "resource limit"])
            .file("huge.x3p", x3p(24000, 24000, &[0u8; 64], None, false)),
        case("contact tangential --cycles 1000000", "contact tangential --cycles 1000000 --out-dir {d}/out", &["--cycles", "resource limit"]),
        case("tangential --steps-per-cycle 1e6", "contact tangential --steps-per-cycle 1000000 --out-dir {d}/out", &["--steps-per-cycle", "resource limit"]),
        case("huge image header", "film --image {d}/big.png --density-calibration {d}/d.csv --pixel-size-mm 0.1 --out-dir {d}/out", &["big.png", "resource limit"])
            .file("big.png", png_header(100_000, 100_000))
            .file("d.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("too many pressures", &format!("contact normal --grid 128 --pressures-pa {} --out-dir {{d}}/out", (1..=1001).map(|k| format!("{k}e3")).collect::<Vec<_>>().join(",")), &["--pressures-pa", "resource limit"]),
        // --- Exit 0 with nonsense: physical sanity.
        case("flat surface kn -inf", "contact normal --surface {d}/flat.npy --out-dir {d}/out", &["flat.npy", "flat"])
            .file("flat.npy", npy("(16, 16)", "<f8", &f64s(std::iter::repeat_n(3e-6, 256))))
            .file("flat.npy.json", sidecar(1e-6)),
        case("--tolerance 1", "contact normal --grid 128 --tolerance 1 --out-dir {d}/out", &["--tolerance", "0 < tolerance < 1"]),
        case("--tolerance 5", "contact normal --grid 128 --tolerance 5 --out-dir {d}/out", &["--tolerance"]),
        case("tangential --tolerance 1", "contact tangential --grid 128 --tolerance 1 --out-dir {d}/out", &["--tolerance"]),
        case("config normal_tolerance = 10", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "contact.normal_tolerance"])
            .file("c.toml", config(("normal_tolerance = 1e-10", "normal_tolerance = 10"))),
        case("--pressures-pa 1e-300", "contact normal --grid 128 --pressures-pa 1e-300 --out-dir {d}/out", &["--pressures-pa", "too small"]),
        case("--pressures-pa 2e10 (above E*/10)", "contact normal --grid 128 --pressures-pa 2e10 --out-dir {d}/out", &["--pressures-pa", "linear-elastic"]),
        case("heights 1e292", "contact normal --surface {d}/h.npy --out-dir {d}/out", &["h.npy", "wrong unit"])
            .file("h.npy", rough(1e292))
            .file("h.npy.json", sidecar(1e-6)),
        case("spacing 1e-300", "contact normal --surface {d}/h.npy --out-dir {d}/out", &["h.npy", "spacing"])
            .file("h.npy", rough(1e-7))
            .file("h.npy.json", sidecar(1e-300)),
        case("spacing 1e300", "contact normal --surface {d}/h.npy --out-dir {d}/out", &["h.npy", "spacing"])
            .file("h.npy", rough(1e-7))
            .file("h.npy.json", sidecar(1e300)),
        case("diagnose forces 1e304", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv:2", "friction_force_N", "exceeds"])
            .file("r.csv", record(1e304)),
        case("diagnose --area-m2 1e30", "diagnose {d}/r.csv --table {d}/t.csv --pressure-pa 1e6 --area-m2 1e30 --out-dir {d}/out", &["--area-m2", "slip force"])
            .file("r.csv", record(100.0))
            .file("t.csv", TABLE),
        case("constant profile Rsk/Rku", "surface stats {d}/p.csv", &["p.csv", "flat"])
            .file("p.csv", "x_um,height_um\n0,0.1\n1,0.1\n2,0.1\n3,0.1\n4,0.1\n"),
        case("truncated Dektak export", "surface stats {d}/dektak.csv", &["dektak.csv:", "truncated export"])
            .file("dektak.csv", truncated_dektak),
        case("duplicate node ids (elements)", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["p.csv:3", "duplicate node id 1"])
            .file("p.csv", "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n1,0,0,1e-6,1e6,1\n1,1e-3,0,1e-6,1e6,1\n")
            .file("t.csv", TABLE),
        case("overflowing heights in stats", "surface stats {d}/h.npy", &["h.npy", "overflow"])
            .file("h.npy", rough(1e200))
            .file("h.npy.json", sidecar(1e-6)),
        // --- Data loss and partial outputs.
        case("elements --out x.json", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/x.json", &["--out", "sidecar"])
            .file("p.csv", PRELOAD)
            .file("t.csv", TABLE),
        case("convert with a bad second -o", "surface convert {d}/h.npy -o {d}/good.x3p -o {d}/afile/bad.npy", &["afile", "not a directory"])
            .file("h.npy", rough(1e-7))
            .file("h.npy.json", sidecar(1e-6))
            .file("afile", "I am a file"),
        case("convert to an unknown format", "surface convert {d}/h.npy -o {d}/good.npy -o {d}/bad.xyz", &["--out", "bad.xyz"])
            .file("h.npy", rough(1e-7))
            .file("h.npy.json", sidecar(1e-6)),
        case("film with one file that cannot be written", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --fit-order 0 --out-dir {d}/out", &["regions.csv", "directory"])
            .file("i.png", disc_png())
            .file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n")
            .file("out/regions.csv/blocker", "a directory where a file should go"),
        case("--out-dir is a file (calibrate)", "calibrate --grid 128 --out-dir {d}/f", &["--out-dir", "not a directory"]).file("f", "x"),
        case("--out-dir is a file (diagnose)", "diagnose {d}/r.csv --out-dir {d}/f", &["--out-dir", "not a directory"])
            .file("r.csv", record(100.0))
            .file("f", "x"),
        case("--out-dir below a file (contact)", "contact normal --grid 128 --out-dir {d}/f/sub", &["--out-dir", "not a directory"]).file("f", "x"),
        // --- Unclear errors.
        case("area of 1 x 5 points names the file", "surface stats {d}/m.csv", &["m.csv", "2 × 2"])
            .file("m.csv", "# unit: m, dx_m: 1e-6, dy_m: 1e-6\n1e-7,2e-7,3e-7,1e-7,5e-8\n"),
        case("time not increasing: file line", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv:4", "does not increase"])
            .file("r.csv", "time_s,displacement_m,friction_force_N\n0,0,0\n1,1e-4,1\n0.5,2e-4,2\n"),
        case("300-digit numbers", "contact normal --grid 128 --youngs-modulus-pa -1e300 --out-dir {d}/out", &["--youngs-modulus-pa", "-1e300"]),
        case("empty ROI: no debug text", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --roi-rect-mm 100,100,200,200 --out-dir {d}/out", &["--roi-rect-mm", "contains no pixel"])
            .file("i.png", disc_png())
            .file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("missing .npy named, not its sidecar", "surface stats {d}/none.npy", &["none.npy", "no such file"]),
        // --- Readers: .npy
        case("npy of int32", "surface stats {d}/i.npy", &["i.npy", "float64"]).file("i.npy", npy("(2, 2)", "<i4", &[0u8; 16])).file("i.npy.json", sidecar(1e-6)),
        case("npy of 3 dimensions", "surface stats {d}/c.npy", &["c.npy", "2-D"]).file("c.npy", npy("(2, 2, 2)", "<f8", &[0u8; 64])).file("c.npy.json", sidecar(1e-6)),
        case("npy without sidecar", "surface stats {d}/n.npy", &["n.npy", "sidecar"]).file("n.npy", rough(1e-7)),
        case("npy sidecar not JSON", "surface stats {d}/n.npy", &["n.npy.json", "bad sidecar"]).file("n.npy", rough(1e-7)).file("n.npy.json", "{dx"),
        case("npy sidecar negative dx", "surface stats {d}/n.npy", &["n.npy.json", "dx_m"]).file("n.npy", rough(1e-7)).file("n.npy.json", sidecar(-1e-6)),
        case("npy sidecar in Pa", "surface stats {d}/n.npy", &["n.npy.json", "not heights"]).file("n.npy", rough(1e-7)).file("n.npy.json", "{\"unit\": \"Pa\", \"dx_m\": 1e-6, \"dy_m\": 1e-6, \"periodic\": false}"),
        case("npy not an npy", "surface stats {d}/t.npy", &["t.npy", "not a .npy"]).file("t.npy", "hello").file("t.npy.json", sidecar(1e-6)),
        case("npy with infinity", "surface stats {d}/n.npy", &["n.npy", "non-finite"]).file("n.npy", npy("(2, 2)", "<f8", &f64s([1.0, f64::INFINITY, 0.0, 1.0]))).file("n.npy.json", sidecar(1e-6)),
        // --- Readers: x3p
        case("x3p not a zip", "surface stats {d}/a.x3p", &["a.x3p", "zip"]).file("a.x3p", "not a zip"),
        case("x3p truncated data", "surface stats {d}/a.x3p", &["a.x3p", "main.xml promises"]).file("a.x3p", x3p(4, 4, &[0u8; 100], None, false)),
        case("x3p validity mask missing", "surface stats {d}/a.x3p", &["a.x3p", "validity mask"]).file("a.x3p", x3p(4, 4, &[0u8; 128], None, true)),
        case("x3p validity mask of the wrong size", "surface stats {d}/a.x3p", &["a.x3p", "validity mask"]).file("a.x3p", x3p(4, 4, &[0u8; 128], Some(("bindata/valid.bin", &[255u8; 5])), true)),
        case("x3p every point invalid", "surface stats {d}/a.x3p", &["a.x3p", "every point is missing"]).file("a.x3p", x3p(4, 4, &[0u8; 128], Some(("bindata/valid.bin", &[0u8; 2])), true)),
        case("x3p SizeX 0", "surface stats {d}/a.x3p", &["a.x3p", "SizeX"]).file("a.x3p", x3p(0, 4, &[], None, false)),
        // --- Readers: text topographies
        case("matrix ragged row", "surface stats {d}/m.txt", &["m.txt:3", "row has 2 values"]).file("m.txt", "# unit: m, dx_m: 1e-6, dy_m: 1e-6\n1,2,3\n4,5\n"),
        case("matrix unknown unit", "surface stats {d}/m.txt", &["m.txt:1", "unit"]).file("m.txt", "# unit: furlong, dx_m: 1e-6, dy_m: 1e-6\n1,2\n3,4\n"),
        case("matrix all nan", "surface stats {d}/m.txt", &["m.txt", "missing"]).file("m.txt", "# unit: m, dx_m: 1e-6, dy_m: 1e-6\nnan,nan\nnan,nan\n"),
        case("profile positions not increasing", "surface stats {d}/p.csv", &["p.csv:4", "increase"]).file("p.csv", "x_um,height_nm\n0,1\n2,2\n1,3\n"),
        case("nan in a nonuniform profile", "surface stats {d}/p.csv", &["p.csv:4", "nonuniform"]).file("p.csv", "x_um,height_nm\n0,1\n0.3,2\n1.7,nan\n2,1\n"),
        case("matrix periodic: yes", "surface stats {d}/m.txt", &["m.txt:1", "periodic: yes", "`true` or `false`"]).file("m.txt", "# unit: m, dx_m: 1e-6, dy_m: 1e-6, periodic: yes\n1,2\n3,4\n"),
        case("matrix periodic: 1 (contact)", "contact normal --surface {d}/m.txt --out-dir {d}/out", &["m.txt:2", "periodic: 1"]).file("m.txt", "# asperity height matrix\n# unit: m, dx_m: 1e-6, dy_m: 1e-6, periodic: 1\n1,2\n3,4\n"),
        case("profile periodic: yes", "surface stats {d}/p.csv", &["p.csv:1", "periodic: yes"]).file("p.csv", "# periodic: yes\nx_um,height_nm\n0,1\n1,2\n2,1\n"),
        case("4 x 1 matrix (contact normal)", "contact normal --surface {d}/p.txt --out-dir {d}/out", &["p.txt", "4 x 1 points", "at least 8"]).file("p.txt", "# unit: m, dx_m: 1e-6, dy_m: 1e-6\n1e-7,3e-7,2e-7,1e-7\n"),
        case("4 x 1 matrix (contact tangential)", "contact tangential --surface {d}/p.txt --out-dir {d}/out", &["p.txt", "4 x 1 points", "at least 8"]).file("p.txt", "# unit: m, dx_m: 1e-6, dy_m: 1e-6\n1e-7,3e-7,2e-7,1e-7\n"),
        case("16 x 7 matrix (contact normal)", "contact normal --surface {d}/p.txt --out-dir {d}/out", &["p.txt", "16 x 7 points", "at least 8"]).file("p.txt", matrix_text(16, 7)),
        case("--pressures-pa -1e6 (normal)", "contact normal --grid 128 --pressures-pa -1e6 --out-dir {d}/out", &["--pressures-pa", "got -1e6"]),
        case("--pressures-pa -1e6,2e6 (tangential)", "contact tangential --grid 128 --pressures-pa -1e6,2e6 --out-dir {d}/out", &["--pressures-pa", "got -1e6"]),
        case("--youngs-modulus-pa 210 (GPa meant)", "contact normal --grid 128 --youngs-modulus-pa 210 --pressures-pa 4.8e7 --out-dir {d}/out", &["--pressures-pa", "check the units", "--youngs-modulus-pa is in Pa"]),
        case("--youngs-modulus-pa 210 (tangential)", "contact tangential --grid 128 --youngs-modulus-pa 210 --pressures-pa 4.8e7 --out-dir {d}/out", &["--pressures-pa", "check the units", "--youngs-modulus-pa is in Pa"]),
        case("profile without units", "surface stats {d}/p.csv", &["p.csv:1", "unit"]).file("p.csv", "x,height\n0,1\n1,2\n"),
        case("dektak without data", "surface stats {d}/d.csv", &["d.csv", "Scan Data"]).file("d.csv", "Scan Parameters\nLength,10 um\n"),
        case("binary junk", "surface stats {d}/j.dat", &["j.dat", "binary"]).file("j.dat", vec![0u8, 1, 2, 3, 0, 9]),
        case("image given as topography", "surface stats {d}/i.png", &["i.png", "not a topography"]).file("i.png", disc_png()),
        // --- Readers: film inputs
        case("colour table not monotone", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --out-dir {d}/out", &["t.csv:3", "monotone"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n3,255,200,200\n2.5,255,0,0\n"),
        case("colour table RGB out of range", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --out-dir {d}/out", &["t.csv:2", "0–255"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n2.5,300,200,200\n10,255,0,0\n"),
        case("density calibration bad header", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --out-dir {d}/out", &["c.csv:1", "header"]).file("i.png", disc_png()).file("c.csv", "a,b\n0.1,1\n"),
        case("density calibration not monotone", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --out-dir {d}/out", &["c.csv", "monotone"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.5,1\n0.3,2\n"),
        case("image that is not an image", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --out-dir {d}/out", &["i.png", "cannot read image"]).file("i.png", "text").file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("image declaring 72 dpi (a software default) and no --pixel-size-mm", "film --image {d}/i.png --density-calibration {d}/c.csv --out-dir {d}/out", &["i.png", "--pixel-size-mm", "72.009 dpi"]).file("i.png", disc_png_72dpi()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("image without dpi and no --pixel-size-mm", "film --image {d}/i.png --density-calibration {d}/c.csv --out-dir {d}/out", &["--pixel-size-mm", "no resolution"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("nodes without columns", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --fit-order 0 --nodes {d}/n.csv --out-dir {d}/out", &["n.csv:1", "id, x_m, y_m"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n").file("n.csv", "a,b\n1,2\n"),
        case("nodes duplicate id", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --fit-order 0 --nodes {d}/n.csv --out-dir {d}/out", &["n.csv:3", "duplicate"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n").file("n.csv", "id,x_m,y_m\n1,0,0\n1,1e-3,0\n"),
        // --- Readers: tables and records
        case("calibration table bad header", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["t.csv:1", "header"]).file("p.csv", PRELOAD).file("t.csv", "a,b\n1,2\n"),
        case("calibration table k = 1", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["t.csv:2", "k"]).file("p.csv", PRELOAD).file("t.csv", TABLE.replace("0.5,0.6", "1.0,0.6")),
        case("calibration table pressures unsorted", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["t.csv:3", "increase"]).file("p.csv", PRELOAD).file("t.csv", TABLE.replace("2e6,0.002", "5e5,0.002")),
        case("calibration table in MPa (no node within it)", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["t.csv", "none of the 2 loaded nodes", "another unit"]).file("p.csv", PRELOAD).file("t.csv", TABLE.replace("\n1e6,", "\n1,").replace("\n2e6,", "\n2,")),
        case("preload far above the table", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["node 2", "above the calibration table"]).file("p.csv", PRELOAD.replace("2,1e-3,0,1e-6,1.5e6,1.5", "2,1e-3,0,1e-6,3e7,30")).file("t.csv", TABLE),
        case("pressure maps with --shard", "contact normal --grid 128 --pressures-pa 1e6 --shard 1/2 --pressure-maps --out-dir {d}/out", &["--pressure-maps", "--shard"]),
        case("preload area negative", "elements --preload {d}/p.csv --table {d}/t.csv --out {d}/e.csv", &["p.csv:2", "area"]).file("p.csv", "id,x_m,y_m,area_m2,pressure_Pa,N0_N\n1,0,0,-1,1e6,1\n").file("t.csv", TABLE),
        case("record without the force column", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv:1", "friction_force_N"]).file("r.csv", "time_s,displacement_m\n0,0\n"),
        case("record with text", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv:3", "not a number"]).file("r.csv", "time_s,displacement_m,friction_force_N\n0,0,0\n1,x,1\n"),
        case("record displacement in um as m", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv:2", "displacement_m", "exceeds"]).file("r.csv", "time_s,displacement_m,friction_force_N\n0,50000,1\n1,1,1\n"),
        case("record with a gap in time (10 samples missing)", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv:102", "time_s", "0.99 s to 1.1 s"]).file("r.csv", record_without_rows(100..110)),
        case("record with the force sign reversed", "diagnose {d}/r.csv --out-dir {d}/out", &["r.csv", "`friction_force_N`", "force sign convention reversed? (∮F dx = -"]).file("r.csv", record(-100.0)),
        case("record displacement in inches", "diagnose {d}/r.csv --displacement-column displacement_in --out-dir {d}/out", &["r.csv", "--displacement-column", "`displacement_in`", "must be in m"]).file("r.csv", String::from_utf8(record(100.0)).unwrap().replacen("displacement_m", "displacement_in", 1)),
        case("record force in kip", "diagnose {d}/r.csv --force-column friction_force_kip --out-dir {d}/out", &["r.csv", "--force-column", "`friction_force_kip`", "must be in N"]).file("r.csv", String::from_utf8(record(100.0)).unwrap().replacen("friction_force_N", "friction_force_kip", 1)),
        // --- Configuration keys
        case("config unknown key", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "unknown field"]).file("c.toml", config(("[fit]\n", "[fit]\nk_start = 0.5\n"))),
        case("config TOML syntax", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:"]).file("c.toml", "[surface\nrq_m = 1"),
        case("config mu negative", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "contact.mu"]).file("c.toml", config(("mu = 0.6", "mu = -0.6"))),
        case("config steps_per_cycle 3", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "loading.steps_per_cycle"]).file("c.toml", config(("steps_per_cycle = 40", "steps_per_cycle = 3"))),
        case("config steps_per_cycle 1e6", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "loading.steps_per_cycle", "resource limit"]).file("c.toml", config(("steps_per_cycle = 40", "steps_per_cycle = 1000000"))),
        case("config nx 100000", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "surface.nx", "resource limit"]).file("c.toml", config(("nx = 1024", "nx = 100000"))),
        case("config tangential tolerance 1", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "contact.tangential_tolerance"]).file("c.toml", config(("tangential_tolerance = 1e-4", "tangential_tolerance = 1.0"))),
        case("config pressures unsorted", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "loading.pressures_pa"]).file("c.toml", config(("pressures_pa = [1e5, 2e5", "pressures_pa = [2e5, 1e5"))),
        case("config pressure 1e-300", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "loading.pressures_pa", "too small"]).file("c.toml", config(("pressures_pa = [1e5", "pressures_pa = [1e-300"))),
        case("config k_starts 1", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml:", "fit.k_starts"]).file("c.toml", config(("k_starts = [0.1, 0.5, 0.9]", "k_starts = [1.0]"))),
        case("config poisson 0.7", "calibrate {d}/c.toml --out-dir {d}/out", &["c.toml", "poisson"]).file("c.toml", config(("poisson_ratio = 0.3", "poisson_ratio = 0.7"))),
        case("generate config unknown key", "surface generate --config {d}/s.toml -o {d}/s.npy", &["s.toml:", "unknown field"]).file("s.toml", "rq_m = 1e-7\nfoo = 1\n"),
        // --- Flags
        case("--poisson-ratio 0.6", "contact normal --grid 128 --poisson-ratio 0.6 --out-dir {d}/out", &["--poisson-ratio"]),
        case("--method bogus", "contact normal --grid 128 --method bogus --out-dir {d}/out", &["--method", "bogus"]),
        case("--grid 4", "contact normal --grid 4 --out-dir {d}/out", &["--grid"]),
        case("--fill without --surface", "contact normal --fill harmonic --out-dir {d}/out", &["--surface"]),
        case("--fill bogus", "surface stats --fill bogus {d}/p.csv", &["--fill"]).file("p.csv", "x_um,height_nm\n0,1\n1,2\n2,0\n"),
        case("--psd-out not csv", "surface stats --psd-out {d}/psd.txt {d}/p.csv", &["--psd-out", ".csv"]).file("p.csv", "x_um,height_nm\n0,1\n1,2\n2,0\n"),
        case("--detrend quadratic", "surface stats --detrend quadratic {d}/p.csv", &["--detrend"]).file("p.csv", "x_um,height_nm\n0,1\n1,2\n2,0\n"),
        case("--friction-coefficient 0", "contact tangential --grid 128 --friction-coefficient 0 --out-dir {d}/out", &["--friction-coefficient"]),
        case("--amplitude-m nan", "contact tangential --grid 128 --amplitude-m nan --out-dir {d}/out", &["--amplitude-m"]),
        case("--steps-per-cycle 2", "contact tangential --grid 128 --steps-per-cycle 2 --out-dir {d}/out", &["--steps-per-cycle"]),
        case("--operator foo", "contact tangential --grid 128 --operator foo --out-dir {d}/out", &["--operator"]),
        case("--rq-m -1", "surface generate --rq-m -1 -o {d}/s.npy", &["--rq-m"]),
        case("--cl-m under-resolved", "surface generate --n 32 --cl-m 1e-9 -o {d}/s.npy", &["--cl-m", "under-resolved"]),
        case("--pixel-size-mm 0", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0 --out-dir {d}/out", &["--pixel-size-mm"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("--smooth-mm -1", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --smooth-mm -1 --out-dir {d}/out", &["--smooth-mm"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("--channel purple", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --channel purple --out-dir {d}/out", &["--channel", "purple"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("--channel complement without stain", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --channel complement --out-dir {d}/out", &["--channel", "--stain-rgb"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("--stain-rgb 1,2", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --stain-rgb 1,2 --out-dir {d}/out", &["--stain-rgb"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("--unstained-density above calibration", "film --image {d}/i.png --density-calibration {d}/c.csv --pixel-size-mm 0.1 --unstained-density 0.5 --out-dir {d}/out", &["--unstained-density"]).file("i.png", disc_png()).file("c.csv", "density,pressure_MPa\n0.3,2.5\n1,10\n"),
        case("--min-solidity 2", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --min-solidity 2 --out-dir {d}/out", &["--min-solidity"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("--roi-rect-mm with 3 values", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --roi-rect-mm 1,2,3 --out-dir {d}/out", &["--roi-rect-mm", "4 values"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("--fit-order 40 (no region fitted)", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 0.1 --fit-order 40 --out-dir {d}/out", &["i.png", "none of the"]).file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("--max-effects 100", "diagnose {d}/r.csv --max-effects 100 --out-dir {d}/out", &["--max-effects", "resource limit"]).file("r.csv", record(100.0)),
        // --- Inputs never overwritten, absurd values never pass, clear work limits.
        case("stats --psd-out is the profile", "surface stats {d}/p.csv --psd-out {d}/p.csv", &["--psd-out", "p.csv", "overwritten"])
            .file("p.csv", "x_um,height_nm\n0,1\n1,2\n2,0\n3,1\n"),
        case("combine -o body 1", "surface combine {d}/p.npy {d}/q.npy -o {d}/p.npy", &["--out", "p.npy", "SURFACE1", "overwritten"])
            .file("p.npy", rough(1e-7)).file("p.npy.json", sidecar(1e-6))
            .file("q.npy", rough(2e-7)).file("q.npy.json", sidecar(1e-6)),
        case("diagnose record in --out-dir", "diagnose {d}/out/diagnose.csv --out-dir {d}/out", &["--out-dir", "diagnose.csv", "measured record"])
            .file("out/diagnose.csv", record(100.0)),
        case("combine a.npy a.npy: identical bodies", "surface combine {d}/a.npy {d}/a.npy -o {d}/c.npy", &["a.npy", "identical bodies"])
            .file("a.npy", rough(1e-7)).file("a.npy.json", sidecar(1e-6)),
        case("stats spacing 1e-300", "surface stats {d}/h.npy", &["h.npy", "spacing"])
            .file("h.npy", rough(1e-7)).file("h.npy.json", sidecar(1e-300)),
        case("stats spacing 1e300", "surface stats {d}/h.npy", &["h.npy", "spacing"])
            .file("h.npy", rough(1e-7)).file("h.npy.json", sidecar(1e300)),
        case("film --pixel-size-mm 1e300", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 1e300 --out-dir {d}/out", &["--pixel-size-mm", "film scan"])
            .file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("film --pixel-size-mm 1e-300", "film --image {d}/i.png --colour-table {d}/t.csv --pixel-size-mm 1e-300 --out-dir {d}/out", &["--pixel-size-mm", "film scan"])
            .file("i.png", disc_png()).file("t.csv", "pressure_MPa,R,G,B\n0,255,255,255\n2.5,255,200,200\n10,255,0,0\n"),
        case("calibrate --shard 1/1000000000", "calibrate --shard 1/1000000000 --out-dir {d}/out", &["--shard", "cannot be split"]),
        case("contact normal --shard 2/3 of one surface", "contact normal --grid 128 --shard 2/3 --out-dir {d}/out", &["--shard", "cannot be split"]),
        case("response sweep.points 1e9", "response {d}/m.toml --out-dir {d}/out", &["m.toml:", "sweep.points", "limit"])
            .file("m.toml", "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n[excitation]\ndofs = [\"m1.x\"]\nlevels_n = [0.02]\n\n[response]\ndofs = [\"m1.x\"]\n\n[sweep]\nfrequency_start_hz = 15.0\nfrequency_end_hz = 50.0\npoints = 1000000000\nharmonics = 3\n"),
        case("identify --local-iterations 0", "identify {d}/a.csv {d}/b.csv --local-iterations 0 --out-dir {d}/out", &["--local-iterations"]),
        case("identify a 20 001-row file", "identify {d}/big.csv {d}/b.csv --out-dir {d}/out", &["big.csv", "resource limit", "rows"])
            .file("big.csv", long_sweep(20_001))
            .file("b.csv", long_sweep(41)),
        case("self-affine --n 8 with its defaults", "surface self-affine --n 8 -o {d}/s.npy", &["--n", "too few", "default"]),
        case("--pressure-pa -1 (diagnose)", "diagnose {d}/r.csv --table {d}/t.csv --pressure-pa -1 --area-m2 1e-4 --out-dir {d}/out", &["--pressure-pa"]).file("r.csv", record(100.0)).file("t.csv", TABLE),
    ]
}

/// A stepped-sine sweep of `rows` rows around a resonance at 80 Hz (accelerance, e^{iωt}).
fn long_sweep(rows: usize) -> String {
    let mut s =
        String::from("frequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n");
    for k in 0..rows {
        let f = 79.0 + 2.0 * k as f64 / rows as f64;
        let r = (80.0_f64.powi(2) - f * f) / 80.0_f64.powi(2);
        let x = num_complex(r, 2.0 * 0.002 * f / 80.0);
        s += &format!("{f},0.2,{:e},{}\n", 1.0 / x.0, x.1);
    }
    s
}

/// `(1/|r + i·c|, arg of −ω²/(r + i·c))` for the sweep above: amplitude scale and phase.
fn num_complex(re: f64, im: f64) -> (f64, f64) {
    let norm = re.hypot(im);
    let phase = std::f64::consts::PI - im.atan2(re);
    (
        norm,
        if phase > std::f64::consts::PI {
            phase - 2.0 * std::f64::consts::PI
        } else {
            phase
        },
    )
}

/// A 60 × 60 PNG with a pink disc (0.1 mm pixels: a 3 mm disc) on white, no dpi.
fn disc_png() -> Vec<u8> {
    let mut im = image::RgbImage::from_pixel(60, 60, image::Rgb([255, 255, 255]));
    for (c, r, px) in im.enumerate_pixels_mut() {
        if (c as f64 - 30.0).hypot(r as f64 - 30.0) <= 15.0 {
            *px = image::Rgb([255, 120, 120]);
        }
    }
    let mut buf = std::io::Cursor::new(Vec::new());
    im.write_to(&mut buf, image::ImageFormat::Png).unwrap();
    buf.into_inner()
}

/// [`disc_png`] declaring 2835 pixels per metre (72 dpi, the default of image software).
fn disc_png_72dpi() -> Vec<u8> {
    let im = image::load_from_memory(&disc_png()).unwrap().to_rgb8();
    png_density::rgb_png_with_density(im.width(), im.height(), &im, 2835)
}

/// Every path below `dir`, recursively.
fn tree(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            out.push(p);
        }
    }
    out.sort();
    out
}

#[test]
fn every_bad_input_is_a_clear_error_with_nothing_left_behind() {
    let mut failures = Vec::new();
    let cases = catalogue();
    for c in &cases {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for (name, content) in &c.files {
            let p = d.join(name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, content).unwrap();
        }
        let before = tree(d);
        let args: Vec<String> = c
            .args
            .iter()
            .map(|a| a.replace("{d}", d.to_str().unwrap()))
            .collect();
        let o = Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(&args)
            .current_dir(d)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        let code = o.status.code();
        let mut problems = Vec::new();
        if !matches!(code, Some(1) | Some(2)) {
            problems.push(format!(
                "exit {code:?} (want 1, or 2 for an argument error)"
            ));
        }
        if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
            problems.push("panic".into());
        }
        for w in &c.want {
            if !err.contains(w) {
                problems.push(format!("message lacks `{w}`"));
            }
        }
        if err.contains(" { ") || err.contains("Some(") {
            problems.push("Rust debug text in the message".into());
        }
        if err
            .split(|ch: char| !ch.is_ascii_digit())
            .any(|t| t.len() > 40)
        {
            problems.push("a number of more than 40 digits".into());
        }
        let after = tree(d);
        if after != before {
            let new: Vec<_> = after.iter().filter(|p| !before.contains(p)).collect();
            problems.push(format!("left behind: {new:?}"));
        }
        if !problems.is_empty() {
            failures.push(format!(
                "{}: {} — stderr: {}",
                c.name,
                problems.join("; "),
                err.trim()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} catalogue cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
    eprintln!(
        "{} bad-input cases: all clear errors, nothing left behind",
        cases.len()
    );
}

#[test]
fn defaults_that_no_longer_surprise() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_asperity"))
            .args(args)
            .current_dir(d)
            .output()
            .unwrap()
    };
    // surface stats writes nothing into the current directory by default.
    std::fs::write(d.join("p.csv"), "x_um,height_nm\n0,1\n1,2\n2,0\n3,1\n").unwrap();
    let o = run(&["surface", "stats", "p.csv"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(tree(d), vec![d.join("p.csv")]);
    // PNG and x3p outputs are 0644 like CSV and JSON.
    let o = run(&[
        "surface", "generate", "--n", "32", "--size-m", "3.2e-5", "--cl-m", "3e-6", "-o", "s.x3p",
        "-o", "s.png", "-o", "s.npy",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    #[cfg(unix)]
    for f in ["s.x3p", "s.png", "s.npy", "s.npy.json"] {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(d.join(f)).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o644, "{f}");
    }
    // surface self-affine with its defaults on every grid from 16 points up (64 and below
    // failed, naming --rolloff-wavelength-m, a flag not given).
    for n in ["16", "32", "64"] {
        let o = run(&["surface", "self-affine", "--n", n, "-o", "sa.npy"]);
        assert!(
            o.status.success(),
            "--n {n}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // contact normal takes --grid; with output redirected, progress prints log lines.
    let o = run(&[
        "contact",
        "normal",
        "--grid",
        "128",
        "--pressures-pa",
        "1e6,5e6",
        "--out-dir",
        "cn",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("normal contact: seed-1"), "{err}");
    assert!(d.join("cn/normal_sweep.csv").exists());
    assert!(!tree(d)
        .iter()
        .any(|p| p.to_string_lossy().contains(".asperity-")));
}
