use asperity::dynamics::aft::{self, AftSettings, Harmonics};
use asperity::dynamics::iwan::Iwan;
use asperity::element::iwan::IwanParams;
use std::time::Instant;
fn main() {
    let h = Harmonics::new(3, true, None).unwrap();
    let hf = Harmonics::new(3, true, Some(4096)).unwrap();
    for chi in [-0.5, -0.1, 0.0] {
        let p = IwanParams::new(1.0, 1e4, chi, 0.5).unwrap();
        for n in [8, 12, 16, 24] {
            let iw = Iwan::new(p, n).unwrap();
            let mut s = format!("chi {chi} n={n}:");
            for frac in [0.05, 0.1, 0.2, 0.5, 0.9] {
                let a = frac * p.phi_max();
                let c = aft::cycle_summary(&iw, &hf, &[a, 0.0, 0.0, 0.0], &AftSettings::default());
                s += &format!(
                    " {frac}:{:+.1}%",
                    100.0 * (c.dissipated_energy_j / p.dissipation_per_cycle(a) - 1.0)
                );
            }
            let t = Instant::now();
            for _ in 0..100 {
                aft::evaluate(
                    &iw,
                    &h,
                    &[0.3 * p.phi_max(), 0.0, 0.0, 0.0],
                    true,
                    &AftSettings::default(),
                );
            }
            println!(
                "{s}  time {:.0} us",
                t.elapsed().as_secs_f64() / 100.0 * 1e6
            );
        }
    }
}
