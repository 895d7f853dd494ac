"""simulate returns the observation the command writes, as arrays."""

import csv
import json

import numpy as np
import pytest

import spec2fab
from conftest import ROOT

SIMULATIONS = ROOT / "datasets" / "simulations"


def cli_simulation(cli, simulator, config, out):
    cli("simulate", simulator, config, "--out", out, "--repeat", 1)
    return json.loads((out / "simulation.json").read_text())


@pytest.mark.parametrize("simulator, config, shape", [
    ("albedo", "albedo_cyan_over_white.json", (3,)),
    ("subsurface", "subsurface_white_over_cyan.json", (None, 3)),
])
def test_values_equal_the_commands(cli, tmp_path, simulator, config, shape):
    record = cli_simulation(cli, simulator, SIMULATIONS / config, tmp_path / "cli")
    observation = spec2fab.simulate(simulator, SIMULATIONS / config)
    assert observation.ndim == len(shape)
    assert all(want is None or want == got for want, got in zip(shape, observation.shape))
    assert isinstance(record["values"], list)
    np.testing.assert_array_equal(observation.ravel(), np.array(record["values"]))


def test_an_image_is_height_by_width(cli, tmp_path):
    config = SIMULATIONS / "caustics_dome.json"
    record = cli_simulation(cli, "caustics", config, tmp_path / "cli")
    image = spec2fab.simulate("caustics", config)
    assert image.ndim == 2 and image.shape[0] > 1 and image.shape[1] > 1
    assert image.max() > 1  # a caustic concentrates light
    assert image.shape == (240, 240) and isinstance(record["values"], list)
    np.testing.assert_array_equal(image.ravel(), np.array(record["values"]))


def test_displacements_are_n_by_3_and_equal_the_commands(cli, tmp_path):
    config = SIMULATIONS / "fem_cantilever.json"
    record = cli_simulation(cli, "fem", config, tmp_path / "cli")
    displacements = spec2fab.simulate("fem", config)
    assert displacements.ndim == 2 and displacements.shape[1] == 3
    # Probes first (simulation.json's probes), then the nodes (displacements.csv).
    probes = np.array([p["displacement_mm"] for p in record["probes"]])
    np.testing.assert_array_equal(displacements[: len(probes)], probes)
    with open(tmp_path / "cli" / "displacements.csv") as f:
        rows = list(csv.DictReader(f))
    nodes = np.array([[float(row[k]) for k in ("ux_mm", "uy_mm", "uz_mm")] for row in rows])
    assert displacements.shape[0] == len(probes) + len(nodes)
    np.testing.assert_allclose(displacements[len(probes):], nodes, rtol=1e-8, atol=1e-9)  # the CSV holds 9 digits


def test_a_dict_config_works_like_its_file():
    config = json.loads((SIMULATIONS / "albedo_cyan_over_white.json").read_text())
    from_dict = spec2fab.simulate("albedo", config, origin=SIMULATIONS / "albedo_cyan_over_white.json")
    np.testing.assert_array_equal(from_dict, spec2fab.simulate("albedo", SIMULATIONS / "albedo_cyan_over_white.json"))
