//! The microslip contact element whose `kn` and `E0` follow the instantaneous normal load
//! (`element::LoadFollowingContact`) in the dynamics: harmonic balance against Newmark time
//! integration of the same equations, and the model file's `load_following` key.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model::Structure;
#[path = "support/hbm_newmark.rs"]
mod hbm_newmark;
use asperity::element::{HystereticElement, LoadFollowingContact, MicroslipContact, ValanisParams};
use hbm_newmark::ramped_hbm_against_newmark;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::sync::Arc;

const M: f64 = 0.1;
const K: f64 = 4.0e5;
const ZETA: f64 = 0.01;
const N0: f64 = 10.0;
const KN: f64 = 2.0e6;

/// A mass on springs in x (tangential) and z (normal), pressed on a rough contact to ground
/// (preload N0, `u = (x, 0, z)`), driven in x and z at once so that the normal load oscillates
/// with the slip.
fn block(element: Arc<dyn HystereticElement>) -> Structure {
    let c = 2.0 * ZETA * (K * M).sqrt();
    let mut s = Structure::lumped(
        vec!["x".into(), "z".into()],
        DMatrix::from_diagonal_element(2, 2, M),
        DMatrix::from_diagonal_element(2, 2, c),
        DMatrix::from_diagonal_element(2, 2, K),
    )
    .unwrap();
    let map = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
    s.attach("contact", element, map).unwrap();
    s
}

fn valanis() -> ValanisParams {
    ValanisParams::new(1.0e6, 0.4, 0.0, 0.6).unwrap()
}

