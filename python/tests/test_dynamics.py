"""Forced response from Python: the model file of `asperity response` and the same model built
from numpy arrays give the CLI's response_level_<i>.csv exactly (compared after the CLI's own
formatting), and bad input raises named exceptions."""

import csv

import numpy as np
import pytest

import asperity as ap

ELEMENTS = (
    "# units: N0_N in N; kn, E0, Et in N/m\n"
    "id,x_m,y_m,area_m2,pressure_Pa,N0_N,kn_N_per_m,E0_N_per_m,k,mu,Et_N_per_m,out_of_range\n"
    "7,0,0,1e-6,2e6,2.0,1e6,2.0e4,0.3,0.5,0,0\n"
    "11,0,0,1e-6,2e6,1.0,1e6,1.0e4,0.5,0.5,0,0\n"
)
MASS = np.array([[1.0, 0.0], [0.0, 0.5]])
STIFFNESS = np.array([[6e4, -2e4], [-2e4, 2e4]])
DAMPING = np.array([[2.0, 0.0], [0.0, 1.0]])


def write_model(d):
    """Two masses (m1 on a ground spring, m2 on m1); two Valanis contacts join m2 to ground."""
    (d / "mass.csv").write_text("# unit: kg\nm1.x,m2.x\n1.0,0\n0,0.5\n")
    (d / "stiffness.csv").write_text("# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-2e4,2e4\n")
    (d / "damping.csv").write_text("# unit: N*s/m\nm1.x,m2.x\n2,0\n0,1\n")
    (d / "elements.csv").write_text(ELEMENTS)
    (d / "pairs.csv").write_text("element_id,node_a,node_b\n7,m2,ground\n11,m2,ground\n")
    (d / "model.toml").write_text(
        '[linear]\nmass = "mass.csv"\ndamping = "damping.csv"\nstiffness = "stiffness.csv"\n\n'
        '[[contact]]\nelements = "elements.csv"\nlaw = "valanis"\npairs = "pairs.csv"\n'
        "normal = [0.0, 0.0, 1.0]\ntangent = [1.0, 0.0, 0.0]\n\n"
        '[excitation]\ndofs = ["m1.x"]\nlevels_n = [0.02, 0.5]\n\n'
        '[response]\ndofs = ["m1.x", "m2.x"]\n\n'
        "[sweep]\nfrequency_start_hz = 15.0\nfrequency_end_hz = 50.0\npoints = 15\n"
        "harmonics = 3\nodd_only = true\n"
    )
    return d / "model.toml"


def array_model():
    m = ap.ResponseModel.lumped(
        ["m1.x", "m2.x"], MASS, DAMPING, STIFFNESS, np.array([1.0, 0.0])
    )
    # Element on m2 against ground: local (t1, t2, n) = (x, y, z) of m2; only x is a coordinate.
    local = np.array([[0.0, 1.0], [0.0, 0.0], [0.0, 0.0]])
    m.attach_valanis_contact("7", ap.ValanisParams(2.0e4, 0.3, 0.0, 0.5), 1e6, 2.0, local)
    m.attach_valanis_contact("11", ap.ValanisParams(1.0e4, 0.5, 0.0, 0.5), 1e6, 1.0, local)
    return m


def cli_format(name, x):
    """The CLI's formatting of a column value (src/dynamics/report.rs, write_level_csv)."""
    if name.endswith("_phase_rad"):
        return f"{x:.6f}"
    if name in ("newton_iterations", "stable"):
        return str(int(x))
    if name in ("relative_residual", "aft_periodicity_error"):
        return rust_exp(x, 3)
    if name.endswith("_fraction") or name in ("dissipated_energy_J", "floquet_max_real_part_per_s"):
        return rust_exp(x, 6)
    return rust_exp(x, 9)


def rust_exp(x, digits):
    """Rust's `{:.Ne}`: mantissa, then `e` and the exponent without sign padding."""
    m, e = f"{x:.{digits}e}".split("e")
    return f"{m}e{int(e)}"


def test_file_model_and_array_model_equal_the_cli(cli, tmp_path):
    path = write_model(tmp_path)
    cli("response", path, "--out-dir", tmp_path / "out")
    from_file = ap.ResponseModel.read(path)
    assert from_file.levels_n == [0.02, 0.5]
    assert from_file.response_labels == ["m1.x", "m2.x"]
    assert [e[1:] for e in from_file.elements] == [("valanis", 3)] * 2
    from_arrays = array_model()
    peaks = []
    for i, level in enumerate(from_file.levels_n, start=1):
        r = from_file.sweep(level)
        with open(tmp_path / "out" / f"response_level_{i}.csv") as f:
            rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
        cols = r.columns
        assert list(cols) == list(rows[0])
        assert len(rows) == len(cols["frequency_Hz"]) > 10
        for name, values in cols.items():
            assert values.dtype == np.float64
            assert [cli_format(name, v) for v in values] == [row[name] for row in rows], name
        # The same model from arrays: the same numbers, bit for bit.
        a = from_arrays.sweep(level, 15.0, 50.0, harmonics=3, odd_only=True, points=15)
        for name, values in cols.items():
            assert np.array_equal(a.columns[name], values), name
        assert r.harmonic_orders == [1, 3]
        x = r.coordinate_harmonics
        assert x.shape == (len(rows), 2, 4)  # cos and sin of orders 1 and 3
        assert np.allclose(np.hypot(x[:, 0, 0], x[:, 0, 1]), cols["m1.x_h1_amplitude_m"], rtol=1e-14)
        assert list(r.peak_elements["element"]) == ["7", "11"]
        peaks.append(cols["m1.x_h1_amplitude_m"][r.peak] / level)
    # Microslip: more damping at the higher level, the receptance peak falls (can fail).
    assert peaks[1] < 0.9 * peaks[0]


