"""Loops from accelerations in Python: `read_record` takes the relative acceleration across the
joint and a mass's acceleration (F = m·a) as `asperity diagnose` does, says how it derived the
columns, and names a missing partner argument."""

import numpy as np
import pytest

import asperity as ap


def write_record(path):
    """A drive with a third harmonic over 4 whole periods of 2 Hz (non-commensurate sampling is
    the library's own test); the force a 2.5 kg mass's inertia."""
    t = np.linspace(0.0, 2.0, 2001)
    w = 2 * np.pi * 2.0
    x = 3e-5 * np.sin(w * t) + 4e-6 * np.sin(3 * w * t + 0.4)
    a = -3e-5 * w**2 * np.sin(w * t) - 9 * 4e-6 * w**2 * np.sin(3 * w * t + 0.4)
    f = 1.7 * np.cos(w * t) + 0.2 * np.sin(3 * w * t)
    a_mass = f / 2.5
    rows = "\n".join(
        f"{ti:.17g},{xi:.17g},{fi:.17g},{ai:.17g},{ami:.17g}" for ti, xi, fi, ai, ami in zip(t, x, f, a, a_mass)
    )
    path.write_text(
        "time_s,displacement_m,friction_force_N,a_rel_m_per_s2,a_mass_m_per_s2\n" + rows + "\n"
    )
    return x, f


def test_accelerations_give_the_displacement_and_force(tmp_path):
    path = tmp_path / "record.csv"
    x, f = write_record(path)
    plain = ap.read_record(path)
    assert plain.derived == []
    r = ap.read_record(
        path,
        relative_acceleration_column="a_rel_m_per_s2",
        inertia_acceleration_column="a_mass_m_per_s2",
        mass_kg=2.5,
    )
    # Double integration on the record's harmonics: exact up to the mean, which an
    # acceleration cannot hold (the displacement here has none).
    np.testing.assert_allclose(r.displacement_m, x, atol=1e-9 * np.abs(x).max())
    np.testing.assert_allclose(r.force_n, f, rtol=1e-12, atol=1e-12)
    assert len(r.derived) == 2
    assert any("a_rel_m_per_s2" in d for d in r.derived)
    assert any("a_mass_m_per_s2" in d for d in r.derived)


def test_an_acceleration_without_its_partner_is_named(tmp_path):
    path = tmp_path / "record.csv"
    write_record(path)
    with pytest.raises(Exception, match="mass_kg"):
        ap.read_record(path, inertia_acceleration_column="a_mass_m_per_s2")
    with pytest.raises(Exception, match="inertia_acceleration_column"):
        ap.read_record(path, mass_kg=2.5)
