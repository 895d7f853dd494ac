"""Parts written in Python: registered by name, they tune shipped experiments
and join the bench beside the C++ parts, with the same checks."""

import json

import numpy as np
import pytest

import spec2fab
from conftest import ROOT

EXPERIMENT = "datasets/experiments/colour_patches_box.json"


class NumpyRgbMse(spec2fab.Metric):
    """Mean squared difference of linear RGB albedos, in numpy."""

    compares = "albedo"

    def error(self, simulated, target):
        return float(np.mean((simulated - target) ** 2))


class RandomSearch(spec2fab.Optimizer):
    """Uniform random search within the bounds."""

    stochastic = True

    def __init__(self, samples=1_000_000):
        super().__init__()
        self.samples = samples

    def minimize(self, problem, x, seed):
        rng = np.random.default_rng(seed)
        lower, upper = np.array(problem.lower), np.array(problem.upper)
        for _ in range(self.samples):
            problem(rng.uniform(lower, upper))  # raises OptimizationStopped once the budget is spent
        return None


spec2fab.register(NumpyRgbMse, "numpy_rgb_mse")
spec2fab.register(RandomSearch, "random_search")


def with_metric(metric):
    experiment = json.loads((ROOT / EXPERIMENT).read_text())
    for tuner in experiment["goal"]["tuners"]:
        tuner["metric"] = {"type": metric}
    return experiment


def test_a_numpy_metric_tunes_a_shipped_experiment_as_its_cpp_twin_does(tmp_path):
    cpp = spec2fab.run(with_metric("rgb_mse"), out=tmp_path / "cpp", threads=2, origin=EXPERIMENT)
    python = spec2fab.run(with_metric("numpy_rgb_mse"), out=tmp_path / "python", threads=2, origin=EXPERIMENT)
    assert python.tree == cpp.tree  # the same inks and thicknesses chosen
    runs = zip(python.result["tuning"]["tuner_runs"], cpp.result["tuning"]["tuner_runs"])
    for a, b in runs:
        assert a["tuner"] == b["tuner"] and a["evaluations"] == b["evaluations"]
        assert a["final_error"] == pytest.approx(b["final_error"], rel=1e-12)


def test_parts_are_checked_like_cpp_ones():
    class ImageOnly(spec2fab.Metric):
        """Compares images."""
        compares = "image"

        def error(self, simulated, target):
            return 0.0

    spec2fab.register(ImageOnly, "image_only_metric")
    with pytest.raises(spec2fab.InputError, match=r"image_only_metric.*image|albedo.*image"):
        spec2fab.validate(with_metric("image_only_metric"), origin=EXPERIMENT)
    with pytest.raises(ValueError, match="already registered"):
        spec2fab.register(NumpyRgbMse, "ciede2000")
    with pytest.raises(TypeError):
        spec2fab.register(object, "nothing")
    assert "numpy_rgb_mse" in spec2fab.list("metric")


def test_a_python_metric_and_optimizer_join_the_bench(tmp_path):
    spec = {
        "materials": "materials/polyjet.json",
        "printer": "printers/j750.json",
        "subtree": {"type": "layered", "layers": [
            {"material": ink, "thickness_mm": {"value": 0.0, "min": 0.0, "max": 0.135, "step": 0.027}}
            for ink in ("VeroCyan", "VeroMagenta", "VeroYellow")] + [{"material": "VeroWhitePlus"}]},
        "simulator": {"type": "albedo", "depth_mm": 0.5},
        "metric": {"type": "numpy_rgb_mse"},
        "reference": [0.054, 0.0, 0.108],
    }
    spec2fab.register_bench_problem("albedo_numpy", spec, "three inks over white, a numpy metric")
    report = spec2fab.bench(problems=["albedo_numpy"], optimizers=["exhaustive", "random_search"], seeds=2,
                            budget="100d", out=tmp_path / "bench")
    assert (tmp_path / "bench" / "report.md").exists()
    [problem] = [p for p in report["problems"] if p["name"] == "albedo_numpy"]
    entrants = {e["entrant"]: e for e in problem["entrants"]}
    assert set(entrants) == {"exhaustive", "random_search"}
    # 6^3 = 216 stacks within the budget of 300: the hidden reference is found.
    assert entrants["exhaustive"]["final_error"]["median"] == pytest.approx(0, abs=1e-12)
    random_runs = entrants["random_search"]["run_list"]
    assert entrants["random_search"]["stochastic"] and len(random_runs) == 2
    assert all(r["evaluations"] == 300 and r["termination"] == "user_terminate" for r in random_runs)
    assert [r["seed"] for r in random_runs] == [1, 2]


