"""The calibration chain from Python (`asperity.calibrate`) writes the files of `asperity
calibrate` byte for byte on the same inputs (wall times excepted) and returns the same numbers;
bad input raises named exceptions."""

import csv
import filecmp
import json

import numpy as np
import pytest

import asperity as ap


def small_config(repo, d, realisations=2):
    """The reference statistics on 64² over 64 µm, 2 pressures, 2 amplitudes: a fraction of a s."""
    keys = {
        "lx_m": "6.4e-5", "ly_m": "6.4e-5", "nx": "64", "ny": "64", "count": str(realisations),
        "pressures_pa": "[1e6, 5e6]", "amplitude_factors": "[0.5, 1.0]", "steps_per_cycle": "20",
    }
    lines = []
    for line in (repo / "calib" / "reference.toml").read_text().splitlines():
        key = line.split("=")[0].strip()
        lines.append(f"{key} = {keys[key]}" if key in keys else line)
    path = d / "small.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def same(value, recorded):
    """A float equals its JSON record (NaN is written as null)."""
    return bool(np.isnan(value)) if recorded is None else value == recorded


def test_calibrate_equals_the_cli(cli, repo, tmp_path):
    config = small_config(repo, tmp_path)
    cli("calibrate", config, "--out-dir", tmp_path / "cli")
    r = ap.calibrate(config, out_dir=tmp_path / "py")
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert sorted(p.rsplit("/", 1)[-1] for p in r.written) == names
    compared = [n for n in names if n != "calibration_timings.csv"]
    assert len(compared) >= 14
    match, mismatch, errors = filecmp.cmpfiles(tmp_path / "cli", tmp_path / "py", compared, shallow=False)
    assert mismatch == [] and errors == [], (mismatch, errors)
    # The returned numbers are the files' numbers (shortest round-trip decimals in the CSVs).
    table = r.table.columns()
    cli_table = ap.CalibrationTable.read_csv(tmp_path / "cli" / "calibration_table.csv").columns()
    for k, v in cli_table.items():
        assert np.array_equal(table[k], v), k
    real = rows(tmp_path / "cli" / "calibration_realisations.csv")
    c = r.realisations
    assert len(real) == len(c["kn_N_per_m3"]) == 4
    for name in ["pressure_Pa", "kn_N_per_m3", "E0_N_per_m3", "k", "fit_R2", "mean_gap_m"]:
        assert np.array_equal(c[name], [float(x[name]) for x in real]), name
    assert list(c["seed"]) == [1, 1, 2, 2]
    # Two realisations differ (the comparison can fail).
    assert c["kn_N_per_m3"][0] != c["kn_N_per_m3"][2]
    conv = json.loads((tmp_path / "cli" / "calibration.json").read_text())["convergence"]
    assert [p.pressure_pa for p in r.convergence.pressures] == [1e6, 5e6]
    assert r.convergence.notes == conv["notes"]
    for spec in ("grid_spec", "patch_spec"):
        ours, theirs = getattr(r.convergence, spec), conv[spec]
        assert (ours is None) == (theirs is None), spec
        if theirs is not None:
            assert {k: getattr(ours, k) for k in theirs} == theirs, spec
    assert len(r.convergence.pressures) == len(conv["pressures"])
    for ours, theirs in zip(r.convergence.pressures, conv["pressures"]):
        assert ours.grid_verdict == theirs["grid_verdict"]
        assert ours.patch_verdict == theirs["patch_verdict"]
        assert ours.contact_spots.n == theirs["contact_spots"]["n"] == 2
        assert ours.contact_spots.mean == theirs["contact_spots"]["mean"]
        assert ours.min_median_spot_points == theirs["min_median_spot_points"]
        for kind in ("grid", "patch"):
            assert [c.quantity for c in getattr(ours, kind)] == ["kn", "E0", "k"]
            assert len(theirs[kind]) == 3
            for c, j in zip(getattr(ours, kind), theirs[kind]):
                assert c.verdict == j["verdict"] and c.tolerance == j["tolerance"]
                assert same(c.change, j["change"]["mean"]) and same(c.change_ci95, j["change"]["ci95"])
    t = r.times
    stages = [t.surface_s, t.normal_s, t.tangential_s, t.fit_s, t.surface_cpu_s, t.normal_cpu_s,
              t.tangential_cpu_s, t.fit_cpu_s]
    assert t.total_s > 0 and t.normal_s > 0 and all(np.isfinite(v) and v >= 0 for v in stages)
    assert any("contact spots" in w for w in r.warnings)


def test_calibrate_on_a_given_surface(repo, tmp_path):
    config = small_config(repo, tmp_path)
    s = ap.Surface.generate(rq_m=0.177e-6, clx_m=6.6e-6, cly_m=6.6e-6, lx_m=64e-6, ly_m=64e-6,
                            nx=64, ny=64, seed=1)
    r = ap.calibrate(config, surface=s)
    assert list(r.realisations["seed"]) == [-1, -1]
    # The same surface as the generated realisation 1: the same kn.
    g = ap.calibrate(config, realisations=1)
    assert np.array_equal(r.realisations["kn_N_per_m3"], g.realisations["kn_N_per_m3"])
    assert r.written == []


def test_bad_calibration_input(repo, tmp_path):
    config = small_config(repo, tmp_path)
    with pytest.raises(ap.ParameterError) as e:
        ap.calibrate(config, grid=8)
    assert e.value.name == "grid"
    with pytest.raises(ap.ParameterError) as e:
        ap.calibrate(config, realisations=0)
    assert e.value.name == "realisations"
    with pytest.raises(ap.FileError):
        ap.calibrate(tmp_path / "absent.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text(config.read_text().replace("mu = 0.6", "mu = -0.6"))
    with pytest.raises(ap.Error, match="mu"):
        ap.calibrate(bad, out_dir=tmp_path / "never")
    assert not (tmp_path / "never").exists()
