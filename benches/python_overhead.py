#!/usr/bin/env python3
"""Python overhead on a normal solve: what the binding adds to the Rust solve.

Measured in one process on the reference surface (Rq 0.177 µm, cl 6.6 µm, 250 µm, seed 1,
default 1024²), cold (uniform-pressure start) load-controlled solves at 0.2, 2 and 10 MPa,
repeated. Per solve the overhead is

    (Surface built from a numpy array: copy + checks)
  + (wall time of NormalSolver.solve_load seen from Python − the solve's own wall_time_s,
     measured inside Rust around the solve: argument conversion, GIL release/re-acquire,
     result wrapping)
  + (handing out pressure, gap and displacement as numpy arrays)

and is reported relative to the solve's own time. NormalSolver set-up (FFT plan, kernel) is
Rust work that a Rust caller does too, so it is not counted. Prints a Markdown table.

Run (builds the package into a throwaway venv):
    python3 -m venv /tmp/asperity-py && /tmp/asperity-py/bin/pip install numpy ./python
    /tmp/asperity-py/bin/python benches/python_overhead.py [--grid 1024] [--repeats 3]
"""

import argparse
import os
import time

import numpy as np

import asperity as ap


def main():
    ap_ = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap_.add_argument("--grid", type=int, default=1024)
    ap_.add_argument("--repeats", type=int, default=3)
    args = ap_.parse_args()
    ref = ap.Surface.generate(nx=args.grid)
    heights = np.array(ref.heights)  # a user's own numpy array
    e_star = ap.composite_modulus(210e9, 0.3)
    print(f"load average {os.getloadavg()[0]:.2f}, RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'all')}")
    print("| grid | p̄ (MPa) | solve (Rust, s) | Surface copy (ms) | call overhead (ms) | arrays out (ms) | overhead / solve |")
    print("|---|---|---|---|---|---|---|")
    worst = 0.0
    for p in [0.2e6, 2e6, 10e6]:
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            surface = ap.Surface(heights, ref.dx_m, periodic=True)
            t1 = time.perf_counter()
            solver = ap.NormalSolver(surface, e_star_pa=e_star)
            t2 = time.perf_counter()
            sol = solver.solve_load(p)
            t3 = time.perf_counter()
            arrays = (sol.pressure, sol.gap, sol.displacement)
            t4 = time.perf_counter()
            assert all(a.shape == (args.grid, args.grid) for a in arrays)
            copy, call, out = t1 - t0, (t3 - t2) - sol.wall_time_s, t4 - t3
            ratio = (copy + call + out) / sol.wall_time_s
            worst = max(worst, ratio)
            print(f"| {args.grid}² | {p / 1e6:g} | {sol.wall_time_s:.3f} | {copy * 1e3:.2f} | {call * 1e3:.3f} "
                  f"| {out * 1e3:.3f} | {100 * ratio:.3f} % |")
    print(f"largest overhead: {100 * worst:.3f} % of the solve")


if __name__ == "__main__":
    main()
