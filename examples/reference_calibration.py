#!/usr/bin/env python3
# %% [markdown]
# # The reference calibration from Python
#
# This notebook-style script (cells marked `# %%`, runnable as a script or in Jupyter/VS Code)
# rebuilds, with the `asperity` Python package, the calibration table that
# `cargo run --release -- calibrate` writes to `calib/calibration_table.csv` and that the
# docs/calibrate.md shows: per realisation (reference statistics, seeds 1, 2, ...) the surface →
# warm-started normal sweep (kn = dp̄/dδ, tangent problem) → per pressure one history of increasing tangential
# amplitudes (0.2 … 1.5 × the gross-slip displacement, 40 steps per cycle, μ = 0.6; the steady
# loop of each amplitude from one half cycle and its point reflection) → one Valanis element
# fitted to all amplitudes together (E0, k; Et = 0); then per pressure the mean over the
# realisations and the half-width of its 95 % Student-t interval.
#
#     python examples/reference_calibration.py              # the reference case: 1024², 8 realisations (many minutes)
#     python examples/reference_calibration.py --grid 256   # a quick look (seconds), NOT the reference numbers of docs/calibrate.md
#
# The same library code runs, composed here in Python: python/tests/test_example.py checks that
# the table equals `asperity calibrate --grid 128` value for value. The CLI also runs the grid
# and patch-size convergence checks, which add only the table's last column (`convergence`, the
# verdict per row); this script does not run them. Units: SI.

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
AMPLITUDE_FACTORS = [0.2, 0.4, 0.7, 1.0, 1.5]  # loop amplitudes / gross-slip displacement
STEPS_PER_CYCLE = 40
TANGENTIAL_TOLERANCE = 1e-4
REALISATIONS = 8  # seeds 1 … 8
E_STAR = ap.composite_modulus(210e9, 0.3)  # steel on steel: E* = 115.4 GPa


def mean_and_interval(values):
    """Mean and half-width of the 95 % Student-t interval of the mean (NaN for one value),
    summed in order as the library does."""
    n = len(values)
    total = 0.0
    for v in values:
        total += v
    mean = total / n
    if n < 2:
        return mean, math.nan
    ss = 0.0
    for v in values:
        ss += (v - mean) * (v - mean)
    sd = math.sqrt(ss / (n - 1))
    return mean, ap.student_t_975(n - 1) * sd / math.sqrt(n)


def realisation(grid, seed, log):
    """One surface through the chain: per pressure (area ratio, kn, fit, energy per cycle at
    the largest amplitude)."""
    # %% 1. A rough surface of the reference statistics: Rq 0.177 µm, cl 6.6 µm, 250 µm.
    surface = ap.Surface.generate(nx=grid, seed=seed)

    # %% 2. Normal sweep, warm-started load after load; kn = dp̄/dδ from the tangent problem on
    #       the contact set (one linear solve per pressure).
    solver = ap.NormalSolver(surface, e_star_pa=E_STAR, tolerance=1e-10)
    results = []
    warm = None
    for p in PRESSURES_PA:
        sol = solver.solve_load(p, warm_start=warm)
        kn = solver.contact_stiffness(sol)
        warm = sol

        # %% 3. Loops at every amplitude from one history, and one element fitted to them all.
        t = ap.TangentialSolver(sol, friction_coefficient=MU, tolerance=TANGENTIAL_TOLERANCE)
        history = t.amplitude_loops(AMPLITUDE_FACTORS, STEPS_PER_CYCLE)
        loops = history.loops
        fit = ap.fit_valanis_loops(
            [(l.fit_q, l.fit_force, p, l.steady) for l in loops], mu=MU
        )
        errors = ", ".join(f"{100 * e.energy_rel_error:+.0f} %" for e in fit.loops)
        log(f"  seed {seed}, {p / 1e6:5.1f} MPa: area ratio {sol.contact_area_ratio:.3e}, kn {kn:.3e} N/m³, "
            f"E0 {fit.params.e0:.3e} N/m³, k {fit.params.k:.3f}, mean R² {fit.r2:.4f}; energy error per amplitude: {errors}")
        results.append((sol.contact_area_ratio, kn, fit, loops[-1].loop_area_j_per_m2))
    return results


