//! Model files of a bladed disk for the `[cyclic]` tests: one sector with its cyclic boundary
//! conditions and a Jenkins damper from the platform to the next sector's blade, and the full
//! assembly of the `N` sectors with a damper per sector under a standing engine-order forcing.

#![allow(dead_code, clippy::needless_range_loop)]

use std::path::{Path, PathBuf};

/// A bladed-disk sector (disk boundary nodes, platform, blade) as in tests/dynamics_cyclic.rs,
/// its matrices over the DOFs `dofs` (sector `j`'s DOF `i` at `index(j, i)`, `sectors` sectors
/// assembled; one sector with `index = i` when `sectors` is 1).
pub fn bladed_disk_matrices(
    sectors: usize,
    size: usize,
    index: &dyn Fn(usize, usize) -> usize,
) -> [Vec<Vec<f64>>; 3] {
    let mut k4 = [[0.0; 4]; 4];
    let mut spring = |a: usize, b: Option<usize>, kk: f64| {
        k4[a][a] += kk;
        if let Some(b) = b {
            k4[b][b] += kk;
            k4[a][b] -= kk;
            k4[b][a] -= kk;
        }
    };
    spring(0, Some(1), 4.0e6);
    spring(0, None, 0.5e6);
    spring(1, None, 0.5e6);
    spring(2, Some(0), 2.0e6);
    spring(2, Some(1), 2.0e6);
    spring(3, Some(2), 1.0e6);
    let m4 = [1.0, 1.0, 0.3, 0.5];
    let mut out = [
        vec![vec![0.0; size]; size],
        vec![vec![0.0; size]; size],
        vec![vec![0.0; size]; size],
    ];
    for j in 0..sectors {
        for a in 0..4 {
            let ga = index(j, a);
            out[0][ga][ga] += m4[a];
            for b in 0..4 {
                let gb = index(j, b);
                out[2][ga][gb] += k4[a][b];
                let m = if a == b { m4[a] } else { 0.0 };
                out[1][ga][gb] += 2.0e-5 * k4[a][b] + 5.0 * m;
            }
        }
    }
    out
}

pub fn write_matrices(dir: &Path, labels: &[String], m: &[Vec<Vec<f64>>; 3]) {
    for (name, unit, a) in [
        ("mass.csv", "kg", &m[0]),
        ("damping.csv", "N*s/m", &m[1]),
        ("stiffness.csv", "N/m", &m[2]),
    ] {
        let mut t = format!("# unit: {unit}\n{}\n", labels.join(","));
        for row in a {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
            t += &format!("{}\n", cells.join(","));
        }
        std::fs::write(dir.join(name), t).unwrap();
    }
}

/// Jenkins slider (E0 = 5e5 N/m, μ·N0 = 2 N) from a platform to the next sector's blade.
pub const DAMPER: &str = "# units: N0_N in N; kn, E0, Et in N/m\n\
id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n";

pub const SWEEP: &str = "[sweep]\nfrequency_start_hz = 120.0\nfrequency_end_hz = 260.0\npoints = 30\nharmonics = 3\nodd_only = true\n";

/// The sector model file with `[cyclic]` (N sectors, engine order `eo`).
pub fn write_sector_model(dir: &Path, sectors: usize, eo: usize) -> PathBuf {
    let labels: Vec<String> = ["disk_l.x", "disk_r.x", "platform.x", "blade.x"]
        .map(String::from)
        .to_vec();
    write_matrices(dir, &labels, &bladed_disk_matrices(1, 4, &|_, i| i));
    std::fs::write(
        dir.join("damper.csv"),
        format!("{DAMPER}1,0,0,1e-6,2e6,4.0,1e6,5.0e5,0.3,0.5,0,0\n"),
    )
    .unwrap();
    let model = format!(
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[cyclic]\nsectors = {sectors}\nengine_order = {eo}\nleft = [\"disk_l.x\"]\nright = [\"disk_r.x\"]\n\n\
[[contact]]\nelements = \"damper.csv\"\nlaw = \"jenkins\"\nnode_a = \"platform\"\nnode_b = \"next:blade\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [\"blade.x\"]\nlevels_n = [2.0, 20.0]\n\n\
[response]\ndofs = [\"blade.x\"]\n\n{SWEEP}"
    );
    std::fs::write(dir.join("model.toml"), model).unwrap();
    dir.join("model.toml")
}

/// The same `N` sectors assembled (boundary nodes merged) with a damper per sector and the
/// travelling-wave forcing of engine order `eo` on the blades (`phases_deg`).
pub fn write_full_model(dir: &Path, sectors: usize, eo: usize) -> PathBuf {
    let index = |j: usize, i: usize| match i {
        0 => 3 * j,
        1 => 3 * ((j + 1) % sectors),
        2 => 3 * j + 1,
        _ => 3 * j + 2,
    };
    let labels: Vec<String> = (0..sectors)
        .flat_map(|j| ["disk", "platform", "blade"].map(|d| format!("s{j}_{d}.x")))
        .collect();
    write_matrices(
        dir,
        &labels,
        &bladed_disk_matrices(sectors, 3 * sectors, &index),
    );
    let mut table = DAMPER.to_string();
    let mut pairs = "element_id,node_a,node_b\n".to_string();
    for j in 0..sectors {
        table += &format!("{},0,0,1e-6,2e6,4.0,1e6,5.0e5,0.3,0.5,0,0\n", j + 1);
        pairs += &format!("{},s{j}_platform,s{}_blade\n", j + 1, (j + 1) % sectors);
    }
    std::fs::write(dir.join("damper.csv"), table).unwrap();
    std::fs::write(dir.join("pairs.csv"), pairs).unwrap();
    let dofs: Vec<String> = (0..sectors).map(|j| format!("\"s{j}_blade.x\"")).collect();
    // The travelling wave F·cos(ωt + j·φ), φ = 360°·EO/N.
    let phases: Vec<String> = (0..sectors)
        .map(|j| format!("{:e}", 360.0 * (eo * j) as f64 / sectors as f64))
        .collect();
    let model = format!(
        "[linear]\nmass = \"mass.csv\"\ndamping = \"damping.csv\"\nstiffness = \"stiffness.csv\"\n\n\
[[contact]]\nelements = \"damper.csv\"\nlaw = \"jenkins\"\npairs = \"pairs.csv\"\n\
normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n\
[excitation]\ndofs = [{}]\nphases_deg = [{}]\nlevels_n = [2.0, 20.0]\n\n\
[response]\ndofs = [\"s0_blade.x\"]\n\n{SWEEP}",
        dofs.join(", "),
        phases.join(", ")
    );
    std::fs::write(dir.join("model.toml"), model).unwrap();
    dir.join("model.toml")
}
