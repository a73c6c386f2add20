//! Cyclic symmetry against the full structure: one sector with travelling-wave boundary
//! conditions ([`asperity::dynamics::cyclic`]) gives the same forced response as the `N` sectors
//! assembled into one lumped model (boundary DOFs merged) and solved by the ordinary harmonic
//! balance under the travelling-wave forcing `F_j(t) = F·cos(ωt + j·φ)`, `φ = 2π·EO/N`, for a
//! linear sector (to 1e-8) and with Jenkins friction dampers between neighbouring sectors and
//! inside the sector (to 1e-6), at engine orders from 0 (standing, in phase) through N/2
//! (standing, alternate sectors opposite) and travelling ones between.

#[path = "support/cyclic_models.rs"]
mod cyclic_models;

use asperity::dynamics::aft::Harmonics;
use asperity::dynamics::cyclic::shift_operator;
use asperity::dynamics::hbm::{Excitation, FormulationChoice, HbmSystem, NewtonSettings};
use asperity::dynamics::model::Structure;
use asperity::dynamics::model_file;
use asperity::element::jenkins::Jenkins;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::TAU;
use std::sync::Arc;

/// Sector DOFs: the disk's left and right boundary nodes, a platform and a blade tip.
const LABELS: [&str; 4] = ["disk_l.x", "disk_r.x", "platform.x", "blade.x"];
const LEFT: usize = 0;
const RIGHT: usize = 1;
const PLATFORM: usize = 2;
const BLADE: usize = 3;

/// A bladed-disk sector as lumped springs and masses: a disk segment between its boundary nodes
/// (mass and ground stiffness split half to each, so the assembly gives each disk node the
/// whole), a platform on both disk nodes and a blade on the platform; Rayleigh damping.
fn sector_matrices() -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let (m_disk, k_disk, k_ground) = (2.0, 4.0e6, 1.0e6);
    let (m_plat, k_plat) = (0.3, 2.0e6);
    let (m_blade, k_blade) = (0.5, 1.0e6);
    let mut k = DMatrix::zeros(4, 4);
    let mut spring = |a: usize, b: Option<usize>, kk: f64| {
        k[(a, a)] += kk;
        if let Some(b) = b {
            k[(b, b)] += kk;
            k[(a, b)] -= kk;
            k[(b, a)] -= kk;
        }
    };
    spring(LEFT, Some(RIGHT), k_disk);
    spring(LEFT, None, 0.5 * k_ground);
    spring(RIGHT, None, 0.5 * k_ground);
    spring(PLATFORM, Some(LEFT), k_plat);
    spring(PLATFORM, Some(RIGHT), k_plat);
    spring(BLADE, Some(PLATFORM), k_blade);
    let m = DMatrix::from_diagonal(&DVector::from_vec(vec![
        0.5 * m_disk,
        0.5 * m_disk,
        m_plat,
        m_blade,
    ]));
    let c = &k * 2.0e-5 + &m * 5.0;
    (m, c, k)
}

/// Friction dampers: a Jenkins slider between a platform and the next sector's blade (not
/// symmetric, so that the next sector cannot pass for the previous one) and one between blade
/// and platform inside the sector (`None`: a linear sector).
#[derive(Clone, Copy)]
struct Dampers {
    across_kt: f64,
    across_slip_n: f64,
    inside_kt: f64,
    inside_slip_n: f64,
}

fn jenkins(kt: f64, slip: f64) -> Arc<Jenkins> {
    Arc::new(Jenkins::new(kt, slip).unwrap())
}

/// The sector with its cyclic boundary conditions and elements.
fn sector(sectors: usize, eo: usize, dampers: Option<Dampers>) -> Structure {
    let (m, c, k) = sector_matrices();
    let labels = LABELS.iter().map(|s| s.to_string()).collect();
    let mut s = Structure::lumped(labels, m, c, k).unwrap();
    s.make_cyclic(sectors, eo, vec![LEFT], vec![RIGHT]).unwrap();
    if let Some(d) = dampers {
        let mut own = DMatrix::zeros(1, 4);
        own[(0, PLATFORM)] = 1.0;
        let mut next = DMatrix::zeros(1, 4);
        next[(0, BLADE)] = -1.0;
        s.attach_across("damper", jenkins(d.across_kt, d.across_slip_n), own, next)
            .unwrap();
        let mut inside = DMatrix::zeros(1, 4);
        inside[(0, BLADE)] = 1.0;
        inside[(0, PLATFORM)] = -1.0;
        s.attach("root", jenkins(d.inside_kt, d.inside_slip_n), inside)
            .unwrap();
    }
    s
}