def test_scipy_drives_a_tuner_problem():
    scipy_optimize = pytest.importorskip("scipy.optimize")
    names = spec2fab.tuner_names(EXPERIMENT)
    assert names == ["sky", "rose", "lemon", "teal"]
    problem = spec2fab.tuner_problem(EXPERIMENT, tuner="rose")
    assert problem.dimension == 2 and problem.kinds == ["choice", "discrete"]
    start = problem.error(problem.snap([0, 0.135]))
    found = scipy_optimize.differential_evolution(problem, problem.bounds, seed=1, maxiter=20, polish=False)
    assert found.fun < start
    assert problem.evaluations >= found.nfev + 1
    # Every one of the tuner's 63 stacks (inks are palette ids 1-3: cyan, magenta, yellow).
    exhaustive = min(problem.error([ink, 0.027 * k]) for ink in (1.0, 2.0, 3.0) for k in range(21))
    assert found.fun == pytest.approx(exhaustive, rel=1e-9)
    assert problem.best_error == pytest.approx(exhaustive, rel=1e-9)
    batch = problem.ask(8, seed=3)
    assert len(batch) == 8 and all(problem.bounds[1][0] <= x[1] <= problem.bounds[1][1] for x in batch)
    assert len(problem.tell(batch)) == 8
    with pytest.raises(spec2fab.InputError, match="name one with tuner="):
        spec2fab.tuner_problem(EXPERIMENT)


# A toy layered-albedo model (Beer-Lambert through one ink layer over white),
# its goal in numpy too: the tree translator's exhaustive search must pick
# the stack a brute force over the same model picks.
ABSORPTION = {"VeroCyan": [9.0, 1.0, 0.4], "VeroMagenta": [1.0, 9.0, 1.5], "VeroYellow": [0.3, 1.2, 9.0]}


def toy_albedo(ink, thickness_mm):
    return np.exp(-2 * thickness_mm * np.array(ABSORPTION[ink]))


class ToyAlbedo(spec2fab.Simulator):
    """One ink layer over white, Beer-Lambert, there and back."""

    produces = "albedo"

    def setup(self, subtree):
        assert subtree["type"] == "layered"

    def simulate(self, parameters):
        ink = self.materials[int(parameters["layers/0/material"])]
        return toy_albedo(ink, parameters["layers/0/thickness_mm"])


class RgbGoal(spec2fab.Goal):
    """A linear RGB albedo."""

    describes = "albedo"

    def __init__(self, rgb):
        super().__init__()
        self.rgb = rgb

    def target(self):
        return np.array(self.rgb, dtype=float)


def test_a_python_simulator_and_goal_tune_a_tree(tmp_path):
    spec2fab.register(ToyAlbedo, "toy_albedo")
    spec2fab.register(RgbGoal, "rgb_goal")
    experiment = json.loads((ROOT / EXPERIMENT).read_text())
    targets = {"sky": [0.3, 0.7, 0.8], "rose": [0.7, 0.2, 0.6], "lemon": [0.8, 0.75, 0.1], "teal": [0.1, 0.6, 0.7]}
    for tuner in experiment["goal"]["tuners"]:
        tuner["simulator"] = {"type": "toy_albedo"}
        tuner["metric"] = {"type": "rgb_mse"}
        tuner["goal"] = {"type": "rgb_goal", "rgb": targets[tuner["name"]]}
    experiment["goal"]["schedule"] = [{"name": "patches", "mode": "serial"}]  # no coupling: each on its own
    run = spec2fab.run(experiment, out=tmp_path / "toy", origin=EXPERIMENT)
    thicknesses = 0.027 * np.arange(21)
    for index, name in enumerate(["sky", "rose", "lemon", "teal"]):
        ink, t = min(((ink, t) for ink in ABSORPTION for t in thicknesses),
                     key=lambda c: np.mean((toy_albedo(*c) - targets[name]) ** 2))
        layer = run.tree["shell"]["children"][index]["layers"][0]
        assert layer["material"]["value"] == ink
        assert layer["thickness_mm"]["value"] == pytest.approx(t, abs=1e-12)
        record = next(r for r in run.result["tuning"]["tuner_runs"] if r["tuner"] == name)
        assert record["final_error"] == pytest.approx(np.mean((toy_albedo(ink, t) - targets[name]) ** 2), rel=1e-9)


