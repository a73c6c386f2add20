use asperity::identify::{effects::Effect, fit::*, measured::*, model::*};
use std::time::Instant;
fn main() {
    let dir = std::path::PathBuf::from("/work/shared/data/frf");
    let sweeps: Vec<Sweep> = [1, 4]
        .iter()
        .map(|i| Sweep::read_csv(&dir.join(format!("brb-force-control-level{i}.csv"))).unwrap())
        .collect();
    let conv = PhaseConvention::detect(&sweeps).unwrap();
    let scales = Scales {
        frequency_hz: 80.3,
        modal_mass_kg: 2.0,
        amplitude_max_m: 2.7e-4,
        amplitude_min_m: 7.8e-5,
        force_n: 1.46,
    };
    let levels: Vec<LevelData> = sweeps.iter().map(|s| LevelData::new(s, &conv)).collect();
    let masks: Vec<Vec<bool>> = levels.iter().map(|l| vec![true; l.drives.len()]).collect();
    for (name, spec) in [
        ("jenkins", ModelSpec::baseline(Family::Jenkins, scales)),
        (
            "jenkins+quad",
            ModelSpec::baseline(Family::Jenkins, scales).with(Effect::QuadraticDamping),
        ),
        (
            "jenkins+cubic",
            ModelSpec::baseline(Family::Jenkins, scales).with(Effect::AmplitudeStiffness),
        ),
        ("valanis", ModelSpec::baseline(Family::Valanis, scales)),
        ("iwan", ModelSpec::baseline(Family::Iwan, scales)),
    ] {
        let mut m = Model::neutral(spec.clone());
        m.values[3] = 0.05;
        m.values[4] = 1e-4;
        let obj = Objective::new(spec.clone(), &levels, &masks, None);
        let t = Instant::now();
        let n = 10;
        let mut c = 0.0;
        for _ in 0..n {
            c = obj.cost_of(&m).0;
        }
        println!(
            "{name}: {:.2} ms per evaluation (82 rows), cost {c:.4e}",
            t.elapsed().as_secs_f64() / n as f64 * 1e3
        );
    }
}
