#!/usr/bin/env python3
# %% [markdown]
# # The reference calibration from Python
#
# This notebook-style script (cells marked `# %%`, runnable as a script or in Jupyter/VS Code)
# rebuilds, with the `asperity` Python package, the calibration table that
# `cargo run --release -- calibrate` writes to `calib/calibration_table.csv` and that the
# README shows: reference surface → warm-started normal sweep (kn = −dp̄/dḡ) → tangential
# hysteresis loop per pressure (virgin quarter cycle + one steady cycle at 1.5 × the gross-slip
# displacement, 40 steps per cycle, μ = 0.6) → Valanis fit (E0, k; Et = 0) → table.
#
#     python examples/reference_calibration.py              # the reference case, 1024² (about a minute on 2 cores)
#     python examples/reference_calibration.py --grid 256   # a quick look (seconds), NOT the README's numbers
#
# At 1024² the numbers are compared with calib/calibration_table.csv (the README's table): they
# agree to 2.1e-11 relative, and bit for bit with a fresh `asperity calibrate` run (the same
# library code runs, composed here in Python; the committed table predates a change of summation
# order in the tangential solver). A coarser grid changes the surface discretisation and hence
# the numbers (contact spots are under-resolved at 256²). Units: SI.

# %%
import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

import asperity as ap

REPO = Path(__file__).resolve().parents[1]
PRESSURES_PA = [0.1e6, 0.2e6, 1e6, 2e6, 5e6, 10e6]  # the reference sweep
MU = 0.6  # friction coefficient (BEM slip limit, held fixed in the fit)
AMPLITUDE_FACTOR = 1.5  # loop amplitude / gross-slip displacement
STEPS_PER_CYCLE = 40
DERIVATIVE_STEP = 0.02  # kn by central difference at p(1 ± ε)
E_STAR = ap.composite_modulus(210e9, 0.3)  # steel on steel: E* = 115.4 GPa