def test_modal_model_with_a_jenkins_element_sweeps(tmp_path):
    m = ap.ResponseModel.modal([20.0], [0.01], np.array([1.0]))
    m.attach_jenkins("j", 5e3, 0.5, np.array([[1.0]]))
    r = m.sweep(0.2, 15.0, 30.0, harmonics=3, points=40)
    c = r.columns
    assert r.formulation in ("coordinates", "receptance")
    assert c["frequency_Hz"][0] == pytest.approx(15.0)
    assert c["frequency_Hz"][-1] == pytest.approx(30.0)
    # Every point converged to the corrector's default tolerance (1e-7 relative residual).
    assert np.all(c["relative_residual"] <= 1e-7)
    # The stuck Jenkins spring stiffens the mode above 20 Hz: the peak lies above it.
    assert c["frequency_Hz"][r.peak] > 20.0


def test_bad_model_input_raises_named_errors(tmp_path):
    f = np.array([1.0, 0.0])
    with pytest.raises(ap.ParameterError, match="mass") as e:
        ap.ResponseModel.lumped(["a", "b"], np.array([[1.0, 0.1], [0.0, 1.0]]), DAMPING, STIFFNESS, f)
    assert e.value.name == "mass"
    with pytest.raises(ap.ParameterError, match="damping"):
        ap.ResponseModel.lumped(["a", "b"], MASS, -DAMPING, STIFFNESS, f)
    with pytest.raises(ap.ArrayTypeError, match="float64"):
        ap.ResponseModel.lumped(["a", "b"], MASS.astype(np.float32), DAMPING, STIFFNESS, f)
    with pytest.raises(ap.ParameterError, match="non-finite"):
        ap.ResponseModel.lumped(["a", "b"], MASS, DAMPING, STIFFNESS, np.array([np.nan, 0.0]))
    with pytest.raises(ap.ParameterError, match="force"):
        ap.ResponseModel.lumped(["a", "b"], MASS, DAMPING, STIFFNESS, np.ones(3))
    with pytest.raises(ap.ParameterError, match="2-D"):
        ap.ResponseModel.lumped(["a", "b"], np.ones(4), DAMPING, STIFFNESS, f)
    m = ap.ResponseModel.lumped(["a", "b"], MASS, DAMPING, STIFFNESS, f)
    with pytest.raises(ap.ParameterError, match="map"):
        m.attach_jenkins("j", 1e3, 1.0, np.ones((1, 3)))
    with pytest.raises(ap.ParameterError, match="slip_force"):
        m.attach_jenkins("j", 1e3, -1.0, np.ones((1, 2)))
    with pytest.raises(ap.ParameterError, match="frequency_start_hz"):
        m.sweep(1.0)
    with pytest.raises(ap.ParameterError, match="formulation"):
        m.sweep(1.0, 10.0, 20.0, formulation="magic")
    path = write_model(tmp_path)
    (tmp_path / "stiffness.csv").write_text("# unit: N/m\nm1.x,m2.x\n6e4,-2e4\n-1e4,2e4\n")
    with pytest.raises(ap.Error, match="stiffness.csv"):
        ap.ResponseModel.read(path)
    with pytest.raises(ap.FileError):
        ap.ResponseModel.read(tmp_path / "absent.toml")


def test_free_decay_is_the_clis(cli, tmp_path):
    """`ResponseModel.free_decay` is `asperity decay`: the same history and periods, bit for bit
    after the CLI's formatting; the stuck structure's frequency; bad input named."""
    path = write_model(tmp_path)
    cli("decay", path, "--amplitude-m", "1e-4", "--periods", "20", "--out-dir", tmp_path / "out")
    r = ap.ResponseModel.read(path).free_decay(1e-4, periods=20)
    rows = [
        line.split(",")
        for line in (tmp_path / "out" / "decay_cycles.csv").read_text().splitlines()
        if not line.startswith("#")
    ][1:]
    assert len(rows) == len(r.cycle_frequency_hz) > 10
    for row, f, z in zip(rows, r.cycle_frequency_hz, r.cycle_damping_ratio):
        assert float(row[2]) == pytest.approx(f, rel=1e-9)
        assert float(row[3]) == pytest.approx(z, rel=1e-6)
    assert r.response_m[0] == pytest.approx(1e-4, rel=1e-12)
    assert len(r.time_s) == 20 * 256 + 1
    with pytest.raises(Exception, match="amplitude"):
        ap.ResponseModel.read(path).free_decay(-1.0)