def test_a_python_metric_run_is_deterministic_for_1_and_2_threads(tmp_path):
    from conftest import assert_same_folders
    one = spec2fab.run(with_metric("numpy_rgb_mse"), out=tmp_path / "one", threads=1, origin=EXPERIMENT)
    two = spec2fab.run(with_metric("numpy_rgb_mse"), out=tmp_path / "two", threads=2, origin=EXPERIMENT)
    assert_same_folders(one.folder, two.folder)


def test_a_python_part_that_raises_raises_through_the_run(tmp_path):
    class Broken(spec2fab.Metric):
        """Raises."""
        compares = "albedo"

        def error(self, simulated, target):
            raise ZeroDivisionError("metric bug")

    spec2fab.register(Broken, "broken_metric")
    with pytest.raises(ZeroDivisionError, match="metric bug"):
        spec2fab.run(with_metric("broken_metric"), out=tmp_path / "out", threads=2, origin=EXPERIMENT)
    assert not (tmp_path / "out").exists()


def test_a_python_optimizer_with_bad_requirements_is_refused(tmp_path):
    class NeedsText(spec2fab.Optimizer):
        """requirements as a string, a missing comma."""
        requirements = ("gradient")

    class NeedsNothingKnown(spec2fab.Optimizer):
        """An unknown capability."""
        requirements = ("telepathy",)

    spec2fab.register(NeedsText, "needs_text")
    spec2fab.register(NeedsNothingKnown, "needs_telepathy")
    experiment = with_metric("rgb_mse")
    experiment["goal"]["tuners"][0]["optimizer"] = {"type": "needs_text"}
    with pytest.raises(spec2fab.InputError, match=r"/goal/tuners/0/optimizer.*requirements is a string"):
        spec2fab.validate(experiment, origin=EXPERIMENT)
    experiment["goal"]["tuners"][0]["optimizer"] = {"type": "needs_telepathy"}
    with pytest.raises(spec2fab.InputError, match=r"'telepathy' is no capability \(gradient, residuals"):
        spec2fab.validate(experiment, origin=EXPERIMENT)
    experiment["goal"]["tuners"][0]["optimizer"] = {"type": "random_search", "samples": 10, "colour": "red"}
    with pytest.raises(spec2fab.InputError, match=r"random_search' refused its options.*colour"):
        spec2fab.validate(experiment, origin=EXPERIMENT)


def test_registering_a_name_again_replaces_the_class(tmp_path):
    class Zero(spec2fab.Metric):
        """Always 0."""
        compares = "albedo"

        def error(self, simulated, target):
            return 0.0

    class One(spec2fab.Metric):
        """Always 1."""
        compares = "albedo"

        def error(self, simulated, target):
            return 1.0

    spec2fab.register(Zero, "constant_metric")
    assert spec2fab.list("metric")["constant_metric"].startswith("Always 0.")
    spec2fab.register(One, "constant_metric")
    assert spec2fab.list("metric")["constant_metric"].startswith("Always 1.")
    problem = spec2fab.tuner_problem(with_metric("constant_metric"), tuner="sky", origin=EXPERIMENT)
    assert problem([1.0, 0.027]) == 1.0


def test_a_problem_kept_past_minimize_refuses_to_be_used(tmp_path):
    kept = []

    class Keeper(spec2fab.Optimizer):
        """Keeps the problem."""

        def minimize(self, problem, x, seed):
            kept.append(problem)
            problem(x)
            return x

    spec2fab.register(Keeper, "keeper")
    experiment = with_metric("rgb_mse")
    for tuner in experiment["goal"]["tuners"]:
        tuner["optimizer"] = {"type": "keeper"}
    spec2fab.run(experiment, out=tmp_path / "out", threads=1, origin=EXPERIMENT)
    assert len(kept) == 4
    with pytest.raises(RuntimeError, match="minimize\\(\\), which has returned"):
        kept[0]([1.0, 0.0])
    with pytest.raises(RuntimeError):
        kept[0].dimension


def test_optimization_stopped_gets_through_except_exception(tmp_path):
    class Stubborn(spec2fab.Optimizer):
        """Swallows every Exception."""
        stochastic = True

        def minimize(self, problem, x, seed):
            rng = np.random.default_rng(seed)
            for _ in range(10_000):
                try:
                    problem(rng.uniform(problem.lower, problem.upper))
                except Exception:
                    pass
            return None

    spec2fab.register(Stubborn, "stubborn")
    report = spec2fab.bench(problems=["albedo_column"], optimizers=["stubborn"], seeds=1, budget="10d",
                            out=tmp_path / "bench")
    [entrant] = report["problems"][0]["entrants"]
    assert entrant["run_list"][0]["evaluations"] == 40