def calibrate(grid=1024, realisations=REALISATIONS, log=print):
    """The calibration on `realisations` surfaces at `grid`² points; returns the table as
    columns named like calibration_table.csv."""
    runs = [realisation(grid, 1 + r, log) for r in range(realisations)]
    rows = {c: [] for c in ["pressure_Pa", "contact_area_ratio", "kn_N_per_m3", "E0_N_per_m3", "k",
                            "mu", "Et_N_per_m3", "fit_R2", "energy_per_cycle_J_per_m2"]}
    intervals = {c: [] for c in ["realisations", "contact_area_ratio_ci95", "kn_ci95_N_per_m3",
                                 "E0_ci95_N_per_m3", "k_ci95", "Et_ci95_N_per_m3",
                                 "energy_per_cycle_ci95_J_per_m2"]}
    for i, p in enumerate(PRESSURES_PA):
        # %% 4. Mean and 95 % interval over the realisations.
        def stat(f):
            return mean_and_interval([f(run[i]) for run in runs])

        area, kn, e0, k = (stat(lambda x: x[0]), stat(lambda x: x[1]),
                           stat(lambda x: x[2].params.e0), stat(lambda x: x[2].params.k))
        et, energy = stat(lambda x: x[2].params.et), stat(lambda x: x[3])
        for c, v in [("pressure_Pa", p), ("contact_area_ratio", area[0]), ("kn_N_per_m3", kn[0]),
                     ("E0_N_per_m3", e0[0]), ("k", k[0]), ("mu", MU), ("Et_N_per_m3", et[0]),
                     ("fit_R2", stat(lambda x: x[2].r2)[0]), ("energy_per_cycle_J_per_m2", energy[0])]:
            rows[c].append(v)
        for c, v in zip(intervals, [float(realisations), area[1], kn[1], e0[1], k[1], et[1], energy[1]]):
            intervals[c].append(v)
    if realisations >= 2:
        rows.update(intervals)
    return {c: np.array(v) for c, v in rows.items()}


# %%
def main():
    parser = argparse.ArgumentParser(description="The reference calibration table from Python.")
    parser.add_argument("--grid", type=int, default=1024,
                        help="points per side (1024: the reference case of docs/calibrate.md; 256: a quick look)")
    parser.add_argument("--realisations", type=int, default=REALISATIONS,
                        help="number of surfaces (seeds 1, 2, ...)")
    parser.add_argument("--compare", type=Path, default=REPO / "calib" / "calibration_table.csv",
                        help="table to compare with at 1024² (the reference numbers of docs/calibrate.md)")
    args = parser.parse_args()
    t0 = time.perf_counter()
    table = calibrate(args.grid, args.realisations)
    print(f"\ncalibration table ({args.grid}², {args.realisations} realisations, {time.perf_counter() - t0:.1f} s):")
    print("| p (MPa) | area ratio | kn (N/m³) | E0 (N/m³) | k | mean fit R² |")
    print("|---|---|---|---|---|---|")
    ci = (lambda c, i: f" ± {table[c][i]:.1e}") if "kn_ci95_N_per_m3" in table else (lambda c, i: "")
    for i, p in enumerate(table["pressure_Pa"]):
        print(f"| {p / 1e6:g} | {table['contact_area_ratio'][i]:.1e} | {table['kn_N_per_m3'][i]:.2e}{ci('kn_ci95_N_per_m3', i)} | "
              f"{table['E0_N_per_m3'][i]:.2e}{ci('E0_ci95_N_per_m3', i)} | {table['k'][i]:.3f}{ci('k_ci95', i)} | {table['fit_R2'][i]:.4f} |")

    # %% The table in use: element parameters at an arbitrary pressure (monotone cubic in ln p).
    if args.grid != 1024 or args.realisations != REALISATIONS:
        print("\n(coarse grid: a quick look, not the reference numbers of docs/calibrate.md)")
        return 0
    reference = ap.CalibrationTable.read_csv(args.compare)
    ref = reference.columns()
    worst = max(float(np.max(np.abs(table[c] / ref[c] - 1.0), initial=0.0))
                for c in ["contact_area_ratio", "kn_N_per_m3", "E0_N_per_m3", "k", "fit_R2", "energy_per_cycle_J_per_m2"])
    same = all(np.array_equal(table[c], ref[c]) for c in ref)
    print(f"\nagainst {args.compare}: {'identical, bit for bit' if same else f'largest relative difference {worst:.2e}'}")
    at = reference.interpolate(3e6)
    print(f"at 3 MPa: kn {at.kn_n_per_m3:.3e} N/m³, E0 {at.e0_n_per_m3:.3e} N/m³, k {at.k:.3f}")
    return 0 if same or worst < 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())
