//! Fuzz harness over every reader and the configuration parsers (proptest; cargo-fuzz needs a
//! nightly toolchain). For each reader, valid seed files are mutated (bytes flipped, inserted,
//! deleted, truncated, numbers replaced by extreme ones, lines duplicated) and random bytes are
//! tried; every reader must return `Ok` or an `Err`, never panic, and never allocate beyond the
//! limits (an out-of-memory abort ends the test process, which fails the test).
//!
//! Bounded in time: `ASPERITY_FUZZ_SECONDS` (default 20) over all readers together; cases past
//! the budget are not generated. Run longer locally with e.g. `ASPERITY_FUZZ_SECONDS=600 cargo
//! test --release --test fuzz_readers`. A failing input is printed.

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, TestRunner};
use std::path::Path;
use std::time::{Duration, Instant};

/// A mutation of a seed: (kind, position, value).
type Edit = (u8, u32, u8);

const EXTREMES: &[&str] = &[
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "0",
    "-0",
    "99999999999999999999",
    "18446744073709551616",
    "",
    ",",
    "1e6,1e6",
    "(1000000, 1000000)",
];

fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut v = seed.to_vec();
    for &(kind, pos, val) in edits {
        let n = v.len();
        let at = if n == 0 { 0 } else { pos as usize % n };
        match kind % 7 {
            0 if n > 0 => v[at] ^= 1 << (val % 8),
            1 => v.insert(at.min(n), val),
            2 if n > 0 => {
                v.remove(at);
            }
            3 => v.truncate(at),
            4 => {
                // Replace the number starting at `at` (if any) by an extreme one.
                let end = v[at.min(n)..]
                    .iter()
                    .position(|b| !(b.is_ascii_digit() || *b == b'.' || *b == b'e' || *b == b'-'))
                    .map_or(n, |k| at + k);
                let rep = EXTREMES[val as usize % EXTREMES.len()].as_bytes();
                v.splice(at.min(n)..end.max(at.min(n)), rep.iter().copied());
            }
            5 => {
                // Duplicate the line around `at`.
                let s = v[..at.min(n)]
                    .iter()
                    .rposition(|b| *b == b'\n')
                    .map_or(0, |k| k + 1);
                let e = v[at.min(n)..]
                    .iter()
                    .position(|b| *b == b'\n')
                    .map_or(n, |k| at + k + 1);
                let line = v[s..e].to_vec();
                v.splice(e..e, line);
            }
            _ => v.push(val),
        }
    }
    v
}