def sine(k, n):
    """sin(2πk/n) with exact zeros and ±1 at the quarter periods (cycles close exactly)."""
    if (2 * k) % n == 0:
        return 0.0
    if (4 * k) % n == 0:
        return 1.0 if (4 * k // n) % 4 == 1 else -1.0
    return math.sin(2.0 * math.pi * k / n)


def calibrate(grid=1024, log=print):
    """The calibration chain on the reference surface at `grid`² points; returns the table as
    columns named like calibration_table.csv."""
    # %% 1. The reference rough surface: Rq 0.177 µm, 1/e correlation length 6.6 µm, 250 µm.
    surface = ap.Surface.generate(nx=grid)
    st = surface.stats()
    log(f"surface {grid}²: Rq = {st['rq_m'] * 1e6:.4f} µm, correlation length (1/e) = "
        f"{st['correlation_length_1_over_e_m'] * 1e6:.2f} µm, rms slope = {st['rms_slope']:.3f}")

    # %% 2. Normal sweep, warm-started load after load; kn by a central difference.
    solver = ap.NormalSolver(surface, e_star_pa=E_STAR, tolerance=1e-10)
    solutions, kn = [], []
    warm = None
    for p in PRESSURES_PA:
        sol = solver.solve_load(p, warm_start=warm)
        lo = solver.solve_load(p * (1.0 - DERIVATIVE_STEP), warm_start=sol)
        hi = solver.solve_load(p * (1.0 + DERIVATIVE_STEP), warm_start=sol)
        kn.append(-2.0 * DERIVATIVE_STEP * p / (hi.mean_gap_m - lo.mean_gap_m))
        solutions.append(sol)
        warm = sol
        log(f"  normal {p / 1e6:5.1f} MPa: area ratio {sol.contact_area_ratio:.3e}, mean gap "
            f"{sol.mean_gap_m * 1e6:.4f} µm, kn {kn[-1]:.3e} N/m³ ({sol.iterations} iterations)")

    # %% 3. One hysteresis loop per pressure: virgin quarter cycle + one steady cycle.
    n = STEPS_PER_CYCLE
    steady = (n // 4, n // 4 + n + 1)
    rows = {c: [] for c in ["pressure_Pa", "contact_area_ratio", "kn_N_per_m3", "E0_N_per_m3", "k",
                            "mu", "Et_N_per_m3", "fit_R2", "energy_per_cycle_J_per_m2"]}
    for p, sol, kn_p in zip(PRESSURES_PA, solutions, kn):
        t = ap.TangentialSolver(sol, friction_coefficient=MU, tolerance=1e-8)
        amplitude = AMPLITUDE_FACTOR * t.gross_slip_displacement((1.0, 0.0))
        t.reset()
        q, tau = [0.0], [0.0]
        for k in range(1, n + n // 4 + 1):
            step = t.step(displacement_m=(amplitude * sine(k, n), 0.0))
            q.append(step["shift_m"][0])
            tau.append(step["mean_shear_pa"][0])
        q, tau = np.array(q), np.array(tau)
        energy = ap.dissipated_energy(q[steady[0]:steady[1]], tau[steady[0]:steady[1]])

        # %% 4. Valanis fit of the loop (μ fixed, Et = 0), three starts of k.
        fit = ap.fit_valanis(q, tau, p, steady, mu=MU)
        for c, v in [("pressure_Pa", p), ("contact_area_ratio", sol.contact_area_ratio), ("kn_N_per_m3", kn_p),
                     ("E0_N_per_m3", fit.params.e0), ("k", fit.params.k), ("mu", MU),
                     ("Et_N_per_m3", fit.params.et), ("fit_R2", fit.r2), ("energy_per_cycle_J_per_m2", energy)]:
            rows[c].append(v)
        log(f"  loop {p / 1e6:5.1f} MPa: amplitude {amplitude * 1e9:.2f} nm, E0 {fit.params.e0:.3e} N/m³, "
            f"k {fit.params.k:.3f}, R² {fit.r2:.4f}, energy/cycle {energy:.3e} J/m²")
    return {c: np.array(v) for c, v in rows.items()}


# %%
def main():
    parser = argparse.ArgumentParser(description="The reference calibration table from Python.")
    parser.add_argument("--grid", type=int, default=1024,
                        help="points per side (1024: the reference case of the README; 256: a quick look)")
    parser.add_argument("--compare", type=Path, default=REPO / "calib" / "calibration_table.csv",
                        help="table to compare with at 1024² (the README's reference numbers)")
    args = parser.parse_args()
    t0 = time.perf_counter()
    table = calibrate(args.grid)
    print(f"\ncalibration table ({args.grid}², {time.perf_counter() - t0:.1f} s):")
    print("| p (MPa) | area ratio | kn (N/m³) | E0 (N/m³) | k | fit R² |")
    print("|---|---|---|---|---|---|")
    for i, p in enumerate(table["pressure_Pa"]):
        print(f"| {p / 1e6:g} | {table['contact_area_ratio'][i]:.1e} | {table['kn_N_per_m3'][i]:.2e} | "
              f"{table['E0_N_per_m3'][i]:.2e} | {table['k'][i]:.3f} | {table['fit_R2'][i]:.4f} |")

    # %% The table in use: element parameters at an arbitrary pressure (monotone cubic in ln p).
    if args.grid != 1024:
        print("\n(coarse grid: a quick look, not the README's reference numbers)")
        return 0
    reference = ap.CalibrationTable.read_csv(args.compare)
    ref = reference.columns()
    worst = max(float(np.max(np.abs(table[c] / ref[c] - 1.0), initial=0.0))
                for c in ["contact_area_ratio", "kn_N_per_m3", "E0_N_per_m3", "fit_R2", "energy_per_cycle_J_per_m2"])
    same = all(np.array_equal(table[c], ref[c]) for c in ref)
    print(f"\nagainst {args.compare}: {'identical, bit for bit' if same else f'largest relative difference {worst:.2e}'}")
    at = reference.interpolate(3e6)
    print(f"at 3 MPa: kn {at['kn_N_per_m3']:.3e} N/m³, E0 {at['E0_N_per_m3']:.3e} N/m³, k {at['k']:.3f}")
    return 0 if same or worst < 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())
