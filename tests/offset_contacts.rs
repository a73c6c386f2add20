//! Contact elements at their own points on rotating nodes (`[nodes]`, `film_origin_m`, DOFs
//! `node.rx|ry|rz`): a rigid block rocking on its contact patch against the closed-form
//! stiffness of springs at offset points.

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem};
use asperity::dynamics::model_file::load;
use nalgebra::{Complex, DMatrix, DVector};
use std::f64::consts::PI;

const M: f64 = 0.2; // kg
const J: f64 = 4e-5; // kg·m² about y
const H: f64 = 0.01; // m: height of the block's node above the contact plane
const KT: f64 = 3e6; // N/m: Jenkins tangential stiffness per element
const KN: f64 = 5e6; // N/m: normal stiffness per element
const N0: f64 = 50.0; // N: preload per element
                      // Element positions in the film frame (m).
const POINTS: [(f64, f64); 4] = [
    (-0.004, -0.002),
    (0.006, -0.002),
    (-0.004, 0.003),
    (0.006, 0.003),
];

/// The block (DOFs x, z, ry at the origin) on four Jenkins contacts to ground at
/// `(x_i, ·, −H)`: the model file, and `(K, M, C)` of the block's own springs.
fn write_model(dir: &std::path::Path, offset: bool, positions: bool) -> std::path::PathBuf {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    w(
        "mass.csv",
        &format!("# unit: kg\nb.x,b.z,b.ry\n{M},0,0\n0,{M},0\n0,0,{J}\n"),
    );
    w(
        "damping.csv",
        "# unit: N*s/m\nb.x,b.z,b.ry\n2.0,0,0\n0,2.0,0\n0,0,1e-4\n",
    );
    w(
        "stiffness.csv",
        "# unit: N/m\nb.x,b.z,b.ry\n1e5,0,0\n0,1e5,0\n0,0,10.0\n",
    );
    let mut e = String::from(
        "# units: as asperity elements\nid,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n",
    );
    for (i, (x, y)) in POINTS.iter().enumerate() {
        e += &format!("{},{x},{y},1e-6,1e6,{N0},{KN},{KT},0.5,0.6,0,0\n", i + 1);
    }
    w("elements.csv", &e);
    let origin = if offset {
        format!("film_origin_m = [0.0, 0.0, {}]\n", -H)
    } else {
        String::new()
    };
    let nodes = if positions {
        "\n[nodes]\nb = [0.0, 0.0, 0.0]\n"
    } else {
        ""
    };
    let model = format!(
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
         [[contact]]\nelements = \"elements.csv\"\nlaw = \"jenkins\"\nnode_a = \"b\"\nnode_b = \"ground\"\n\
         normal = [0.0, 0.0, -1.0]\ntangent = [1.0, 0.0, 0.0]\n{origin}{nodes}\n\
         [excitation]\ndofs = [\"b.x\", \"b.ry\"]\nweights = [1.0, 0.02]\nlevels_n = [1.0]\n\n\
         [response]\ndofs = [\"b.x\"]\n\n\
         [sweep]\nfrequency_start_hz = 100.0\nfrequency_end_hz = 200.0\nharmonics = 3\nodd_only = false\n"
    );
    let path = dir.join("model.toml");
    std::fs::write(&path, model).unwrap();
    path
}

/// Stuck Jenkins contacts are linear springs, so the harmonic balance's first harmonic is the
/// receptance of the block with the contact stiffness written by hand from the geometry: at the
/// point `(x_i, ·, −H)` a rotation `ry` moves the contact by `u_x = −H·ry` (tangential) and
/// `u_z = −x_i·ry` (normal), so `K_c = Σ KT·aᵀa + KN·bᵀb` with `a = (1, 0, −H)`,
/// `b = (0, 1, −x_i)` over `(x, z, ry)`. Within 1e-9; without `film_origin_m` the elements act
/// at the node and the rotation decouples (`a = (1, 0, 0)`, `b = (0, 1, 0)`).
#[test]
fn block_rocking_on_offset_contacts_matches_the_hand_written_stiffness() {
    let dir = tempfile::tempdir().unwrap();
    for offset in [true, false] {
        let model = write_model(dir.path(), offset, true);
        let loaded = load(&model).unwrap();
        let s = &loaded.structure;
        assert_eq!(s.n(), 3);
        let h = Harmonics::new(3, false, Some(64)).unwrap();
        let sys = HbmSystem::new(
            s,
            h,
            Excitation {
                force: loaded.force.clone(),
                harmonic: 1,
                force_sin: None,
            },
            FormulationChoice::Coordinates,
        )
        .unwrap();
        let mut kc = DMatrix::<f64>::zeros(3, 3);
        for (x, _) in POINTS {
            let (hh, xi) = if offset { (H, x) } else { (0.0, 0.0) };
            let a = DVector::from_column_slice(&[1.0, 0.0, -hh]);
            let b = DVector::from_column_slice(&[0.0, 1.0, -xi]);
            kc += KT * &a * a.transpose() + KN * &b * b.transpose();
        }
        let k = DMatrix::from_diagonal(&DVector::from_column_slice(&[1e5, 1e5, 10.0])) + kc;
        let m = DMatrix::from_diagonal(&DVector::from_column_slice(&[M, M, J]));
        let c = DMatrix::from_diagonal(&DVector::from_column_slice(&[2.0, 2.0, 1e-4]));
        for f_hz in [300.0, 900.0, 1500.0] {
            let w = 2.0 * PI * f_hz;
            // A level that keeps every contact stuck (|F_t| ≪ μ·N0).
            let level = 5.0;
            let p = sys.solve(w, level, None).unwrap();
            assert!(p.converged);
            let xh = sys.coordinates(&p);
            let (ci, si) = sys.harmonics.index_of(1).unwrap();
            let dyn_ = k.map(Complex::from) - (m.clone() * w * w).map(Complex::from)
                + c.map(|v| Complex::new(0.0, w * v));
            let f = DVector::from_iterator(
                3,
                [1.0, 0.0, 0.02]
                    .iter()
                    .map(|v| Complex::new(level * v, 0.0)),
            );
            let x = dyn_.lu().solve(&f).unwrap();
            let scale = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for d in 0..3 {
                let n = sys.harmonics.len();
                // x = a·cos + b·sin ↔ X = a − i·b.
                let got = Complex::new(xh[d * n + ci], -xh[d * n + si]);
                assert!(
                    (got - x[d]).norm() < 1e-9 * scale,
                    "offset {offset}, {f_hz} Hz, DOF {d}: {got} vs {}",
                    x[d]
                );
            }
        }
    }
    // A rotating node under offset elements needs its position.
    let model = write_model(dir.path(), true, false);
    let e = load(&model).unwrap_err().to_string();
    assert!(e.contains("elements.csv:3") && e.contains("[nodes]"), "{e}");
}

