"""Bad input raises InputError with the command's one line."""

import json

import pytest

import spec2fab
from conftest import ROOT

EXPERIMENT = "datasets/experiments/colour_patches_box.json"


def experiment_dict():
    """The experiment with absolute paths, so that a copy works anywhere."""
    experiment = json.loads((ROOT / EXPERIMENT).read_text())
    folder = (ROOT / EXPERIMENT).parent
    for key in ("materials", "printer"):
        experiment[key] = str((folder / experiment[key]).resolve())
    experiment["geometry"]["mesh"] = str((folder / experiment["geometry"]["mesh"]).resolve())
    return experiment


def cli_message(cli, path):
    done = cli("validate", path, check=False)
    assert done.returncode == 2
    return done.stderr.strip().removeprefix("error: ")


def before_known(message):
    """A message up to its list of known names (Python parts registered by
    other tests add to the module's)."""
    return message.split(" (known: ")[0]


def test_a_missing_file_is_named(cli, tmp_path):
    missing = tmp_path / "nothing.json"
    with pytest.raises(spec2fab.InputError) as raised:
        spec2fab.validate(missing)
    assert str(raised.value) == cli_message(cli, missing)
    assert isinstance(raised.value, ValueError)


def test_an_unknown_part_is_named_with_its_json_path(cli, tmp_path):
    experiment = experiment_dict()
    experiment["goal"]["tuners"][1]["metric"]["type"] = "ciede2001"
    path = tmp_path / "unknown_metric.json"
    path.write_text(json.dumps(experiment))
    with pytest.raises(spec2fab.InputError, match=r"/goal/tuners/1/metric/type: unknown metric 'ciede2001'"):
        spec2fab.run(path, out=tmp_path / "out")
    assert not (tmp_path / "out").exists()
    with pytest.raises(spec2fab.InputError) as raised:
        spec2fab.validate(path)
    assert before_known(str(raised.value)) == before_known(cli_message(cli, path))


def test_a_dict_is_named_by_its_origin(tmp_path):
    experiment = experiment_dict()
    experiment["seed"] = -3
    with pytest.raises(spec2fab.InputError, match=r"datasets/experiments/colour_patches_box.json: /seed: "):
        spec2fab.validate(experiment, origin=ROOT / "datasets/experiments/colour_patches_box.json")


def test_a_value_json_cannot_hold_is_refused(tmp_path):
    experiment = experiment_dict()
    experiment["goal"]["tuners"][0]["goal"]["srgb"] = [float("nan"), 0.5, 0.5]
    with pytest.raises(spec2fab.InputError, match=r"/goal/tuners/0/goal/srgb/0: nan is not a JSON number"):
        spec2fab.validate(experiment, origin=EXPERIMENT)


def test_a_key_nobody_reads_is_named(tmp_path):
    experiment = experiment_dict()
    experiment["goal"]["tunerz"] = []
    with pytest.raises(spec2fab.InputError, match=r"/goal/tunerz"):
        spec2fab.validate(experiment, origin=EXPERIMENT)


def test_simulate_names_an_unknown_simulator():
    with pytest.raises(spec2fab.InputError, match="unknown simulator 'albedoo'"):
        spec2fab.simulate("albedoo", "datasets/simulations/albedo_cyan_over_white.json")