/// Full-structure index of sector `j`'s DOF `i`: three DOFs per sector (disk node, platform,
/// blade); a sector's right disk node is the next sector's left one.
fn global(sectors: usize, j: usize, i: usize) -> usize {
    match i {
        LEFT => 3 * j,
        RIGHT => 3 * ((j + 1) % sectors),
        PLATFORM => 3 * j + 1,
        _ => 3 * j + 2,
    }
}

/// The `N` sectors assembled into one lumped structure, elements on every sector.
fn full(sectors: usize, dampers: Option<Dampers>) -> Structure {
    let (ms, cs, ks) = sector_matrices();
    let n = 3 * sectors;
    let (mut m, mut c, mut k) = (
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
        DMatrix::zeros(n, n),
    );
    for j in 0..sectors {
        for a in 0..4 {
            for b in 0..4 {
                let (ga, gb) = (global(sectors, j, a), global(sectors, j, b));
                m[(ga, gb)] += ms[(a, b)];
                c[(ga, gb)] += cs[(a, b)];
                k[(ga, gb)] += ks[(a, b)];
            }
        }
    }
    let labels = (0..sectors)
        .flat_map(|j| ["disk", "platform", "blade"].map(|d| format!("s{j}_{d}.x")))
        .collect();
    let mut s = Structure::lumped(labels, m, c, k).unwrap();
    if let Some(d) = dampers {
        for j in 0..sectors {
            let mut p = DMatrix::zeros(1, n);
            p[(0, global(sectors, j, PLATFORM))] = 1.0;
            p[(0, global(sectors, (j + 1) % sectors, BLADE))] = -1.0;
            s.attach(
                format!("damper {j}"),
                jenkins(d.across_kt, d.across_slip_n),
                p,
            )
            .unwrap();
            let mut p = DMatrix::zeros(1, n);
            p[(0, global(sectors, j, BLADE))] = 1.0;
            p[(0, global(sectors, j, PLATFORM))] = -1.0;
            s.attach(
                format!("root {j}"),
                jenkins(d.inside_kt, d.inside_slip_n),
                p,
            )
            .unwrap();
        }
    }
    s
}

/// Travelling-wave forcing of the full structure: `F·cos(ωt + j·φ)` on every blade, i.e.
/// `F cos jφ` in phase and `−F sin jφ` in quadrature.
fn travelling_wave(sectors: usize, eo: usize, force: f64) -> Excitation {
    let n = 3 * sectors;
    let phi = TAU * eo as f64 / sectors as f64;
    let (mut fc, mut fs) = (DVector::zeros(n), DVector::zeros(n));
    for j in 0..sectors {
        let b = global(sectors, j, BLADE);
        fc[b] = force * (j as f64 * phi).cos();
        fs[b] = -force * (j as f64 * phi).sin();
    }
    Excitation {
        force: fc,
        harmonic: 1,
        force_sin: Some(fs),
    }
}

fn blade_force(force: f64) -> Excitation {
    let mut f = DVector::zeros(4);
    f[BLADE] = force;
    Excitation {
        force: f,
        harmonic: 1,
        force_sin: None,
    }
}

/// Lowest natural frequency (rad/s) of the full undamped structure among the modes whose blades
/// move as a wave of harmonic index `k` (most of the blades' discrete Fourier content at `k`).
fn cyclic_frequency(sectors: usize, k: usize) -> f64 {
    let s = full(sectors, None);
    let l = s.mass.clone().cholesky().unwrap().l();
    let li = l.clone().try_inverse().unwrap();
    let a = &li * &s.stiffness * li.transpose();
    let e = a.symmetric_eigen();
    // The mode whose shape is a wave of index k: sector-to-sector correlation.
    let mut best = f64::INFINITY;
    for (i, &lam) in e.eigenvalues.iter().enumerate() {
        let v = li.transpose() * e.eigenvectors.column(i);
        // Discrete Fourier content of the blade DOFs at index k.
        let (mut re, mut im, mut tot) = (0.0, 0.0, 0.0);
        for j in 0..sectors {
            let x = v[global(sectors, j, BLADE)];
            let a = TAU * (k * j) as f64 / sectors as f64;
            re += x * a.cos();
            im += x * a.sin();
            tot += x * x;
        }
        if (re * re + im * im) > 0.4 * sectors as f64 * tot && lam.sqrt() < best {
            best = lam.sqrt();
        }
    }
    best
}