/// First-harmonic amplitudes of x by the harmonic balance (ramped in level from the linear
/// regime) and by Newmark's steady state started from it.
fn hbm_and_newmark(structure: &Structure, f_hz: f64, level: f64, samples: usize) -> (f64, f64) {
    let h = Harmonics::new(9, false, Some(samples)).unwrap();
    let sys = HbmSystem::new(
        structure,
        h,
        Excitation {
            force: DVector::from_column_slice(&[1.0, 0.6]),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let w = 2.0 * PI * f_hz;
    let (_, a_hbm, a_ti) =
        ramped_hbm_against_newmark(&sys, w, level, &format!("{f_hz} Hz"), samples);
    (a_hbm, a_ti)
}

/// Harmonic balance against Newmark on the block with `kn ∝ N^0.75`, `E0 ∝ N^0.7` (the
/// reference table's exponents near 2–5 MPa), through microslip and slip with the normal load
/// varying by tens of percent: first harmonic within 1e-4 ... and the load following changes the
/// response by more than the tolerance (the test can tell the laws apart).
#[test]
fn load_following_contact_harmonic_balance_matches_newmark() {
    let following: Arc<dyn HystereticElement> =
        Arc::new(LoadFollowingContact::new(valanis(), KN, N0, 0.75, 0.7).unwrap());
    let plain: Arc<dyn HystereticElement> =
        Arc::new(MicroslipContact::new(valanis(), KN, N0).unwrap());
    for (f_hz, level) in [(520.0, 3.0), (560.0, 5.0)] {
        let s = block(following.clone());
        let (a_hbm, a_ti) = hbm_and_newmark(&s, f_hz, level, 2048);
        let (a_plain, _) = hbm_and_newmark(&block(plain.clone()), f_hz, level, 2048);
        let err = (a_hbm - a_ti).abs() / a_ti;
        let change = (a_hbm - a_plain).abs() / a_plain;
        eprintln!(
            "{f_hz:.1} Hz: HBM {a_hbm:.6e}, Newmark {a_ti:.6e}, relative {err:.1e}; plain element {a_plain:.6e} ({change:.1e})"
        );
        assert!(err < 1e-4, "{f_hz} Hz: {err:.2e}");
        assert!(
            change > 1e-2,
            "{f_hz} Hz: load following changes nothing ({change:.1e})"
        );
    }
}

/// `load_following = "<calibration table>"` in a `[[contact]]`: each element follows the load
/// with the exponents of the table segment its pressure lies in (computed here from the rows:
/// `ln(v₂/v₁)/ln(p₂/p₁)`), including one beyond the table (the end pair's); the law's force
/// then differs from the constant element's under a changed normal load and not at the preload.
/// Refused with the file and line: with the `jenkins` law, and for an element table without
/// `pressure_Pa`.
#[test]
fn model_file_load_following_takes_the_calibration_tables_exponents() {
    use asperity::dynamics::model_file::{load, referenced_files};
    let dir = tempfile::tempdir().unwrap();
    let w = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    w("mass.csv", "# unit: kg\nb.x,b.z\n1.0,0\n0,1.0\n");
    w("damping.csv", "# unit: N*s/m\nb.x,b.z\n1.0,0\n0,1.0\n");
    w("stiffness.csv", "# unit: N/m\nb.x,b.z\n1e4,0\n0,1e4\n");
    // Rows at 1, 2 and 5 MPa.
    let rows = [
        (1e6, 2.0e12, 1.0e12, 0.6),
        (2e6, 3.2e12, 1.5e12, 0.55),
        (5e6, 6.0e12, 2.6e12, 0.5),
    ];
    let mut table = String::from(
        "pressure_Pa,contact_area_ratio,kn_N_per_m3,E0_N_per_m3,k,mu,Et_N_per_m3,fit_R2,energy_per_cycle_J_per_m2\n",
    );
    for (p, kn, e0, k) in rows {
        table += &format!("{p},0.01,{kn},{e0},{k},0.6,0,0.99,1e-3\n");
    }
    w("calibration_table.csv", &table);
    // Three elements: within the first and the second segment, and above the table.
    let area = 1e-6;
    let mut elements = String::from(
        "# units: as written by asperity elements\nid,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n",
    );
    for (id, p) in [(1, 1.5e6), (2, 3e6), (3, 7e6)] {
        elements += &format!(
            "{id},0,0,{area},{p},{},{},{},0.55,0.6,0,0\n",
            p * area,
            3e12 * area,
            1.4e12 * area
        );
    }
    w("elements.csv", &elements);
    let contact = "[[contact]]\nelements = \"elements.csv\"\nlaw = \"valanis\"\nnode_a = \"b\"\n\
                   node_b = \"ground\"\nnormal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\
                   load_following = \"calibration_table.csv\"\n";
    let head = "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n";
    let tail = "\n[excitation]\ndofs = [\"b.x\"]\nlevels_n = [1.0]\n\n[response]\ndofs = [\"b.x\"]\n\n\
                [sweep]\nfrequency_start_hz = 10.0\nfrequency_end_hz = 20.0\nharmonics = 3\nodd_only = false\n";
    let model = dir.path().join("model.toml");
    std::fs::write(&model, format!("{head}{contact}{tail}")).unwrap();
    let loaded = load(&model).unwrap();
    let slope = |i: usize, f: fn(&(f64, f64, f64, f64)) -> f64| {
        (f(&rows[i + 1]) / f(&rows[i])).ln() / (rows[i + 1].0 / rows[i].0).ln()
    };
    for ((_, row), segment) in loaded.element_rows.iter().zip([0, 1, 1]) {
        let [b, a] = row.load_exponents.expect("load exponents");
        assert!(
            (b - slope(segment, |r| r.1)).abs() < 1e-12,
            "element {}",
            row.id
        );
        assert!(
            (a - slope(segment, |r| r.2)).abs() < 1e-12,
            "element {}",
            row.id
        );
    }
    let files = referenced_files(&model).unwrap();
    assert!(files
        .iter()
        .any(|(role, p)| role.contains("load_following") && p.ends_with("calibration_table.csv")));
    // At the preload the element is the constant one; pressed 20 % harder it is stiffer in both
    // directions: tangential force after a small stuck step ∝ E0(N), normal force ∝ ∫kn dN.
    let el = &loaded.structure.elements[0].element;
    let (_, row) = &loaded.element_rows[0];
    let n0 = row.n0_n;
    let plain =
        MicroslipContact::new(row.element.valanis().unwrap(), row.element.kn_n_per_m, n0).unwrap();
    let step = |e: &dyn HystereticElement, un: f64| {
        let (mut s1, mut f) = ([0.0; 4], [0.0; 3]);
        e.step(
            &[0.0; 4],
            &[0.0, 0.0, un],
            &[1e-12, 0.0, un],
            &mut s1,
            &mut f,
            None,
        );
        f
    };
    let (fa, fb) = (step(el.as_ref(), 0.0), step(&plain, 0.0));
    assert!((fa[0] - fb[0]).abs() < 1e-12 * fb[0].abs() && fa[2] == fb[2]);
    let [b, a] = row.load_exponents.unwrap();
    let un = 0.2 * n0 / row.element.kn_n_per_m; // ≈ 20 % more load
    let f = step(el.as_ref(), un);
    let n = n0 + f[2];
    let expect_n = n0 * (1.0 + (1.0 - b) * 0.2).powf(1.0 / (1.0 - b));
    assert!((n - expect_n).abs() < 1e-12 * n0, "{n} vs {expect_n}");
    // A step of 1e-12 m from a virgin element: F ≈ E0(N)·Δq (to 1e-5, the secant's curvature).
    let expect_e0 = row.element.e0_n_per_m * (n / n0).powf(a);
    assert!(
        (f[0] / 1e-12 / expect_e0 - 1.0).abs() < 1e-5,
        "{} vs {expect_e0}",
        f[0] / 1e-12
    );
    // Refusals.
    let jenkins = contact.replace("law = \"valanis\"", "law = \"jenkins\"");
    std::fs::write(&model, format!("{head}{jenkins}{tail}")).unwrap();
    let e = load(&model).unwrap_err().to_string();
    assert!(
        e.contains("model.toml:13") && e.contains("load_following"),
        "{e}"
    );
    w(
        "elements.csv",
        &elements
            .replace(",pressure_Pa,", ",p_Pa,")
            .replace("# units", "# no pressure"),
    );
    std::fs::write(&model, format!("{head}{contact}{tail}")).unwrap();
    let e = load(&model).unwrap_err().to_string();
    assert!(
        e.contains("elements.csv:3") && e.contains("pressure_Pa"),
        "{e}"
    );
}