struct Target {
    name: &'static str,
    file_name: &'static str,
    seeds: Vec<Vec<u8>>,
    /// Extra files the reader needs beside the fuzzed one (e.g. a .npy sidecar).
    extra: Vec<(&'static str, Vec<u8>)>,
    read: fn(&Path),
}

fn npy_seed(nx: usize, ny: usize) -> Vec<u8> {
    let mut buf = Vec::new();
    let a = ndarray::Array2::from_shape_fn((nx, ny), |(i, j)| 1e-7 * ((i * 7 + j * 3) % 5) as f64);
    ndarray_npy::WriteNpyExt::write_npy(&a, &mut buf).unwrap();
    buf
}

fn file(rel: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

fn topography(path: &Path) {
    if let Ok(t) = asperity::surface::io::read(path) {
        let _ = asperity::surface::stats(&t, asperity::surface::Detrend::Mean);
        let _ = asperity::surface::stats(&t, asperity::surface::Detrend::Plane);
        let _ = asperity::surface::stats::power_spectrum(&t, asperity::surface::Detrend::Mean);
        if let Ok((t, _)) =
            asperity::surface::missing::fill_topography(t, asperity::surface::Fill::Nearest)
        {
            let _ = asperity::surface::stats(&t, asperity::surface::Detrend::Mean);
        }
    }
}

/// A stepped-sine sweep through a resonance at 80 Hz (accelerance, e^{iωt}), with a header
/// comment stating the control when `stated`.
fn frf_seed(stated: bool) -> Vec<u8> {
    let mut s = String::new();
    if stated {
        s += "# Response control; level 1\n";
    }
    s += "frequency_Hz,force_amplitude_N,acceleration_amplitude_m_per_s2,phase_rad\n";
    for k in 0..21 {
        let f = 79.0 + 0.1 * k as f64;
        let (re, im) = (1.0 - (f / 80.0).powi(2), 0.004 * f / 80.0);
        let amp = 0.2 / re.hypot(im);
        let phase = std::f64::consts::PI - im.atan2(re);
        s += &format!("{f},0.2,{amp:e},{phase}\n");
    }
    s.into_bytes()
}

/// An identified single-mode model as `identify` saves it.
fn model_json_seed() -> Vec<u8> {
    use asperity::identify::model::{Family, Model, ModelSpec, Scales};
    let scales = Scales {
        frequency_hz: 80.0,
        modal_mass_kg: 2.0,
        amplitude_max_m: 2e-4,
        amplitude_min_m: 2e-5,
        force_n: 0.6,
    };
    let model = Model::new(
        ModelSpec::baseline(Family::Jenkins, scales),
        vec![80.0, 1e-3, 2.0, 0.02, 3e-5],
    )
    .unwrap();
    let saved = asperity::identify::SavedModel {
        format: asperity::identify::pipeline::MODEL_FORMAT.into(),
        version: 1,
        model,
        phase_convention: asperity::identify::measured::PhaseConvention::MODEL,
        parameters: Vec::new(),
        identified_from: Vec::new(),
        ensemble: None,
    };
    serde_json::to_vec_pretty(&saved).unwrap()
}

/// A two-mass response model (`asperity response`), the files it names in
/// [`response_model_files`].
const RESPONSE_MODEL: &str = "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[[contact]]\nelements = \"elements.csv\"\nlaw = \"valanis\"\npairs = \"pairs.csv\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [\"m1.x\"]\nlevels_n = [0.02, 0.5]\n\n\
[response]\ndofs = [\"m1.x\", \"m2.x\"]\n\n\
[sweep]\nfrequency_start_hz = 15.0\nfrequency_end_hz = 50.0\npoints = 15\nharmonics = 3\nodd_only = true\n";

fn response_model_files() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("mass.csv", b"# unit: kg\nm1.x,m2.x\n1.0,0\n0,0.5\n".to_vec()),
        ("stiffness.csv", b"# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-2e4,2e4\n".to_vec()),
        ("damping.csv", b"# unit: N*s/m\nm1.x,m2.x\n2,0\n0,1\n".to_vec()),
        (
            "elements.csv",
            b"id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n7,0,0,1e-6,2e6,2.0,1e6,2.0e4,0.3,0.5,0,0\n".to_vec(),
        ),
        ("pairs.csv", b"element_id,node_a,node_b\n7,m2,ground\n".to_vec()),
    ]
}

