"""Side by side with tamaas 2.9 (PolonskyKeerRey, pressure control) on the same surface, from
Python: contact area ratio and mean gap within 1e-6 relative. Conventions as in
benches/peers/tamaas_compare.py: tamaas model E = E*, ν = 0 (its hertz modulus equals E*),
periodic kernel 2/(E*|q|) in both; tamaas' mean gap is mean(u − h).

Prints the numbers (pytest -s) that docs/python.md and BENCHMARKS.md record.
"""

import numpy as np
import pytest

import asperity as ap

tm = pytest.importorskip("tamaas")

E_STAR = ap.composite_modulus(210e9, 0.3)


@pytest.mark.parametrize("n, seed", [(256, 1), (256, 2)])
def test_area_and_mean_gap_match_tamaas(n, seed):
    s = ap.Surface.generate(nx=n, seed=seed)
    h = s.heights - s.heights.mean()
    tm.set_log_level(tm.LogLevel.error)
    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, list(s.size_m), list(s.shape))
    model.E = E_STAR
    model.nu = 0.0
    pk = tm.PolonskyKeerRey(model, np.ascontiguousarray(h), 1e-12)
    solver = ap.NormalSolver(s, e_star_pa=E_STAR, tolerance=1e-12)
    for p in [0.2e6, 2e6, 10e6]:
        model.traction[...] = 0.0
        model.displacement[...] = 0.0
        pk.solve(p)
        trac = np.array(model.traction)
        disp = np.array(model.displacement)
        area_tm = float((trac > 0).mean())
        gap_tm = float((disp - h).mean())
        sol = solver.solve_load(p)
        print(f"tamaas side-by-side: {n}² seed {seed} p={p:.1e} Pa: area ratio asperity "
              f"{sol.contact_area_ratio:.9e} tamaas {area_tm:.9e}; mean gap asperity "
              f"{sol.mean_gap_m:.9e} m tamaas {gap_tm:.9e} m; "
              f"rel. diff {sol.contact_area_ratio / area_tm - 1:+.2e}, {sol.mean_gap_m / gap_tm - 1:+.2e}")
        assert sol.contact_area_ratio == pytest.approx(area_tm, rel=1e-6)
        assert sol.mean_gap_m == pytest.approx(gap_tm, rel=1e-6)
