"""The Python package and the CLI give the same numbers on the same inputs, bit for bit.

Each test runs the `asperity` binary and the binding on identical inputs and compares the
values exactly: CSV and JSON numbers are printed by the shortest round-trip representation
(or compared after the same formatting), so equality here means equal float64 values.
"""

import csv
import json

import numpy as np
import pytest

import asperity as ap

E_STAR = ap.composite_modulus(210e9, 0.3)


def csv_rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def test_generated_surface_is_the_cli_surface(cli, tmp_path):
    out = tmp_path / "s.npy"
    cli("surface", "generate", "--rq-m", "0.3e-6", "--clx-m", "9e-6", "--cly-m", "5e-6",
        "--lx-m", "200e-6", "--ly-m", "150e-6", "--nx", "96", "--ny", "64", "--seed", "7", "-o", out)
    s = ap.Surface.generate(rq_m=0.3e-6, clx_m=9e-6, cly_m=5e-6, lx_m=200e-6, ly_m=150e-6,
                            nx=96, ny=64, seed=7)
    c = ap.Surface.read(out)
    assert np.array_equal(s.heights, np.load(out))
    assert (s.dx_m, s.dy_m, s.periodic) == (c.dx_m, c.dy_m, c.periodic) == (200e-6 / 96, 150e-6 / 64, True)
    assert s.heights.shape == (96, 64)
    # A different seed is a different surface (the comparison can fail).
    assert not np.array_equal(ap.Surface.generate(nx=96, ny=64, lx_m=200e-6, ly_m=150e-6,
                                                  rq_m=0.3e-6, clx_m=9e-6, cly_m=5e-6, seed=8).heights,
                              s.heights)


def cli_stats(cli, path, tmp_path):
    r = cli("surface", "stats", path, "--json", "--psd-out", tmp_path / "psd.csv")
    return json.loads(r.stdout)


def assert_stats_equal(got, expected):
    """Every field of a SurfaceStats equals the CLI's JSON key of the same name."""
    fields = [k for k in dir(got) if not k.startswith("_")]
    assert len(fields) == 22
    for key in fields:
        assert expected[key] == getattr(got, key), key


@pytest.mark.parametrize("detrend", ["mean", "plane"])
def test_statistics_equal_the_cli(cli, tmp_path, detrend):
    s = ap.Surface.generate(nx=128, seed=3)
    path = tmp_path / "s.npy"
    s.write(path)
    r = cli("surface", "stats", path, "--json", "--detrend", detrend, "--psd-out", tmp_path / "psd.csv")
    expected = json.loads(r.stdout)
    got = s.stats(detrend)
    assert_stats_equal(got, expected)
    if detrend == "mean":
        assert got.rq_m == pytest.approx(0.177e-6, rel=1e-12)


def test_profile_statistics_equal_the_cli(cli, tmp_path, data_file):
    path = data_file("topography/dektak-1.csv")
    p = ap.read_topography(path)
    assert isinstance(p, ap.Profile)
    expected = cli_stats(cli, path, tmp_path)
    assert_stats_equal(p.stats(), expected)


def test_normal_sweep_equals_the_cli(cli, tmp_path):
    s = ap.Surface.generate(nx=128, seed=5)
    path = tmp_path / "s.npy"
    s.write(path)
    pressures = [0.5e6, 2e6, 8e6]
    cli("contact", "normal", "--surface", path, "--pressures-pa", ",".join(map(str, pressures)),
        "--out-dir", tmp_path / "out")
    rows = csv_rows(tmp_path / "out" / "normal_sweep.csv")
    py = ap.normal_sweep(s, pressures, e_star_pa=E_STAR)
    assert len(rows) == 3
    for k, row in enumerate(rows):
        assert row["surface"] == str(path)
        for col in ["pressure_Pa", "contact_area_ratio", "mean_gap_m", "kn_N_per_m3", "approach_m", "residual"]:
            assert float(row[col]) == py[col][k], col
        for col in ["contact_spots", "smallest_spot_points", "median_spot_points", "iterations"]:
            assert int(row[col]) == py[col][k], col
    # The solver object gives the same solution as the sweep at the first load (cold start).
    sol = ap.NormalSolver(s, e_star_pa=E_STAR).solve_load(pressures[0])
    assert sol.mean_gap_m == py["mean_gap_m"][0]
    assert sol.contact_area_ratio == py["contact_area_ratio"][0]
    assert sol.contact_points == round(sol.contact_area_ratio * 128 * 128)
    assert np.count_nonzero(sol.pressure) == sol.contact_points