struct Comparison {
    /// Largest difference between the sector's harmonics and sector 0 of the full solution,
    /// relative to the largest harmonic.
    sector_error: f64,
    /// Largest difference between sector 2 of the full solution and the time-shifted sector 0.
    wave_error: f64,
    /// The blade's first-harmonic amplitude at each frequency (m).
    blade: Vec<f64>,
}

/// Solve sector and full structure at frequencies across the index's first resonance (Newton,
/// warm-started along the frequencies) and compare every DOF's harmonics.
fn compare(sectors: usize, eo: usize, dampers: Option<Dampers>, force: f64) -> Comparison {
    // Samples per period a multiple of N: sector j of the full structure is sector 0 shifted by
    // j·EO/N of a period, a whole number of samples, so the full structure's AFT is cyclically
    // symmetric too (with 64 samples and N = 5 its sectors differ by the AFT's sampling error,
    // some 1e-3 of the response in slip).
    let harmonics = Harmonics::new(3, false, Some(16 * sectors)).unwrap();
    let len = harmonics.len();
    let s_sector = sector(sectors, eo, dampers);
    let s_full = full(sectors, dampers);
    let newton = NewtonSettings {
        tolerance: 1e-11,
        max_iterations: 60,
    };
    let mut sys_s = HbmSystem::new(
        &s_sector,
        harmonics.clone(),
        blade_force(force),
        FormulationChoice::Auto,
    )
    .unwrap();
    sys_s.newton = newton;
    assert_eq!(
        sys_s.unknowns(),
        3 * len,
        "sector unknowns: all but the right boundary"
    );
    let mut sys_f = HbmSystem::new(
        &s_full,
        harmonics.clone(),
        travelling_wave(sectors, eo, force),
        FormulationChoice::Coordinates,
    )
    .unwrap();
    sys_f.newton = newton;
    let k = sys_s.cyclic().unwrap().harmonic_index(1);
    let w0 = cyclic_frequency(sectors, k);
    assert!(w0.is_finite(), "no mode of index {k}");
    let phi = TAU * eo as f64 / sectors as f64;
    let shift = |j: usize| shift_operator(&harmonics, j as f64 * phi);
    let (mut gs, mut gf) = (None::<DVector<f64>>, None::<DVector<f64>>);
    let mut out = Comparison {
        sector_error: 0.0,
        wave_error: 0.0,
        blade: Vec::new(),
    };
    for i in 0..=12 {
        let w = w0 * (0.85 + 0.3 * i as f64 / 12.0);
        let ps = sys_s.solve(w, 1.0, gs.as_ref()).unwrap();
        let pf = sys_f.solve(w, 1.0, gf.as_ref()).unwrap();
        let qs = sys_s.coordinates(&ps);
        let qf = sys_f.coordinates(&pf);
        let scale = qf.amax();
        for (i_sec, _) in LABELS.iter().enumerate() {
            for h in 0..len {
                let d = (qs[i_sec * len + h] - qf[global(sectors, 0, i_sec) * len + h]).abs();
                out.sector_error = out.sector_error.max(d / scale);
            }
        }
        // Sector 2 of the full solution is sector 0 advanced by 2φ/ω.
        let j = 2 % sectors;
        let s2 = shift(j);
        for i_sec in [LEFT, PLATFORM, BLADE] {
            let x0 = DVector::from_fn(len, |h, _| qf[global(sectors, 0, i_sec) * len + h]);
            let xj = &s2 * x0;
            for h in 0..len {
                let d = (xj[h] - qf[global(sectors, j, i_sec) * len + h]).abs();
                out.wave_error = out.wave_error.max(d / scale);
            }
        }
        let (ci, si) = harmonics.index_of(1).unwrap();
        out.blade
            .push(qs[BLADE * len + ci].hypot(qs[BLADE * len + si]));
        gs = Some(ps.z);
        gf = Some(pf.z);
    }
    out
}

#[test]
fn linear_sector_equals_the_full_assembly_at_every_engine_order() {
    for (sectors, eo) in [(6, 0), (6, 1), (6, 2), (6, 3), (5, 2), (3, 1)] {
        let c = compare(sectors, eo, None, 10.0);
        assert!(
            c.sector_error < 1e-8 && c.wave_error < 1e-8,
            "N = {sectors}, EO = {eo}: sector vs full {:.2e}, travelling wave {:.2e}",
            c.sector_error,
            c.wave_error
        );
        assert!(c.blade.iter().all(|a| *a > 0.0));
    }
}

