"""The sub-modules per stage, the names kept at the top level, and `Surface.from_topography`
against SurfaceTopography (installed in the CI virtualenv like tamaas; never a dependency)."""

import inspect
import os

import numpy as np
import pytest

import asperity as ap
import asperity.calibrate
import asperity.contact
import asperity.dynamics
import asperity.film
import asperity.identify
import asperity.surface


def test_every_stage_module_reexports_the_native_names():
    modules = [ap.surface, ap.contact, ap.calibrate, ap.film, ap.dynamics, ap.identify]
    seen = set()
    for m in modules:
        for name in m.__all__:
            assert getattr(m, name) is getattr(ap._native, name), (m.__name__, name)
            seen.add(name)
    public = {n for n in dir(ap._native) if not n.startswith("_")}
    assert public == seen, public ^ seen


def test_top_level_names_stay():
    # Classes and functions are the native ones.
    assert ap.Surface is ap.surface.Surface
    assert ap.predict is ap.identify.predict
    assert ap.diagnose is ap.identify.diagnose
    # The stages named like their function are modules that call it.
    for name in ("film", "calibrate", "identify"):
        module = getattr(ap, name)
        assert inspect.ismodule(module) and callable(module)
        function = getattr(module, name)
        assert inspect.signature(module) == inspect.signature(function)
    with pytest.raises(ap.ParameterError, match="family"):
        ap.identify(["x.csv"], family="coulomb")
    # The exception classes are exported with everything else.
    assert set(ap.errors.__all__) <= set(ap.__all__)
    assert all(hasattr(ap, n) for n in ap.__all__)


def _surface_topography():
    try:
        import SurfaceTopography
    except ImportError:
        if os.environ.get("ASPERITY_REQUIRE_DATA") == "1":
            pytest.fail("SurfaceTopography not importable and ASPERITY_REQUIRE_DATA=1")
        pytest.skip("SurfaceTopography not installed")
    return SurfaceTopography


def test_surface_from_topography_matches_surfacetopography():
    st = _surface_topography()
    rng = np.random.default_rng(4)
    h_um = rng.normal(size=(64, 48)) * 0.2  # µm
    t = st.Topography(h_um, (128.0, 96.0), unit="µm", periodic=True)
    s = ap.Surface.from_topography(t)
    assert s.shape == (64, 48) and s.periodic
    assert s.dx_m == pytest.approx(2e-6, rel=1e-15)
    assert np.allclose(s.heights, h_um * 1e-6, rtol=1e-15, atol=0)
    # The peer's own Sq (mean subtracted), converted from µm.
    stats = s.stats("mean")
    assert stats.rq_m == pytest.approx(t.Sq() * 1e-6, rel=1e-12)
    # Slopes are dimensionless: the peer's along x (Rdq) and its gradient, unconverted.
    assert stats.rms_slope == pytest.approx(t.Rdq(), rel=1e-12)
    assert stats.rms_gradient == pytest.approx(t.rms_gradient(), rel=1e-12)
    # A non-periodic topography in mm keeps its window kind and scale.
    t2 = st.Topography(h_um * 1e-3, (0.128, 0.096), unit="mm", periodic=False)
    s2 = ap.Surface.from_topography(t2)
    assert not s2.periodic and np.allclose(s2.heights, s.heights, rtol=1e-12)
    # Without a unit the scale is unknown: refused, naming it.
    with pytest.raises(ap.ParameterError, match="unit"):
        ap.Surface.from_topography(st.Topography(h_um, (128.0, 96.0)))
    # A line scan is not an area.
    line = st.UniformLineScan(h_um[:, 0], 128.0, unit="µm")
    with pytest.raises(ap.ParameterError, match="Profile"):
        ap.Surface.from_topography(line)
