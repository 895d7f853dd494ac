"""run and validate: files identical to the command's, whatever the threads."""

import json

import pytest

import spec2fab
from conftest import ROOT, assert_same_folders

EXPERIMENT = "datasets/experiments/colour_patches_box.json"


def experiment_dict():
    return json.loads((ROOT / EXPERIMENT).read_text())


def test_run_from_a_dict_writes_what_the_command_writes(cli, tmp_path):
    cli("run", EXPERIMENT, "--out", tmp_path / "cli", "--threads", 2)
    run = spec2fab.run(experiment_dict(), out=tmp_path / "python", threads=2, origin=EXPERIMENT)
    assert run.folder == tmp_path / "python"
    assert run.result["translator"] == "tree"
    assert run.result["inputs"]["experiment"] == EXPERIMENT
    assert run.tree == json.loads((tmp_path / "cli" / "tree.json").read_text())
    assert_same_folders(tmp_path / "cli", tmp_path / "python")


def test_run_is_deterministic_for_1_and_2_threads(tmp_path):
    one = spec2fab.run(EXPERIMENT, out=tmp_path / "one", threads=1, seed=7)
    two = spec2fab.run(EXPERIMENT, out=tmp_path / "two", threads=2, seed=7)
    assert one.result["seed"] == 7
    assert one.timing["threads"] == 1 and two.timing["threads"] == 2
    assert_same_folders(one.folder, two.folder)


def test_report_is_written_and_written_again(tmp_path):
    run = spec2fab.run(EXPERIMENT, out=tmp_path / "run", threads=2)
    page = run.report.read_bytes()
    assert page.startswith(b"<!doctype html>")
    run.report.unlink()
    assert spec2fab.report(run.folder) == run.folder / "report.html"
    assert run.report.read_bytes() == page
    bare = spec2fab.run(EXPERIMENT, out=tmp_path / "bare", threads=2, report=False)
    assert not (bare.folder / "report.html").exists()
    with pytest.raises(spec2fab.InputError, match="neither a run folder"):
        spec2fab.report(tmp_path)


def test_a_dict_without_origin_resolves_paths_from_the_current_folder(tmp_path):
    experiment = experiment_dict()
    for key in ("materials", "printer"):
        experiment[key] = "datasets/" + experiment[key].removeprefix("../")
    experiment["geometry"]["mesh"] = "datasets/" + experiment["geometry"]["mesh"].removeprefix("../")
    del experiment["name"]
    run = spec2fab.run(experiment, out=tmp_path / "here", threads=1)
    assert run.result["experiment"] == "experiment"
    assert run.result["inputs"]["experiment"] == "experiment.json"


def test_validate_says_what_it_found():
    found = spec2fab.validate(EXPERIMENT)
    assert found["name"] == "colour_patches_box"
    assert found["translator"] == "tree"
    assert found["triangles"] == 48
    assert found["volume_mm3"] == pytest.approx(40 * 30 * 20)
    assert "VeroCyan" in found["materials"]


def test_list_names_the_registered_parts():
    everything = spec2fab.list()
    assert "ciede2000" in everything["metric"]
    assert "albedo" in everything["translator"]
    assert spec2fab.list("metrics") == everything["metric"]
    assert "polyjet" in spec2fab.list("material")
    with pytest.raises(spec2fab.InputError, match="unknown kind 'frobnicate'"):
        spec2fab.list("frobnicate")


def test_help_answers_questions():
    assert "byte-identical to the command's" in spec2fab.run.__doc__
    assert "InputError" in spec2fab.__doc__


def test_long_work_releases_the_gil(tmp_path):
    """A thread counting in Python keeps a good share of its free-running
    pace while the C++ run works, measured around the extension call alone."""
    import threading
    import time
    from spec2fab import _spec2fab

    counted = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counted[0] += 1

    thread = threading.Thread(target=count)
    thread.start()
    try:
        time.sleep(0.05)
        start, before = time.perf_counter(), counted[0]
        time.sleep(0.5)
        free_rate = (counted[0] - before) / (time.perf_counter() - start)  # main thread asleep: no contention
        start, before = time.perf_counter(), counted[0]
        _spec2fab._run(EXPERIMENT, str(tmp_path / "run"), 1, None, None, False, True)
        during_rate = (counted[0] - before) / (time.perf_counter() - start)
    finally:
        stop.set()
        thread.join()
    assert during_rate > 0.3 * free_rate, (during_rate, free_rate)
