#!/usr/bin/env python3
"""Jenkins friction cases (SDOF, and a 2-DOF chain) by pyHarm (pyharm-os), for comparison with asperity.

Run with the throwaway venv of benches/peers/setup_pyharm.sh:

    /tmp/asperity-pyharm-venv/bin/python benches/peers/pyharm_jenkins.py CASE.json OUT.json

CASE.json: m_kg, k_N_per_m, c_N_s_per_m (one entry per mass: mass, spring and dashpot to ground),
k12_N_per_m, c12_N_s_per_m (spring and dashpot between masses 1 and 2, when there are two),
kt_N_per_m, slip_force_N (the Jenkins element: to ground from mass 1 for one mass, between masses 1
and 2 for two), force_N (cos ωt on mass 1), f_start_Hz, f_end_Hz, h_max (harmonics 0..h_max),
n_time (samples per period), ds_max (pyHarm's arclength step cap). Amplitudes are of mass 1.
OUT.json: frequency_Hz and first-harmonic amplitude_m of every point, the peak, wall and CPU time
of the analysis (Maestro construction and JIT compilation excluded as far as pyHarm separates
them: the analysis is run twice and the second run is timed).
Units: SI.
"""
import json
import sys
import time

import numpy as np
from pyHarm.Maestro import Maestro


def build(case):
    sub = "chain"
    n = len(case["m_kg"])
    node = lambda i: {sub: [i]}
    pair = {sub: [0], "INTERNAL": [1]}
    con = {}
    for i in range(n):
        con[f"mass{i}"] = {"type": "GOElement", "connect": node(i), "dirs": [0], "dto": 2, "xo": 1, "k": case["m_kg"][i]}
        con[f"spring{i}"] = {"type": "LinearSpring", "connect": node(i), "dirs": [0], "k": case["k_N_per_m"][i]}
        if case["c_N_s_per_m"][i] > 0:
            con[f"damper{i}"] = {"type": "LinearDamper", "connect": node(i), "dirs": [0], "k": case["c_N_s_per_m"][i]}
    if n == 2:
        con["spring12"] = {"type": "LinearSpring", "connect": dict(pair), "dirs": [0], "k": case["k12_N_per_m"]}
        con["damper12"] = {"type": "LinearDamper", "connect": dict(pair), "dirs": [0], "k": case["c12_N_s_per_m"]}
    con["jenkins"] = {"type": "Jenkins", "connect": dict(pair) if n == 2 else node(0), "dirs": [0],
                      "mu": 1.0, "N0": case["slip_force_N"], "k": case["kt_N_per_m"]}
    con["force"] = {"type": "CosinusForcing", "connect": node(0), "dirs": [0], "amp": case["force_N"]}
    return {
        "system": {"type": "Base", "nh": case["h_max"], "nti": case["n_time"]},
        "substructures": {sub: {"type": "onlydofs", "nnodes": n, "ndofs": 1}},
        "connectors": con,
        "analysis": {
            "FRF": {"study": "frf", "puls_inf": 2 * np.pi * case["f_start_Hz"],
                    "puls_sup": 2 * np.pi * case["f_end_Hz"], "ds_max": case["ds_max"],
                    "ds0": case["ds_max"], "verbose": False},
        },
    }


def main(case_path, out_path):
    with open(case_path) as f:
        case = json.load(f)
    result = None
    for run in range(2):
        m = Maestro(build(case))
        t0, c0 = time.perf_counter(), time.process_time()
        m.operate()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        sols = [s for s in m.nls["FRF"].SolList if s.flag_accepted]
        freq, amp = [], []
        nh = case["h_max"]
        for s in sols:
            x = np.asarray(s.x)
            om = x[-1]
            # pyHarm's layout: harmonic-major [a0 (all dofs), a1 (all dofs), b1 (all dofs), ...].
            nd = len(case["m_kg"])
            freq.append(om / (2 * np.pi))
            amp.append(float(np.hypot(x[nd], x[2 * nd])))
        i = int(np.argmax(amp))
        result = {"frequency_Hz": freq, "amplitude_m": amp, "peak_frequency_Hz": freq[i],
                  "peak_amplitude_m": amp[i], "points": len(freq), "wall_s": wall, "cpu_s": cpu,
                  "run": run}
    with open(out_path, "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