/// Several contact frames on one interface (a node-pair file with each element's own
/// `normal_*`, `tangent_*`): a block in a V-groove of faces inclined at ±α. With stuck Jenkins
/// contacts the block's stiffness is, by hand, `k_x = Σ (KN·sin²α + KT·cos²α)`,
/// `k_z = Σ (KN·cos²α + KT·sin²α)`, uncoupled by symmetry; the harmonic balance's first harmonic
/// is that receptance within 1e-9. A frame column that is not a number is refused with the line.
#[test]
fn v_groove_with_a_frame_per_element_matches_the_hand_written_stiffness() {
    let dir = tempfile::tempdir().unwrap();
    let w = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    w("mass.csv", &format!("# unit: kg\nb.x,b.z\n{M},0\n0,{M}\n"));
    w("damping.csv", "# unit: N*s/m\nb.x,b.z\n2.0,0\n0,2.0\n");
    w("stiffness.csv", "# unit: N/m\nb.x,b.z\n1e5,0\n0,1e5\n");
    let mut e = String::from(
        "id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n",
    );
    for i in 1..=4 {
        e += &format!("{i},0,0,1e-6,1e6,{N0},{KN},{KT},0.5,0.6,0,0\n");
    }
    w("elements.csv", &e);
    let alpha: f64 = 0.5; // rad
    let (sa, ca) = alpha.sin_cos();
    // Elements 1, 2 on the left face (normal from the block into the face: (−sin α, 0, −cos α)),
    // 3, 4 on the right face ((sin α, 0, −cos α)); tangents along each face.
    let mut pairs = String::from(
        "element_id,node_a,node_b,normal_x,normal_y,normal_z,tangent_x,tangent_y,tangent_z\n",
    );
    for (i, s) in [(1, -1.0), (2, -1.0), (3, 1.0), (4, 1.0)] {
        pairs += &format!("{i},b,ground,{},0,{},{},0,{}\n", s * sa, -ca, ca, s * sa);
    }
    w("pairs.csv", &pairs);
    let model = dir.path().join("model.toml");
    std::fs::write(
        &model,
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
         [[contact]]\nelements = \"elements.csv\"\nlaw = \"jenkins\"\npairs = \"pairs.csv\"\n\
         normal = [0.0, 0.0, -1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
         [excitation]\ndofs = [\"b.x\", \"b.z\"]\nweights = [1.0, 0.5]\nlevels_n = [1.0]\n\n\
         [response]\ndofs = [\"b.x\"]\n\n\
         [sweep]\nfrequency_start_hz = 100.0\nfrequency_end_hz = 200.0\nharmonics = 3\nodd_only = false\n",
    )
    .unwrap();
    let loaded = load(&model).unwrap();
    let sys = HbmSystem::new(
        &loaded.structure,
        Harmonics::new(3, false, Some(64)).unwrap(),
        Excitation {
            force: loaded.force.clone(),
            harmonic: 1,
            force_sin: None,
        },
        FormulationChoice::Coordinates,
    )
    .unwrap();
    let kx = 1e5 + 4.0 * (KN * sa * sa + KT * ca * ca);
    let kz = 1e5 + 4.0 * (KN * ca * ca + KT * sa * sa);
    for f_hz in [500.0, 1500.0] {
        let wv = 2.0 * PI * f_hz;
        let level = 5.0;
        let p = sys.solve(wv, level, None).unwrap();
        assert!(p.converged);
        let xh = sys.coordinates(&p);
        let (ci, si) = sys.harmonics.index_of(1).unwrap();
        let n = sys.harmonics.len();
        for (d, k, f) in [(0, kx, level), (1, kz, 0.5 * level)] {
            let exact = Complex::new(f, 0.0) / Complex::new(k - M * wv * wv, 2.0 * wv);
            let got = Complex::new(xh[d * n + ci], -xh[d * n + si]);
            assert!(
                (got - exact).norm() < 1e-9 * exact.norm(),
                "{f_hz} Hz, DOF {d}: {got} vs {exact}"
            );
        }
    }
    w(
        "pairs.csv",
        &pairs.replace(&format!("3,b,ground,{sa}"), "3,b,ground,oops"),
    );
    let e = load(&model).unwrap_err().to_string();
    assert!(e.contains("pairs.csv:4") && e.contains("normal_x"), "{e}");
}