def test_tangential_loops_equal_the_cli(cli, tmp_path):
    amplitude = 3e-8
    cli("contact", "tangential", "--grid", "128", "--pressures-pa", "2e6", "--amplitude-m", amplitude,
        "--cycles", "1", "--steps-per-cycle", "8", "--out-dir", tmp_path)
    rows = csv_rows(tmp_path / "tangential_loops.csv")
    s = ap.Surface.generate(nx=128)
    sol = ap.NormalSolver(s, e_star_pa=E_STAR).solve_load(2e6)
    t = ap.TangentialSolver(sol, friction_coefficient=0.6)
    r = t.oscillate(amplitude_m=(amplitude, 0.0), cycles=1, steps_per_cycle=8)
    st = r.steps
    assert len(rows) == len(st["displacement_m"]) == 9
    for k, row in enumerate(rows):
        assert float(row["displacement_m"]) == st["displacement_m"][k]
        assert float(row["mean_shear_stress_Pa"]) == st["mean_shear_stress_Pa"][k]
        assert float(row["mean_shear_stress_y_Pa"]) == st["mean_shear_stress_y_Pa"][k]
        assert float(row["force_N"]) == st["force_N"][k]
        assert float(row["accumulated_slip_m"]) == st["accumulated_slip_m"][k]
        assert float(row["residual"]) == st["residual"][k]
        assert int(row["iterations"]) == st["iterations"][k]
        assert row["stick_fraction"] == f"{st['stick_fraction'][k]:.6f}"
    energy = csv_rows(tmp_path / "tangential_energy.csv")
    assert float(energy[0]["dissipated_J_per_m2"]) == r.cycles[0].dissipated_j_per_m2
    assert r.cycles[0].dissipated_j_per_m2 > 0
    assert r.metadata.friction_coefficient == 0.6 and r.metadata.grid == (128, 128)
    assert r.metadata.contact_points == sol.contact_points
    step = t.step(displacement_m=(amplitude, 0.0))
    assert step.shift_m == (amplitude, 0.0) and step.converged


