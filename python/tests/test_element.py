"""The Valanis element and its fit from Python, against closed-form properties of the element
(not against our own numbers): initial slope E0, Coulomb limit μFz, reload slope 2E0/(1+k),
and recovery of known parameters by the fit."""

import numpy as np
import pytest

import asperity as ap


def test_arguments_follow_the_rust_constructor():
    # ValanisParams::new(e0, k, et, mu): positional arguments in the same order.
    p = ap.ValanisParams(1e12, 0.4, 1e10, 0.6)
    assert (p.e0, p.k, p.et, p.mu) == (1e12, 0.4, 1e10, 0.6)
    assert p == ap.ValanisParams(e0=1e12, k=0.4, et=1e10, mu=0.6)


def test_virgin_loading_slope_and_coulomb_limit():
    p = ap.ValanisParams(e0=2e12, k=0.4, et=0.0, mu=0.5)
    fz = 3e6
    q = np.linspace(0.0, 40 * p.mu * fz / p.e0, 4001)  # far into gross slip
    f = ap.valanis_integrate(p, q, fz, method="reference")
    assert f[0] == 0.0
    q0 = np.array([0.0, 1e-5 * p.mu * fz / p.e0])
    f0 = ap.valanis_integrate(p, q0, fz, method="reference")
    assert f0[1] / q0[1] == pytest.approx(p.e0, rel=1e-4)  # dF/dq = E0 at x = 0
    assert f[-1] == pytest.approx(p.mu * fz, rel=1e-6)  # asymptote μFz for Et = 0
    assert np.all(np.diff(f) >= 0) and np.all(f < p.mu * fz * (1 + 1e-12))


def test_reload_slope_after_gross_slip():
    p = ap.ValanisParams(e0=1e12, k=0.6, et=0.0, mu=0.6)
    fz, qmax = 1e6, 30 * 0.6 * 1e6 / 1e12
    n = 20001
    q = np.concatenate([np.linspace(0, qmax, n), qmax - np.linspace(0, 1e-3 * qmax, 101)[1:]])
    f = ap.valanis_integrate(p, q, np.full(q.shape, fz), method="reference")
    slope = (f[n] - f[n - 1]) / (q[n] - q[n - 1])
    assert slope == pytest.approx(p.reload_slope, rel=2e-3)
    assert p.reload_slope == 2 * p.e0 / (1 + p.k)


def test_fit_recovers_known_parameters():
    truth = ap.ValanisParams(e0=3e12, k=0.35, et=0.0, mu=0.6)
    fz = 2e6
    q = ap.sine_history(2.5 * truth.mu * fz / truth.e0, 2, 60)
    f = ap.valanis_integrate(truth, q, fz, method="reference")
    fit = ap.fit_valanis(q, f, fz, (60, 121), mu=0.6)
    assert fit.r2 > 1 - 1e-9
    assert fit.params.e0 == pytest.approx(truth.e0, rel=1e-4)
    assert fit.params.k == pytest.approx(truth.k, abs=1e-4)
    assert fit.model_force.shape == f.shape
    assert fit.energy_rel_error == pytest.approx(0.0, abs=1e-6)
    e = ap.dissipated_energy(q[60:121], f[60:121])
    assert e == pytest.approx(fit.energy_data, rel=1e-12) and e > 0


def test_normal_load_history_clips_at_separation():
    fz = ap.normal_load_history(10.0, 1e3, np.array([0.0, -0.02, 0.01]))
    assert list(fz) == [10.0, 0.0, 20.0]