def test_nonlinear_mode_is_the_clis(cli, tmp_path):
    """`ResponseModel.nonlinear_mode` is `asperity modes`: the same backbone after the CLI's
    formatting; bad amplitudes named."""
    path = write_model(tmp_path)
    cli(
        "modes", path, "--mode", "1", "--amplitude-min-m-sqrt-kg", "1e-6",
        "--amplitude-max-m-sqrt-kg", "1e-4", "--points", "12", "--out-dir", tmp_path / "out",
    )
    r = ap.ResponseModel.read(path).nonlinear_mode(1e-6, 1e-4, mode=1, points=12)
    rows = list(
        csv.DictReader(
            line
            for line in (tmp_path / "out" / "modes.csv").read_text().splitlines()
            if not line.startswith("#")
        )
    )
    assert r.stopped is None and len(rows) == len(r.frequency_hz) == 12
    for row, a, f, z in zip(rows, r.modal_amplitude_m_sqrt_kg, r.frequency_hz, r.damping_ratio):
        assert float(row["modal_amplitude_m_sqrt_kg"]) == pytest.approx(a, rel=1e-9)
        assert float(row["frequency_Hz"]) == pytest.approx(f, rel=1e-9)
        assert float(row["damping_ratio"]) == pytest.approx(z, rel=1e-9)
    # The contacts slip along the backbone: the frequency falls, the energy grows.
    assert r.frequency_hz[-1] < r.frequency_hz[0]
    assert np.all(np.diff(r.element_energy_j) > 0)
    assert r.energy_per_element_j.shape == (12, 2)
    assert r.coordinate_harmonics.shape == (12, 2, len(r.harmonic_orders) * 2)
    with pytest.raises(Exception, match="amplitude_min_m_sqrt_kg"):
        ap.ResponseModel.read(path).nonlinear_mode(-1.0, 1e-4)


def test_nonlinear_mode_of_a_duffing_oscillator_is_its_backbone():
    """Duffing SDOF, one harmonic: ω² = k/m + ¾·k3·X²/m (the first-harmonic backbone), X = a/√m,
    and the modal damping ratio c/(2mω) (mass-proportional damping leaves the backbone
    undamped); within 1e-6 (the Newton solves stop at a relative residual of 1e-7)."""
    m, k, c, k3 = 2.0, 8.0e3, 0.4, 1.0e10
    model = ap.ResponseModel.lumped(
        ["x.x"], np.array([[m]]), np.array([[c]]), np.array([[k]]), np.array([1.0])
    )
    model.attach_cubic_spring("duffing", k3, np.array([[1.0]]))
    r = model.nonlinear_mode(1e-5, 2e-3, points=20, harmonics=1, odd_only=True)
    assert r.stopped is None
    x = r.modal_amplitude_m_sqrt_kg / np.sqrt(m)
    omega = np.sqrt(k / m + 0.75 * k3 * x**2 / m)
    np.testing.assert_allclose(r.frequency_hz, omega / (2 * np.pi), rtol=1e-6)
    np.testing.assert_allclose(r.damping_ratio, c / (2 * m * omega), rtol=1e-6)
    # The backbone hardens far beyond the linear frequency.
    assert r.frequency_hz[-1] > 1.5 * r.linear_frequency_hz


def test_a_static_preload_is_balanced_by_the_mean(tmp_path):
    """A model file's `[static]` force: `sweep` balances it with the response's mean (F0/k for a
    linear oscillator); `free_decay` and `nonlinear_mode`, which do not solve it, refuse it."""
    (tmp_path / "mass.csv").write_text("# unit: kg\nm.x\n1.0\n")
    (tmp_path / "stiffness.csv").write_text("# unit: N/m\nm.x\n1e4\n")
    (tmp_path / "damping.csv").write_text("# unit: N*s/m\nm.x\n2.0\n")
    path = tmp_path / "model.toml"
    path.write_text(
        '[linear]\nmass = "mass.csv"\ndamping = "damping.csv"\nstiffness = "stiffness.csv"\n\n'
        '[static]\ndofs = ["m.x"]\nforces_n = [30.0]\n\n'
        '[excitation]\ndofs = ["m.x"]\nlevels_n = [1.0]\n\n[response]\ndofs = ["m.x"]\n\n'
        "[sweep]\nfrequency_start_hz = 10.0\nfrequency_end_hz = 20.0\npoints = 10\n"
        "harmonics = 1\nodd_only = false\n"
    )
    model = ap.ResponseModel.read(path)
    r = model.sweep(1.0)
    np.testing.assert_allclose(r.columns["m.x_h0_mean_m"], 3e-3, rtol=1e-9)
    with pytest.raises(Exception, match="static"):
        model.free_decay(1e-4)
    with pytest.raises(Exception, match="static"):
        model.nonlinear_mode(1e-6, 1e-4)
