"""`asperity.identify` / `asperity.predict` against the CLI binary on the same inputs: the
typed reports carry the numbers of the CLI's identify.json / predict.json, and the files written
through `out_dir` are the command's. Small settings (three Brake–Reuss levels, no effect
search, one short swarm, capped Nelder–Mead, no bands) keep it to seconds; the search itself is
tested in Rust.
"""

import json

import pytest

import asperity as ap

LEVELS = ["frf/brb-force-control-level1.csv", "frf/brb-force-control-level2.csv",
          "frf/brb-force-control-level4.csv"]
QUICK = dict(max_effects=0, starts=1, particles=4, swarm_iterations=5, local_iterations=150,
             chain_steps=0, seed=3)
QUICK_FLAGS = ["--max-effects", "0", "--starts", "1", "--particles", "4",
               "--swarm-iterations", "5", "--local-iterations", "150", "--chain-steps", "0",
               "--seed", "3"]


@pytest.fixture(scope="module")
def identified(cli, tmp_path_factory, data_dir):
    files = [data_dir / f for f in LEVELS]
    for f in files:
        if not f.exists():
            pytest.skip(f"reference data file {f} not found (set ASPERITY_DATA_DIR)")
    tmp = tmp_path_factory.mktemp("identify")
    cli("identify", *files, *QUICK_FLAGS, "--out-dir", tmp / "cli")
    got = ap.identify(files, out_dir=tmp / "py", **QUICK)
    return files, tmp, got


def _without_times(j):
    """The report without what differs from run to run: wall times and stage times."""
    if isinstance(j, dict):
        return {k: _without_times(v) for k, v in j.items()
                if k not in ("wall_time_s", "stage_times")}
    if isinstance(j, list):
        return [_without_times(v) for v in j]
    return j


def test_identify_equals_the_cli(identified):
    files, tmp, got = identified
    expected = json.loads((tmp / "cli" / "identify.json").read_text())
    ours = json.loads((tmp / "py" / "identify.json").read_text())
    # The same search with the same seed: the same report, file for file.
    assert _without_times(ours) == _without_times(expected)
    assert sorted(p.split("/")[-1] for p in got.written) == sorted(
        p.name for p in (tmp / "cli").iterdir())
    # The typed report carries the JSON's numbers.
    assert got.kind == "mode"
    assert got.fit_levels == expected["levels_fit"] == [1, 3]
    assert got.selected_effects == []
    final = expected["final"]["parameters"]
    assert [p.name for p in got.parameters] == [p["name"] for p in final]
    assert [p.value for p in got.parameters] == [p["value"] for p in final]
    assert [p.unit for p in got.parameters] == [p["unit"] for p in final]
    assert all(p.lo_95 is None and p.hi_95 is None for p in got.parameters)
    assert "not requested" in got.uncertainty_reason
    for ours_e, theirs in zip(got.errors_after, expected["errors_after"]):
        assert ours_e.role == theirs["role"]
        assert ours_e.peak_error == theirs["peak_error"]
        assert ours_e.rms_complex == theirs["rms_complex"]
    assert [e.file for e in got.held_out_errors] == ["brb-force-control-level2.csv"]
    assert got.text == (tmp / "py" / "identify.txt").read_text()
    assert "wrote:" not in got.text


def test_predict_equals_the_cli(identified, cli):
    files, tmp, _ = identified
    model = tmp / "cli" / "model.json"
    cli("predict", "--model", model, *files, "--out-dir", tmp / "cli-predict")
    got = ap.predict(model, files, out_dir=tmp / "py-predict")
    expected = json.loads((tmp / "cli-predict" / "predict.json").read_text())
    ours = json.loads((tmp / "py-predict" / "predict.json").read_text())
    assert _without_times(ours) == _without_times(expected)
    assert got.control == "force" and got.control_source.startswith("stated in the header")
    assert [f.file for f in got.files] == [str(f) for f in files]
    for f, theirs in zip(got.files, expected["prediction"]["files"]):
        assert f.errors.peak_error == theirs["errors"]["peak_error"]
        assert f.force_rms_error is None
    # Without out_dir nothing is written, and the numbers are the same.
    again = ap.predict(model, files)
    assert again.written == [] and again.text == got.text


def test_bad_arguments_name_the_parameter(identified, tmp_path):
    files, tmp, _ = identified
    with pytest.raises(ap.ParameterError, match="family"):
        ap.identify(files, family="coulomb")
    with pytest.raises(ap.ParameterError, match="--chain-steps"):
        ap.identify(files, chain_steps=10)
    with pytest.raises(ap.ParameterError, match="--candidates"):
        ap.identify(files, candidates=["bogus"])
    with pytest.raises(ap.ParameterError, match="control"):
        ap.predict(tmp / "cli" / "model.json", files, control="displacement")
    # A response-control flag that contradicts the files' headers is refused, nothing written.
    out = tmp_path / "refused"
    with pytest.raises(ap.ParameterError, match="--control"):
        ap.predict(tmp / "cli" / "model.json", files, control="response", out_dir=out)
    assert not out.exists() or not any(out.iterdir())
    # An output directory that is an input file is refused.
    with pytest.raises(ap.ParameterError, match="out_dir"):
        ap.identify(files, out_dir=files[0], **QUICK)
