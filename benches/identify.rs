//! Benchmark: cost of one model evaluation in identification (the harmonic balance at every
//! measured row of the Brake–Reuss beam's levels 1 and 4, 82 rows, warm-started along each
//! sweep), per joint family and effect, as single-thread CPU time (robust to other processes
//! sharing the machine) with the ratio to the Jenkins baseline; and, with
//! `ASPERITY_BENCH_FULL=1`, the wall time of the whole identification with the CLI's defaults.
//!
//! Run: `ASPERITY_DATA_DIR=../shared/data cargo bench --bench identify`. One model only:
//! `ASPERITY_BENCH_CASE=jenkins`; a fixed number of evaluations instead of 2 s of CPU time
//! (for instruction counts under `valgrind --tool=callgrind`, deterministic where CPU time on a
//! shared machine is not): `ASPERITY_BENCH_EVALS=25`.

use asperity::identify::effects::Effect;
use asperity::identify::fit::{LevelData, Objective};
use asperity::identify::measured::{PhaseConvention, Sweep};
use asperity::identify::model::{Family, Model, ModelSpec, Scales};
use asperity::identify::{identify, Options};
use std::time::Instant;

/// CPU time of the calling thread (s; `CLOCK_THREAD_CPUTIME_ID`, exact to the nanosecond
/// where /proc/thread-self/schedstat moves in scheduler ticks of several ms). With a one-thread
/// rayon pool every solve runs on that pool's thread, so this is the solve's CPU time, robust
/// to other processes sharing the machine.
fn thread_cpu_s() -> f64 {
    cpu_time::ThreadTime::now().as_duration().as_secs_f64()
}

fn main() {
    let dir = asperity::core::testdata::data_dir().join("frf");
    let read = |i: usize| {
        Sweep::read_csv(&dir.join(format!("brb-force-control-level{i}.csv"))).unwrap_or_else(|e| {
            eprintln!("{e} (set ASPERITY_DATA_DIR)");
            std::process::exit(1)
        })
    };
    let sweeps = vec![read(1), read(4)];
    let conv = PhaseConvention::detect(&sweeps).unwrap();
    let levels: Vec<LevelData> = sweeps.iter().map(|s| LevelData::new(s, &conv)).collect();
    let masks: Vec<Vec<bool>> = levels.iter().map(|l| vec![true; l.drives.len()]).collect();
    let scales = Scales {
        frequency_hz: 80.3,
        modal_mass_kg: 2.0,
        amplitude_max_m: 2.7e-4,
        amplitude_min_m: 7.8e-5,
        force_n: 1.46,
    };
    let base = |f| ModelSpec::baseline(f, scales);
    let cases = [
        ("jenkins", base(Family::Jenkins)),
        (
            "jenkins + amplitude_stiffness",
            base(Family::Jenkins).with(Effect::AmplitudeStiffness),
        ),
        (
            "jenkins + quadratic_stiffness",
            base(Family::Jenkins).with(Effect::QuadraticStiffness),
        ),
        (
            "jenkins + quadratic_damping",
            base(Family::Jenkins).with(Effect::QuadraticDamping),
        ),
        (
            "jenkins + power_law_damping",
            base(Family::Jenkins).with(Effect::PowerLawDamping),
        ),
        (
            "jenkins + higher_harmonics",
            base(Family::Jenkins).with(Effect::HigherHarmonics),
        ),
        ("valanis", base(Family::Valanis)),
        ("iwan (16 sliders)", base(Family::Iwan)),
    ];
    println!(
        "load average: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    println!(
        "{:<32} {:>14} {:>10}",
        "model", "CPU ms / eval", "× jenkins"
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut reference = f64::NAN;
    let only = std::env::var("ASPERITY_BENCH_CASE").ok();
    let fixed_evals: Option<usize> = std::env::var("ASPERITY_BENCH_EVALS").ok().map(|v| {
        v.parse().unwrap_or_else(|_| {
            eprintln!("ASPERITY_BENCH_EVALS={v}: expected a whole number of evaluations");
            std::process::exit(2)
        })
    });
    for (name, spec) in cases {
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let mut m = Model::neutral(spec.clone());
        // A joint slipping over part of the measured range: κ = 5 %, δ = 100 µm.
        m.values[3] = 0.05;
        m.values[4] = 1e-4;
        let obj = Objective::new(spec, &levels, &masks);
        let per = pool.install(|| {
            obj.cost_of(&m);
            // At least 2 s of CPU time (a shared machine's CPU time per evaluation scatters by
            // ±30 % over 0.5 s), or exactly the evaluations asked for.
            let (t0, mut n) = (thread_cpu_s(), 0);
            while fixed_evals.map_or(n < 5 || thread_cpu_s() - t0 < 2.0, |f| n < f) {
                obj.cost_of(&m);
                n += 1;
            }
            (thread_cpu_s() - t0) / n as f64
        });
        if reference.is_nan() {
            reference = per;
        }
        println!("{name:<32} {:>14.2} {:>10.1}", per * 1e3, per / reference);
    }
    if std::env::var("ASPERITY_BENCH_FULL").is_ok_and(|v| v == "1") {
        let all: Vec<Sweep> = (1..=4).map(read).collect();
        let t = Instant::now();
        let id = identify(all, &Options::new(Family::Jenkins), None).unwrap();
        println!(
            "full identification (CLI defaults, levels 1-4, fit 1 and 4): {:.1} s wall, {} \
             baseline evaluations, final effects {:?}",
            t.elapsed().as_secs_f64(),
            id.selection.baseline_train_fit.evaluations,
            id.after.model.spec.effects
        );
    }
}
