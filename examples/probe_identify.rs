use asperity::identify::{backbone, fit::*, measured::*, model::*};
use std::time::Instant;
fn main() {
    let dir = std::path::PathBuf::from("/work/shared/data/frf");
    let sweeps: Vec<Sweep> = (1..=4)
        .map(|i| Sweep::read_csv(&dir.join(format!("brb-force-control-level{i}.csv"))).unwrap())
        .collect();
    let conv = PhaseConvention::detect(&sweeps).unwrap();
    println!("{}", conv.describe());
    let frfs: Vec<_> = sweeps.iter().map(|s| s.frf(&conv)).collect();
    let bb = backbone::from_data(&sweeps, &frfs).unwrap();
    for b in &bb {
        println!(
            "{} F={:.3} lin f={:.3} z={:.5} m={:.3} rms={:.3} Apk={:.3e}",
            b.file,
            b.mean_force_n,
            b.linear.frequency_hz,
            b.linear.damping_ratio,
            b.linear.modal_mass_kg,
            b.linear.relative_rms,
            b.peak_amplitude_m
        );
        for p in &b.points {
            println!(
                "   A={:.3e} f={:.3} z={:.5}",
                p.amplitude_m, p.frequency_hz, p.damping_ratio
            );
        }
    }
    let scales = Scales {
        frequency_hz: 80.3,
        modal_mass_kg: bb[0].linear.modal_mass_kg,
        amplitude_max_m: bb[3].peak_amplitude_m,
        amplitude_min_m: bb[0].peak_amplitude_m,
        force_n: sweeps[3].mean_force_n(),
    };
    let levels: Vec<LevelData> = [0usize, 3]
        .iter()
        .map(|&i| LevelData::new(&sweeps[i], &conv))
        .collect();
    let masks: Vec<Vec<bool>> = levels.iter().map(|l| vec![true; l.drives.len()]).collect();
    let fam = match std::env::args().nth(1).as_deref() { Some("valanis") => Family::Valanis, Some("iwan") => Family::Iwan, _ => Family::Jenkins };
    let mut spec = ModelSpec::baseline(fam, scales);
    if let Some(list) = std::env::args().nth(2) {
        for e in list.split(',') {
            spec = spec.with(asperity::identify::effects::Effect::from_id(e).unwrap());
        }
    }
    let m = Model::neutral(spec.clone());
    let obj = Objective::new(spec.clone(), &levels, &masks, None);
    let t = Instant::now();
    for _ in 0..20 {
        obj.cost_of(&m);
    }
    println!("eval {:.3} ms", t.elapsed().as_secs_f64() / 20.0 * 1e3);
    let opts = FitOptions::default();
    let t = Instant::now();
    let r = fit_global(&spec, &levels, &masks, &opts, None).unwrap();
    println!(
        "fit {:.1}s cost {:.4e} conv {} evals {} failed {} bounds {:?}",
        t.elapsed().as_secs_f64(),
        r.cost,
        r.converged,
        r.evaluations,
        r.failed_rows,
        r.at_bounds
    );
    for s in &r.starts {
        println!("  {:?}", s);
    }
    for (p, v) in spec.params().iter().zip(&r.model.values) {
        println!("  {} = {:.5e} {}", p.name, v, p.unit);
    }
    let all: Vec<LevelData> = sweeps.iter().map(|s| LevelData::new(s, &conv)).collect();
    for l in &all {
        let (y, _) = l.model_frf(&r.model).unwrap();
        let f: Vec<f64> = l
            .drives
            .iter()
            .map(|d| d.omega / std::f64::consts::TAU)
            .collect();
        let (fm, pm) =
            backbone::resonance(&f, &l.measured.iter().map(|v| v.norm()).collect::<Vec<_>>());
        let (fp, pp) = backbone::resonance(&f, &y.iter().map(|v| v.norm()).collect::<Vec<_>>());
        let rms =
            (l.residuals(&y).iter().map(|r| r.norm_sqr()).sum::<f64>() / y.len() as f64).sqrt();
        println!(
            "{}: meas {:.3} Hz {:.2}  model {:.3} Hz {:.2}  dF {:.3} Hz peak err {:.1}% rms {:.3}",
            l.name,
            fm,
            pm,
            fp,
            pp,
            fp - fm,
            100.0 * (pp / pm - 1.0),
            rms
        );
    }
}