#[test]
fn friction_dampers_between_sectors_match_the_full_assembly() {
    let dampers = Dampers {
        across_kt: 5.0e5,
        across_slip_n: 2.0,
        inside_kt: 3.0e5,
        inside_slip_n: 3.0,
    };
    // The same sliders never slipping (slip forces far above any element force).
    let stuck = Dampers {
        across_slip_n: 1e9,
        inside_slip_n: 1e9,
        ..dampers
    };
    for (sectors, eo) in [(4, 1), (6, 3), (6, 0), (5, 2)] {
        let c = compare(sectors, eo, Some(dampers), 10.0);
        assert!(
            c.sector_error < 1e-6 && c.wave_error < 1e-6,
            "N = {sectors}, EO = {eo}: sector vs full {:.2e}, travelling wave {:.2e}",
            c.sector_error,
            c.wave_error
        );
        // The dampers slip: the response is far from the stuck structure's (measured: by 0.39
        // (EO = 0) to 10.6 times the stuck one's largest amplitude in the band, whose resonance
        // the stuck dampers move out of it).
        let linear = compare(sectors, eo, Some(stuck), 10.0);
        let scale = linear.blade.iter().fold(0.0f64, |m, a| m.max(*a));
        let change = c
            .blade
            .iter()
            .zip(&linear.blade)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs() / scale));
        assert!(
            change > 0.1,
            "N = {sectors}, EO = {eo}: the response with slip differs from the stuck one by {change:.3}"
        );
    }
}

/// The sector's Jacobian with an element across the boundary is exact: it matches central
/// differences of the residual at a point in partial slip (Jenkins forces are piecewise linear
/// in the displacement, so the differences are exact up to rounding away from a slip onset).
#[test]
fn sector_jacobian_matches_central_differences() {
    let dampers = Dampers {
        across_kt: 5.0e5,
        across_slip_n: 2.0,
        inside_kt: 3.0e5,
        inside_slip_n: 3.0,
    };
    let (sectors, eo) = (5, 2);
    let s = sector(sectors, eo, Some(dampers));
    let harmonics = Harmonics::new(3, false, Some(80)).unwrap();
    let sys = HbmSystem::new(&s, harmonics, blade_force(10.0), FormulationChoice::Auto).unwrap();
    let w = cyclic_frequency(sectors, sys.cyclic().unwrap().harmonic_index(1));
    let p = sys.solve(w, 1.0, None).unwrap();
    let z = &p.z * 1.1;
    let ev = sys.evaluate(&z, w, 1.0, true);
    let dz =
        DVector::from_fn(z.len(), |i, _| ((i * 7919) % 13) as f64 / 13.0 - 0.5) * (z.amax() * 1e-6);
    let plus = sys.evaluate(&(&z + &dz), w, 1.0, false).residual;
    let minus = sys.evaluate(&(&z - &dz), w, 1.0, false).residual;
    let fd = (plus - minus) / 2.0;
    let exact = &ev.jacobian * &dz;
    let err = (&fd - &exact).amax() / exact.amax();
    assert!(err < 1e-6, "Jacobian vs central differences: {err:.2e}");
    // And the derivative in frequency.
    let dw = w * 1e-7;
    let fd_w = (sys.evaluate(&z, w + dw, 1.0, false).residual
        - sys.evaluate(&z, w - dw, 1.0, false).residual)
        / (2.0 * dw);
    let err_w = (&fd_w - &ev.d_omega).amax() / ev.d_omega.amax();
    assert!(err_w < 1e-6, "∂R/∂ω vs central differences: {err_w:.2e}");
}

/// The model file's `[cyclic]` section and `next:` contact nodes build the same problem as the
/// full assembly's model file (its travelling-wave forcing by `phases_deg`): the sector's
/// solution equals sector 0 of the full one at frequencies across the resonance, in partial
/// slip, at engine orders 0, 1 and 2 of 4.
#[test]
fn model_files_of_sector_and_full_assembly_give_the_same_solution() {
    for eo in [0, 1, 2] {
        sector_and_full_model_files_agree(eo, false);
    }
}

/// As [`model_files_of_sector_and_full_assembly_give_the_same_solution`] with the dampers as
/// thin-layer `[[joint]]`s (same stick stiffness 5e5 N/m and yield force 2 N as the Jenkins
/// dampers, 10 % hardening) from each platform to the next sector's blade (`next:blade`).
#[test]
fn joints_across_the_sector_boundary_match_the_full_assembly() {
    for eo in [0, 1, 2] {
        sector_and_full_model_files_agree(eo, true);
    }
}