fn targets() -> Vec<Target> {
    let table = b"pressure_Pa,contact_area_ratio,kn_N_per_m3,E0_N_per_m3,k,mu,Et_N_per_m3,fit_R2,energy_per_cycle_J_per_m2\n1e6,0.001,1e13,6e12,0.5,0.6,0,0.99,0.01\n2e6,0.002,2e13,1e13,0.3,0.6,0,0.99,0.02\n".to_vec();
    let mut png = Vec::new();
    image::RgbImage::from_fn(12, 9, |x, y| {
        image::Rgb([255, (20 * x) as u8, (25 * y) as u8])
    })
    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
    .unwrap();
    let sidecar =
        b"{\"unit\": \"m\", \"dx_m\": 1e-6, \"dy_m\": 1e-6, \"periodic\": false}".to_vec();
    vec![
        Target {
            name: "npy",
            file_name: "h.npy",
            seeds: vec![npy_seed(6, 5), npy_seed(1, 3)],
            extra: vec![("h.npy.json", sidecar.clone())],
            read: topography,
        },
        Target {
            name: "npy sidecar",
            file_name: "h.npy.json",
            seeds: vec![sidecar],
            extra: vec![("h.npy", npy_seed(6, 5))],
            read: |p| topography(&p.with_file_name("h.npy")),
        },
        Target {
            name: "x3p",
            file_name: "h.x3p",
            seeds: vec![file("surfaces/missing-points.x3p")],
            extra: vec![],
            read: topography,
        },
        Target {
            name: "height matrix",
            file_name: "m.csv",
            seeds: vec![
                file("surfaces/missing-points-periodic.csv"),
                b"# unit: nm, dx_m: 1e-6, dy_m: 2e-6\n1,2,3\n4,nan,6\n7,8,9\n".to_vec(),
            ],
            extra: vec![],
            read: topography,
        },
        Target {
            name: "profile text",
            file_name: "p.csv",
            seeds: vec![
                file("surfaces/missing-points-profile.csv"),
                file("surfaces/example-profile.csv"),
                b"# dx_m: 1e-6\nheight_nm\n1\n2\nnan\n4\n".to_vec(),
            ],
            extra: vec![],
            read: topography,
        },
        Target {
            name: "Dektak export",
            file_name: "d.csv",
            seeds: vec![b"Scan Parameters\nLength,1.0 um\nResolution,0.25 um/sample\n\nScan Data\nLateral um,Raw Micrometer,\n0.0,0.1,,\n0.25,0.2,,\n0.5,0.1,,\n0.75,0.3,,\n1.0,0.2,,\n".to_vec()],
            extra: vec![],
            read: topography,
        },
        Target {
            name: "colour table",
            file_name: "t.csv",
            seeds: vec![
                b";Pressure,R,G,B\n0,255,255,255\n2,0,255,0\n2.5,255,227,227\n3.44,255,198,198\n4.38,255,170,170\n10,255,255,0\n".to_vec(),
            ],
            extra: vec![],
            read: |p| {
                let _ = asperity::film::colour::ColourTable::read_csv(p, 20.0);
            },
        },
        Target {
            name: "density calibration",
            file_name: "c.csv",
            seeds: vec![b"# d\ndensity,pressure_MPa\n0.1,1\n0.5,5\n".to_vec()],
            extra: vec![],
            read: |p| {
                let _ = asperity::film::colour::DensityCalibration::read_csv(p);
            },
        },
        Target {
            name: "nodes",
            file_name: "n.csv",
            seeds: vec![b"id,x_m,y_m,area_m2\n1,0,0,1e-6\n2,1e-3,0,1e-6\n3,0,1e-3,1e-6\n".to_vec()],
            extra: vec![],
            read: |p| {
                if let Ok(n) = asperity::film::nodes::read_nodes_csv(p) {
                    let pts: Vec<(f64, f64)> = n.iter().map(|n| (n.x_m, n.y_m)).collect();
                    let _ = asperity::film::nodes::tributary_areas(&pts);
                }
            },
        },
        Target {
            name: "preloads",
            file_name: "pre.csv",
            seeds: vec![b"id,x_m,y_m,area_m2,pressure_Pa,N0_N\n1,0,0,1e-6,1e6,1\n2,1e-3,0,1e-6,2e6,2\n".to_vec()],
            extra: vec![],
            read: |p| {
                let _ = asperity::film::nodes::read_preloads_csv(p);
            },
        },
        Target {
            name: "calibration table",
            file_name: "table.csv",
            seeds: vec![table, file("calib/calibration_table.csv")],
            extra: vec![],
            read: |p| {
                if let Ok(t) = asperity::calibrate::table::CalibrationTable::read_csv(p) {
                    let _ = t.interpolate(1.5e6);
                }
            },
        },
        Target {
            name: "measured record",
            file_name: "r.csv",
            seeds: vec![{
                let mut s = String::from("time_s,displacement_m,friction_force_N\n");
                for k in 0..40 {
                    let t = k as f64 * 0.05;
                    s += &format!("{t},{:e},{:e}\n", 1e-3 * (6.0 * t).sin(), 50.0 * (6.0 * t).cos());
                }
                s.into_bytes()
            }],
            extra: vec![],
            read: |p| {
                let _ = asperity::diagnose::Record::read_csv(p, &Default::default());
            },
        },
        Target {
            name: "FE matrix (Matrix Market)",
            file_name: "k.mtx",
            seeds: vec![b"%%MatrixMarket matrix coordinate real symmetric\n% K\n3 3 5\n1 1 2.0\n2 1 -1.0\n2 2 2.0\n3 2 -1.0\n3 3 1.0\n".to_vec()],
            extra: vec![],
            read: |p| {
                if let Ok(k) = asperity::dynamics::fe_matrices::read_matrix_market(p) {
                    if k.nrows == k.ncols && (2..=64).contains(&k.nrows) {
                        let m = asperity::dynamics::fe_matrices::SparseMatrix {
                            nrows: k.nrows,
                            ncols: k.ncols,
                            entries: (0..k.nrows).map(|i| (i, i, 1.0)).collect(),
                        };
                        let _ = asperity::dynamics::craig_bampton::reduce(&k, &m, &[0], &Default::default());
                    }
                }
            },
        },
        Target {
            name: "FE DOF map (CalculiX .dof)",
            file_name: "job.dof",
            seeds: vec![b"5.1\n5.2\n5.3\n6.1\n6.2\n6.3\n".to_vec()],
            extra: vec![],
            read: |p| {
                if let Ok(d) = asperity::dynamics::fe_matrices::read_dof_map(p) {
                    let _ = asperity::dynamics::fe_matrices::read_calculix_matrix(p, d.len());
                }
            },
        },
        Target {
            name: "calibration config (TOML)",
            file_name: "c.toml",
            seeds: vec![file("calib/reference.toml")],
            extra: vec![],
            read: |p| {
                let _ = asperity::calibrate::config::CalibrationConfig::read(p);
            },
        },
        Target {
            name: "surface spec (TOML)",
            file_name: "s.toml",
            seeds: vec![file("surfaces/reference.toml")],
            extra: vec![],
            read: |p| {
                let text = String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
                if let Ok(s) = toml::from_str::<asperity::surface::GaussianSurfaceSpec>(&text) {
                    let _ = s.validate();
                }
            },
        },
        Target {
            name: "frequency response (identify, predict)",
            file_name: "frf.csv",
            seeds: vec![frf_seed(false), frf_seed(true)],
            extra: vec![],
            read: |p| {
                let _ = asperity::identify::predict::stated_control(p);
                if let Ok(s) = asperity::identify::measured::Sweep::read_csv(p) {
                    let _ = asperity::identify::measured::PhaseConvention::detect_file(&s);
                    let sweeps = vec![s];
                    let _ = asperity::identify::measured::PhaseConvention::detect_common(&sweeps);
                    let _ = asperity::identify::predict::choose_control(&sweeps, None);
                }
            },
        },
        Target {
            name: "identified model (model.json)",
            file_name: "model.json",
            seeds: vec![model_json_seed()],
            extra: vec![],
            read: |p| {
                let _ = asperity::identify::predict::model_inputs(p);
                let _ = asperity::identify::reduced::SavedReducedModel::is_reduced(p);
                let _ = asperity::identify::SavedModel::read(p);
                let _ = asperity::identify::reduced::SavedReducedModel::read(p);
            },
        },
        Target {
            name: "response model (TOML)",
            file_name: "model.toml",
            seeds: vec![RESPONSE_MODEL.as_bytes().to_vec()],
            extra: response_model_files(),
            read: |p| {
                let _ = asperity::dynamics::model_file::referenced_files(p);
                let _ = asperity::dynamics::model_file::load(p);
            },
        },
        Target {
            name: "response matrix",
            file_name: "stiffness.csv",
            seeds: vec![b"# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-2e4,2e4\n".to_vec()],
            extra: {
                let mut f = response_model_files();
                f.retain(|(n, _)| *n != "stiffness.csv");
                f.push(("model.toml", RESPONSE_MODEL.as_bytes().to_vec()));
                f
            },
            read: |p| {
                let _ = asperity::dynamics::model_file::load(&p.with_file_name("model.toml"));
            },
        },
        Target {
            name: "film image",
            file_name: "i.png",
            seeds: vec![png],
            extra: vec![],
            read: |p| {
                let _ = asperity::film::scan::resolution(p);
                let d = asperity::film::colour::DensityCalibration::new(vec![(0.1, 1e6), (0.5, 5e6)], "d")
                    .unwrap();
                let _ = asperity::film::regions::FilmMap::read_image(
                    p,
                    &asperity::film::colour::ColourToPressure::Density(d),
                    1e-4,
                );
            },
        },
    ]
}