def test_tangential_sweep_is_the_clis(cli, tmp_path):
    """``tangential_sweep`` runs the library function the command runs: the same files, byte
    for byte, and typed results equal to them; under a varying normal load the element check
    too."""
    args = dict(grid=128, pressures_pa=[2e6, 5e6], cycles=2, steps_per_cycle=8,
                normal_amplitude_ratio=0.3, normal_phase_deg=90.0)
    cli("contact", "tangential", "--grid", "128", "--pressures-pa", "2e6,5e6", "--cycles", "2",
        "--steps-per-cycle", "8", "--normal-amplitude-ratio", "0.3", "--normal-phase-deg", "90",
        "--out-dir", tmp_path / "cli")
    r = ap.tangential_sweep(**args, out_dir=tmp_path / "py")
    assert sorted(p.rsplit("/", 1)[-1] for p in r.written) == sorted(
        p.name for p in (tmp_path / "cli").iterdir())
    for name in ("tangential_loops.csv", "tangential_energy.csv", "tangential_element.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert r.pressures_pa == [2e6, 5e6] and len(r.results) == 2 and len(r.element_checks) == 2
    energy = csv_rows(tmp_path / "cli" / "tangential_energy.csv")
    assert len(energy) == 4
    for row in energy:
        res = r.results[r.pressures_pa.index(float(row["pressure_Pa"]))]
        cycle = res.cycles[int(row["cycle"]) - 1]
        assert float(row["dissipated_J_per_m2"]) == cycle.dissipated_j_per_m2
    check = r.element_checks[0]
    assert check.bem_energy_j_per_m2 > 0 and np.isfinite(check.energy_rel_error)
    assert len(check.normal_pressure_pa) == len(r.results[0].steps["displacement_m"])
    # The normal load varies about the nominal pressure by the ratio asked for.
    p = check.normal_pressure_pa
    assert abs(p.max() / 2e6 - 1.3) < 0.02 and abs(p.min() / 2e6 - 0.7) < 0.02
    # The load-following element: fitted at the cycle's lowest, mean and highest loads, its
    # energy error the file's.
    assert check.load_following_loads_pa == pytest.approx([1.4e6, 2e6, 2.6e6], rel=1e-12)
    assert [q.e0 for q in check.load_following_params][1] == check.table_params.e0
    row = csv_rows(tmp_path / "cli" / "tangential_element.csv")[0]
    assert float(row["load_following_energy_error"]) == pytest.approx(
        check.load_following_energy_rel_error, abs=1e-6)
    # Without out_dir nothing is written; bad input names the argument.
    assert ap.tangential_sweep(grid=128, pressures_pa=[2e6], cycles=1, steps_per_cycle=8).written == []
    with pytest.raises(Exception, match="operator"):
        ap.tangential_sweep(grid=128, operator="fast")


def test_elements_equal_the_cli(cli, tmp_path, repo):
    table_path = repo / "calib" / "calibration_table.csv"
    table = ap.CalibrationTable.read_csv(table_path)
    lo, hi = table.pressure_range
    # Nodes below, inside (between and on rows) and above the table's range.
    pressures = np.array([lo / 3, lo, 0.37e6, 1e6, 3.3e6, hi, 4 * hi])
    n = len(pressures)
    area = np.linspace(1e-8, 3e-8, n)
    preloads = {
        "id": np.arange(10, 10 + n, dtype=np.uint64),
        "x_m": np.linspace(0.0, 1e-3, n),
        "y_m": np.linspace(1e-3, 0.0, n),
        "area_m2": area,
        "pressure_Pa": pressures,
        "N0_N": pressures * area,
    }
    pre_path = tmp_path / "preload.csv"
    ap.write_preloads(pre_path, preloads, "test nodes")
    cli("elements", "--preload", pre_path, "--table", table_path, "--out", tmp_path / "elements.csv")
    rows = csv_rows(tmp_path / "elements.csv")
    cols, summary = ap.join_elements(ap.read_preloads(pre_path), table, out=tmp_path / "py-elements.csv")
    assert len(rows) == n
    for k, row in enumerate(rows):
        for col, value in row.items():
            if col in ("id", "out_of_range"):
                assert int(value) == cols[col][k], col
            else:  # the CSV holds 10 significant digits (13 for N0_N): round ours the same way
                digits = 12 if col == "N0_N" else 9
                assert float(value) == float(f"{cols[col][k]:.{digits}e}"), col
    assert list(cols["out_of_range"]) == [-1, 0, 0, 0, 0, 0, 1]
    assert isinstance(summary, ap.ElementSummary)
    assert summary.n_elements == n and summary.n_open == 0 and summary.open_ids == []
    assert summary.n_below_range == 1 and summary.n_above_range == 1
    assert summary.below_range_ids == [10] and summary.above_range_ids == [10 + n - 1]
    # Against the nodes as written (the preload CSV holds 10 significant digits).
    assert summary.total_area_m2 == pytest.approx(area.sum(), rel=1e-9)
    assert summary.total_load_n == pytest.approx((pressures * area).sum(), rel=1e-9)
    assert summary.element_pressure_min_pa == pytest.approx(pressures.min(), rel=1e-9)
    assert summary.element_pressure_max_pa == pytest.approx(pressures.max(), rel=1e-9)
    assert (summary.table_pressure_min_pa, summary.table_pressure_max_pa) == table.pressure_range
    # The element CSV written from Python is the CLI's, byte for byte.
    assert (tmp_path / "py-elements.csv").read_bytes() == (tmp_path / "elements.csv").read_bytes()
    # Interpolation hits the table rows exactly at the tabulated pressures.
    tabulated = table.columns()
    at = table.interpolate(tabulated["pressure_Pa"])
    assert isinstance(at, ap.TableColumns) and len(at) == len(table)
    for attr, col in [("kn_n_per_m3", "kn_N_per_m3"), ("e0_n_per_m3", "E0_N_per_m3"), ("k", "k"),
                      ("mu", "mu"), ("et_n_per_m3", "Et_N_per_m3"), ("contact_area_ratio", "contact_area_ratio")]:
        assert np.array_equal(getattr(at, attr), tabulated[col]), attr
    assert at.range.dtype == np.int8 and list(at.range) == [0] * len(table)
    # A number gives the same values as the array's entry; below the table the range flag is −1.
    one = table.interpolate(float(tabulated["pressure_Pa"][1]))
    assert isinstance(one, ap.TableValues) and one.range == 0
    assert one.kn_n_per_m3 == tabulated["kn_N_per_m3"][1] and one.mu == tabulated["mu"][1]
    assert table.interpolate(0.5 * table.pressure_range[0]).range == -1
    assert table.interpolate(2.0 * table.pressure_range[1]).range == 1


def test_film_preloads_equal_the_cli(cli, tmp_path, data_file, repo):
    image = data_file("film/prescale-lw-pressure-map.png")
    colours = data_file("film/prescale-lw-colour-table.csv")
    nodes_path = repo / "calib" / "film" / "example-nodes-8mm-patch.csv"
    out = tmp_path / "cli"
    cli("film", "--image", image, "--colour-table", colours, "--pixel-size-mm", "0.2343",
        "--nodes", nodes_path, "--nodes-region", "1", "--node-offset-mm", "52.137,223.796",
        "--total-load-n", "100.5", "--reduce-mesh-size-mm", "1", "--out-dir", out)
    m = ap.FilmMap.read(image, 0.2343e-3, colour_table=colours)
    assert np.array_equal(m.pressure_pa, np.load(out / "pressure_map_Pa.npy"), equal_nan=True)
    regions, _ = m.detect_patches()
    region = next(r for r in regions if r.id == 1)
    fit = m.fit(region, order=4)
    pre, summary = ap.film_preloads(m, region, fit, ap.read_nodes(nodes_path),
                                    offset_m=(52.137e-3, 223.796e-3), total_load_n=100.5)
    assert isinstance(summary, ap.PreloadSummary)
    assert summary.total_load_n == pytest.approx(100.5, rel=1e-12)
    assert summary.n_nodes == len(pre["id"])
    assert summary.total_load_n == pytest.approx(pre["N0_N"].sum(), rel=1e-12)
    assert summary.total_area_m2 == pytest.approx(pre["area_m2"].sum(), rel=1e-12)
    assert summary.load_scale == pytest.approx(summary.total_load_n / summary.raw_total_load_n, rel=1e-12)
    reduced = ap.reduce_preloads(pre, 1e-3)
    for name, cols in [("preload.csv", pre), ("preload_reduced.csv", reduced)]:
        ap.write_preloads(tmp_path / name, cols)
        ours = [l for l in (tmp_path / name).read_text().splitlines() if not l.startswith("#")]
        theirs = [l for l in (out / name).read_text().splitlines() if not l.startswith("#")]
        assert ours == theirs, name
    regions_csv = csv_rows(out / "regions.csv")
    assert float(regions_csv[0]["fit_R2"]) == pytest.approx(fit.r_squared, abs=5e-5)


def assert_typed_equals_json(ours, theirs, where="summary"):
    """A typed result equals its JSON record: objects attribute by attribute, lists item by
    item, NaN written as null; the node readings per pixel class are a list of records with
    ``pixel_class`` where the JSON keys them by class; a fit's ``frame`` is not exposed."""
    if isinstance(theirs, dict):
        for key, value in theirs.items():
            if key == "frame":
                continue
            if key == "pixel_classes":
                got = {r.pixel_class: r for r in ours.pixel_classes}
                assert sorted(got) == sorted(value), where
                for name, reading in value.items():
                    assert_typed_equals_json(got[name], reading, f"{where}.pixel_classes.{name}")
                continue
            assert_typed_equals_json(getattr(ours, key), value, f"{where}.{key}")
    elif isinstance(theirs, list):
        ours = list(ours)
        assert len(ours) == len(theirs), where
        for i, (a, b) in enumerate(zip(ours, theirs)):
            assert_typed_equals_json(a, b, f"{where}[{i}]")
    elif theirs is None and isinstance(ours, float):
        assert np.isnan(ours), where
    else:
        assert type(ours) is not dict, where
        assert ours == theirs, where


def test_film_pipeline_is_the_clis(cli, tmp_path, data_file, repo):
    """``film()`` runs the library function the CLI calls: with ``out_dir`` it writes the CLI's
    files byte for byte (film.json up to its creation time), and its result holds what they
    hold."""
    image = data_file("film/prescale-lw-pressure-map.png")
    colours = data_file("film/prescale-lw-colour-table.csv")
    nodes_path = repo / "calib" / "film" / "example-nodes-8mm-patch.csv"
    out = tmp_path / "cli"
    cli("film", "--image", image, "--colour-table", colours, "--pixel-size-mm", "0.2343",
        "--nodes", nodes_path, "--nodes-region", "1", "--node-offset-mm", "52.137,223.796",
        "--total-load-n", "100.5", "--reduce-mesh-size-mm", "1", "--out-dir", out)
    got = ap.film(image, colour_table=colours, pixel_size_mm=0.2343, nodes=nodes_path,
                  nodes_region=1, node_offset_mm=(52.137, 223.796), total_load_n=100.5,
                  reduce_mesh_size_mm=1.0, out_dir=tmp_path / "py")
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(p.name for p in (tmp_path / "py").iterdir())
    assert sorted(p.name for p in got.written) == names
    for name in names:
        ours, theirs = (tmp_path / "py" / name).read_bytes(), (out / name).read_bytes()
        if name == "film.json":
            ours, theirs = (json.loads(ours), json.loads(theirs))
            for j in (ours, theirs):
                del j["created_unix_s"]
        assert ours == theirs, name
    assert len(got.regions) == 6 and all(f is not None for f in got.fits)
    summary = json.loads((out / "film.json").read_text())["summary"]
    # The typed summary is film.json's, field for field.
    assert_typed_equals_json(got.summary, summary)
    assert got.summary.nodes is not None and got.summary.nodes.reduction is not None
    assert len(got.summaries) == len(summary["regions"])
    for ours, theirs in zip(got.summaries, summary["regions"]):
        counts = theirs.pop("counts")
        assert {k: getattr(ours, k) for k in theirs} == theirs
        assert {k: getattr(ours.counts, k) for k in counts} == counts
    total = got.film_map.class_counts
    assert sum(getattr(total, k) for k in ap.FilmMap.class_names) == got.film_map.shape[0] * got.film_map.shape[1]
    assert np.array_equal(got.film_map.pressure_pa, np.load(out / "pressure_map_Pa.npy"),
                          equal_nan=True)
    assert got.preloads["N0_N"].sum() == pytest.approx(100.5, rel=1e-12)
    assert got.reduced_preloads["N0_N"].sum() == pytest.approx(100.5, rel=1e-12)
    assert any("nodes on region 1" in m for m in got.messages)
    # Errors name the keyword argument.
    with pytest.raises(ap.ParameterError, match="pixel_size_mm") as e:
        ap.film(image, colour_table=colours, pixel_size_mm=-1.0)
    assert e.value.name == "pixel_size_mm"


def test_diagnose_equals_the_cli(cli, tmp_path, data_file):
    record = data_file("loops/brfd-dataset2-0.5Hz30lbtension0.5amplitude.csv")
    cli("diagnose", record, "--out-dir", tmp_path)
    expected = json.loads((tmp_path / "diagnose.json").read_text())
    rec = ap.read_record(record)
    report = ap.diagnose(rec.time_s, rec.displacement_m, rec.force_n, source=str(record))
    got = json.loads(report.json)
    assert "backlash" in report.text
    # The JSON report is the CLI's, value for value, but for the wall times and the input's
    # column names.
    for r in (got, expected):
        del r["baseline_fit"]["wall_time_s"]
        for rnd in r["rounds"]:
            for c in rnd["candidates"]:
                del c["fit"]["wall_time_s"]
        r["input"].pop("columns")
    assert got == expected
    # The typed fields are the report's.
    assert report.effects_added == expected["effects_added"] == ["backlash"]
    assert report.errors_after.nrms == expected["errors_after"]["nrms"]
    assert report.errors_before.held_out_rms_over_noise == (
        expected["errors_before"]["held_out_rms_over_noise"])
    assert report.samples_analysed == expected["samples_analysed"]
    assert report.training_cycles == expected["training_cycles"]
    assert len(report.final_force_n) == expected["samples_analysed"]