/// A thin-layer joint block from `a` to `b` along x.
fn thin_layer_joint(a: &str, b: &str) -> String {
    format!(
        "[[joint]]\nlaw = \"thin-layer\"\nnode_a = \"{a}\"\nnode_b = \"{b}\"\n\
         direction = [1.0, 0.0, 0.0]\nelastic_modulus_pa = 5e5\nplastic_modulus_pa = 5e4\n\
         yield_stress_pa = 2e4\ntransition_exponent = 2.0\narea_m2 = 1e-4\nthickness_m = 1e-4\n\n"
    )
}

/// Replace the `[[contact]]` block of a model file by `joints`.
fn contacts_to_joints(model: &std::path::Path, joints: &str) {
    let text = std::fs::read_to_string(model).unwrap();
    let a = text.find("[[contact]]").unwrap();
    let b = a + text[a..].find("[excitation]").unwrap();
    std::fs::write(model, format!("{}{joints}{}", &text[..a], &text[b..])).unwrap();
}

fn sector_and_full_model_files_agree(eo: usize, joints: bool) {
    let sectors = 4;
    {
        let dir = tempfile::tempdir().unwrap();
        let (ds, df) = (dir.path().join("sector"), dir.path().join("full"));
        std::fs::create_dir_all(&ds).unwrap();
        std::fs::create_dir_all(&df).unwrap();
        let (ps, pf) = (
            cyclic_models::write_sector_model(&ds, sectors, eo),
            cyclic_models::write_full_model(&df, sectors, eo),
        );
        if joints {
            contacts_to_joints(&ps, &thin_layer_joint("platform", "next:blade"));
            let full: String = (0..sectors)
                .map(|j| {
                    thin_layer_joint(
                        &format!("s{j}_platform"),
                        &format!("s{}_blade", (j + 1) % sectors),
                    )
                })
                .collect();
            contacts_to_joints(&pf, &full);
        }
        let ms = model_file::load(&ps).unwrap();
        let mf = model_file::load(&pf).unwrap();
        assert!(ms.structure.cyclic.is_some() && ms.structure.has_elements_across());
        assert_eq!(mf.structure.elements.len(), sectors);
        let h = Harmonics::new(3, true, Some(64)).unwrap();
        let system = |m: &model_file::LoadedModel| {
            let excitation = Excitation {
                force: m.force.clone(),
                harmonic: 1,
                force_sin: m.force_sin.clone(),
            };
            (m.structure.clone(), excitation)
        };
        let ((ss, es), (sf, ef)) = (system(&ms), system(&mf));
        let mut sys_s = HbmSystem::new(&ss, h.clone(), es, FormulationChoice::Coordinates).unwrap();
        let mut sys_f = HbmSystem::new(&sf, h.clone(), ef, FormulationChoice::Coordinates).unwrap();
        for s in [&mut sys_s, &mut sys_f] {
            s.newton = NewtonSettings {
                tolerance: 1e-11,
                max_iterations: 100,
            };
        }
        let len = h.len();
        let (mut gs, mut gf) = (None::<DVector<f64>>, None::<DVector<f64>>);
        let mut slipped = false;
        for f in [200.0, 220.0, 230.0, 236.0, 238.0, 240.0, 250.0] {
            let w = f * TAU;
            let ps = sys_s.solve(w, 2.0, gs.as_ref()).unwrap();
            let pf = sys_f.solve(w, 2.0, gf.as_ref()).unwrap();
            let (qs, qf) = (sys_s.coordinates(&ps), sys_f.coordinates(&pf));
            // Sector DOFs disk_l, disk_r, platform, blade; full: s0_disk, s1_disk, s0_platform,
            // s0_blade.
            let scale = qf.amax();
            for (i, g) in [(0, 0), (1, 3), (2, 1), (3, 2)] {
                for k in 0..len {
                    let d = (qs[i * len + k] - qf[g * len + k]).abs() / scale;
                    assert!(
                        d < 1e-10,
                        "EO = {eo}, {f} Hz: DOF {i} harmonic {k}: {d:.2e}"
                    );
                }
            }
            // The damper leaves its linear range: the contact slips, the layer yields (its
            // force beyond the 2 N yield force).
            slipped |= if joints {
                let c = &sys_s.element_cycles(&ps)[0];
                c.dissipated_energy_j > 0.0
                    && sys_s.element_samples(&ps)[0]
                        .f
                        .iter()
                        .any(|f| f.abs() > 2.0)
            } else {
                sys_s.element_cycles(&ps)[0].slip_fraction > 0.0
            };
            gs = Some(ps.z);
            gf = Some(pf.z);
        }
        assert!(slipped, "EO = {eo}: the damper never slips");
    }
}