#[test]
fn readers_never_panic_on_mutated_or_random_input() {
    let budget = Duration::from_secs_f64(
        std::env::var("ASPERITY_FUZZ_SECONDS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(20.0),
    );
    let targets = targets();
    let per_target = budget / targets.len() as u32;
    let dir = tempfile::tempdir().unwrap();
    let mut report = Vec::new();
    for t in &targets {
        let d = dir.path().join(t.name.replace(' ', "_"));
        std::fs::create_dir_all(&d).unwrap();
        for (name, bytes) in &t.extra {
            std::fs::write(d.join(name), bytes).unwrap();
        }
        let path = d.join(t.file_name);
        let start = Instant::now();
        let count = std::cell::Cell::new(0usize);
        let mut runner = TestRunner::new(Config {
            failure_persistence: None,
            ..Config::default()
        });
        let strategy = (
            0..t.seeds.len() + 1,
            prop::collection::vec((any::<u8>(), any::<u32>(), any::<u8>()), 0..12),
            prop::collection::vec(any::<u8>(), 0..512),
        );
        while start.elapsed() < per_target {
            let (k, edits, random) = strategy.new_tree(&mut runner).unwrap().current();
            count.set(count.get() + 1);
            let bytes = if k < t.seeds.len() {
                mutate(&t.seeds[k], &edits)
            } else {
                random
            };
            std::fs::write(&path, &bytes).unwrap();
            let read = t.read;
            let p = path.clone();
            let outcome = std::panic::catch_unwind(move || read(&p));
            assert!(
                outcome.is_ok(),
                "{} panicked on input {:?}",
                t.name,
                String::from_utf8_lossy(&bytes)
            );
        }
        report.push(format!(
            "{} {} in {:.1} s",
            t.name,
            count.get(),
            start.elapsed().as_secs_f64()
        ));
    }
    eprintln!("fuzzed inputs per reader: {}", report.join(", "));
}

/// The seeds of the frequency-response, model.json and response-model targets are valid input
/// (so the mutations start from files the readers accept and reach past their first check).
#[test]
fn the_seeds_of_the_newer_readers_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for stated in [false, true] {
        let p = d.join("frf.csv");
        std::fs::write(&p, frf_seed(stated)).unwrap();
        let s = asperity::identify::measured::Sweep::read_csv(&p).unwrap();
        asperity::identify::measured::PhaseConvention::detect_file(&s).unwrap();
    }
    let p = d.join("model.json");
    std::fs::write(&p, model_json_seed()).unwrap();
    asperity::identify::SavedModel::read(&p).unwrap();
    for (name, bytes) in response_model_files() {
        std::fs::write(d.join(name), bytes).unwrap();
    }
    let p = d.join("model.toml");
    std::fs::write(&p, RESPONSE_MODEL).unwrap();
    assert_eq!(
        asperity::dynamics::model_file::referenced_files(&p)
            .unwrap()
            .len(),
        6
    );
    asperity::dynamics::model_file::load(&p).unwrap();
}
