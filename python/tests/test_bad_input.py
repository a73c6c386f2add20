"""Bad input from Python: clear exceptions of the documented classes, naming the argument."""

import numpy as np
import pytest

import asperity as ap

E_STAR = ap.composite_modulus(210e9, 0.3)
TABLE = __import__("pathlib").Path(__file__).resolve().parents[2] / "calib" / "calibration_table.csv"


@pytest.mark.parametrize(
    "heights, kind, needle",
    [
        (np.zeros((8, 8), dtype=np.float32), ap.ArrayTypeError, "float32"),
        (np.zeros((8, 8), dtype=np.int64), ap.ArrayTypeError, "int64"),
        ([[0.0, 1.0], [1.0, 0.0]], ap.ArrayTypeError, "list"),
        (np.zeros(8), ap.ParameterError, "2-D"),
        (np.zeros((2, 4, 4)), ap.ParameterError, "2-D"),
        (np.zeros((8, 16))[:, ::2], ap.ParameterError, "C-contiguous"),
        (np.asfortranarray(np.random.default_rng(0).random((8, 6))), ap.ParameterError, "C-contiguous"),
        (np.zeros((8, 8)).T[::2], ap.ParameterError, "C-contiguous"),
    ],
)
def test_array_type_shape_and_layout(heights, kind, needle):
    with pytest.raises(kind) as e:
        ap.Surface(heights, 1e-6)
    assert needle in str(e.value) and "heights" in str(e.value)
    assert isinstance(e.value, ap.Error)
    assert isinstance(e.value, TypeError if kind is ap.ArrayTypeError else ValueError)


def test_nan_and_inf_name_the_point():
    h = np.zeros((8, 8))
    h[3, 5] = np.nan
    with pytest.raises(ap.ParameterError, match=r"\(3, 5\)") as e:
        ap.Surface(h, 1e-6)
    assert e.value.name == "heights"
    h[3, 5] = np.inf
    with pytest.raises(ValueError, match="inf"):
        ap.Surface(h, 1e-6)
    q = np.array([0.0, 1e-6, np.nan])
    with pytest.raises(ap.ParameterError, match="index 2"):
        ap.valanis_integrate(ap.ValanisParams(1e12, 0.5, 0.0, 0.6), q, 1e6)
    with pytest.raises(ap.ParameterError, match="pressure"):
        ap.NormalSolver(ap.Surface.generate(nx=64, lx_m=100e-6, clx_m=5e-6), e_star_pa=E_STAR).displacement_of(
            np.zeros((64, 63)))


def test_parameter_values_are_named():
    with pytest.raises(ap.ParameterError, match="clx_m") as e:
        ap.Surface.generate(nx=16)  # correlation length under two spacings
    assert e.value.name == "clx_m"
    with pytest.raises(ap.ParameterError, match="k"):
        ap.ValanisParams(1e12, 1.2, 0.0, 0.6)
    with pytest.raises(ValueError, match="dx"):
        ap.Surface(np.zeros((4, 4)), -1.0)
    s = ap.Surface.generate(nx=64, lx_m=100e-6, clx_m=5e-6)
    with pytest.raises(ap.ParameterError, match="mean_pressure_pa"):
        ap.NormalSolver(s, e_star_pa=E_STAR).solve_load(-1.0)
    with pytest.raises(ap.ParameterError, match="operator"):
        ap.TangentialSolver(np.ones((4, 4)), friction_coefficient=0.5, spacing_m=(1e-6, 1e-6),
                            periodic=True, operator="magic")
    with pytest.raises(ap.ParameterError, match="preloads"):
        ap.join_elements({"id": np.array([1], dtype=np.uint64)}, ap.CalibrationTable.read_csv(TABLE))


def test_files_and_solvers():
    with pytest.raises(ap.FileError) as e:
        ap.Surface.read("/nonexistent/dir/surface.x3p")
    assert isinstance(e.value, OSError) and e.value.errno == 2
    assert e.value.filename == "/nonexistent/dir/surface.x3p"
    s = ap.Surface.generate(nx=128)
    with pytest.raises(ap.ConvergenceError) as c:
        ap.NormalSolver(s, e_star_pa=E_STAR, max_iterations=2).solve_load(1e6)
    assert c.value.iterations == 2 and c.value.residual > c.value.tolerance == 1e-10
    assert isinstance(c.value, RuntimeError) and "did not converge" in str(c.value)


def test_malformed_table_names_file_and_line(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text(
        "pressure_Pa,contact_area_ratio,kn_N_per_m3,E0_N_per_m3,k,mu,Et_N_per_m3,fit_R2,energy_per_cycle_J_per_m2\n"
        "1e6,0.001,1e13,5e12,0.5,0.6,0,0.99,1e-3\n"
        "2e6,0.002,oops,6e12,0.4,0.6,0,0.99,2e-3\n"
    )
    with pytest.raises(ap.ParseError) as e:
        ap.CalibrationTable.read_csv(p)
    assert e.value.line == 3 and e.value.path == str(p) and str(p) in str(e.value)
    assert isinstance(e.value, ValueError)


def test_views_are_read_only_and_keep_their_owner_alive():
    s = ap.Surface.generate(nx=64, lx_m=100e-6, clx_m=5e-6)
    h = s.heights
    with pytest.raises(ValueError):
        h[0, 0] = 1.0
    assert not np.shares_memory(h, h.copy())
    h2 = s.heights
    assert np.shares_memory(h, h2)  # both views of the surface's own memory: no copy
    before = h.copy()
    del s, h2
    import gc

    gc.collect()
    assert np.array_equal(h, before)  # the view keeps the surface alive
    sol = ap.NormalSolver(ap.Surface.generate(nx=64, lx_m=100e-6, clx_m=5e-6), e_star_pa=E_STAR).solve_load(1e6)
    p = sol.pressure
    with pytest.raises(ValueError):
        p[0, 0] = 0.0
    assert np.shares_memory(p, sol.pressure)


def test_one_small_strain_limit_as_the_cli():
    """The library's solver refuses a nominal pressure above 0.1·E* as `contact normal` does."""
    s = ap.Surface.generate(nx=64, lx_m=100e-6, clx_m=5e-6)
    with pytest.raises(ap.ParameterError, match=r"0\.1 × E\*") as e:
        ap.NormalSolver(s, e_star_pa=E_STAR).solve_load(0.11 * E_STAR)
    assert e.value.name == "mean_pressure_pa"
