"""Spec2Fab from Python: run experiments, simulate, benchmark, and write parts.

Spec2Fab turns a functional specification (a texture to show, light to
scatter, a caustic image to cast, a shape to bend into) into a multi-material
3D print. This module binds the same typed C++ API the ``spec2fab`` command
runs, so files written from Python are identical to the command's.

    >>> import spec2fab
    >>> run = spec2fab.run("datasets/experiments/earth_sphere.json", out="out/earth")
    >>> run.result["albedo"]["delta_e00"]["in_gamut"]["mean"]   # doctest: +SKIP

Functions: run, validate, simulate, list, bench, tuner_problem, register.
Parts written in Python derive from Metric, Goal, Simulator or Optimizer and
are registered by name with ``register``; the name then works in experiments
run from this process, in ``validate`` and in ``bench``. Bad input raises
InputError (a ValueError) whose message is the command's one line: file,
JSON path, problem. Ctrl-C stops a run and removes its partial folder
(raising Stopped, a KeyboardInterrupt). See docs/python.md.
"""

from __future__ import annotations

import builtins
import inspect
import json
import os
import pathlib
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from . import _spec2fab
from ._spec2fab import InputError, OptimizationStopped, Problem, Stopped, WriteError

# `list` is left out: `from spec2fab import *` would hide the builtin.
__all__ = [
    "run", "validate", "simulate", "bench", "report", "tuner_problem", "tuner_names",
    "register", "register_bench_problem", "set_log_level",
    "Run", "Metric", "Goal", "Simulator", "Optimizer", "Problem",
    "InputError", "WriteError", "Stopped", "OptimizationStopped", "datasets",
]

__version__ = _spec2fab._version()

Experiment = Union[str, os.PathLike, Mapping[str, Any]]

#: The shipped datasets folder (materials, printers, meshes, experiments).
datasets = pathlib.Path(_spec2fab._datasets())


# Classes registered from Python, by kind and name, and bench problems' specs:
# the C++ registries' factories look them up there each time they build a
# part. They live on the extension, so that a reload of this package keeps
# them (the C++ registries keep the names).
_parts: dict = _spec2fab._parts
_bench_problems: dict = _spec2fab._bench_problems


class Run:
    """What ``run`` wrote: ``folder`` (a pathlib.Path), ``result`` (result.json
    as a dict: inputs, the goal's figures, tuning, fabrication, files) and
    ``tree`` (tree.json: the tuned reducer tree, which ``spec2fab export``
    reads)."""

    def __init__(self, folder: pathlib.Path):
        self.folder = folder
        self.result = json.loads((folder / "result.json").read_text())
        self.tree = json.loads((folder / "tree.json").read_text())

    @property
    def headline(self) -> Optional[dict]:
        """result.json's "headline", where the run has one: for the caustic
        translators, the exported print/surface.stl traced by caustic_check
        (a tracer sharing no code with the simulator) -- ssim, psnr_db,
        relative_rmse -- beside ``simulated_ssim`` and ``agreement`` (within
        0.02 SSIM, or why not). None for the other translators."""
        return self.result.get("headline")

    @property
    def timing(self) -> dict:
        """timing.json: wall times and threads (not part of the result, which
        is byte-identical whatever the machine)."""
        return json.loads((self.folder / "timing.json").read_text())

    @property
    def report(self) -> pathlib.Path:
        """report.html: the page to open first (goal beside achieved, figures,
        a 3D view of the print); self-contained, it works offline. Written by
        the run unless ``run(..., report=False)``; ``spec2fab.report(folder)``
        writes it again."""
        return self.file("report.html")

    def open_report(self) -> None:
        """Opens report.html in the system's web browser."""
        import webbrowser
        webbrowser.open(self.report.resolve().as_uri())

    def file(self, name: str) -> pathlib.Path:
        """A file of the run folder, e.g. ``run.file("preview/render.png")``."""
        path = self.folder / name
        if not path.exists():
            raise FileNotFoundError(f"{path}: not written by this run")
        return path

    def __repr__(self) -> str:
        traced = f", print traced: SSIM {self.headline['ssim']:.3f}" if self.headline else ""
        return f"Run({str(self.folder)!r}, translator={self.result.get('translator')!r}{traced})"


def _origin(experiment: Experiment, origin: Optional[Union[str, os.PathLike]]) -> Optional[str]:
    if origin is not None:
        return os.fspath(origin)
    return None


def run(experiment: Experiment, out: Optional[Union[str, os.PathLike]] = None, threads: Optional[int] = None,
        seed: Optional[int] = None, *, origin: Optional[Union[str, os.PathLike]] = None,
        resume: bool = False, report: bool = True) -> Run:
    """Runs an experiment and writes its run folder, as ``spec2fab run`` does.

    experiment: a path to an experiment file, or a dict in the same format
        (docs/experiment-format.md).
    out: the run folder (default ``out/<experiment name>``); written
        all-or-nothing: a run that fails or is stopped leaves nothing.
    threads: worker threads (default: all cores); the files do not depend on it.
    seed: overrides the experiment's seed (0 to 2**64 - 1).
    origin: for a dict, the file it stands for: its relative paths resolve
        against origin's folder (default: the current folder) and the run
        report records origin as the experiment. With the experiment file's
        own path, the run folder is byte-identical to the command's.
    resume: go on from the checkpoint of a killed run into the same folder.
    report: write report.html (``Run.report``); False leaves it out, as
        ``spec2fab run --no-report`` does.

    Returns a Run (``.folder``, ``.result``, ``.tree``). Raises InputError for
    bad input (the command's one line), WriteError when the system refuses a
    write, Stopped on Ctrl-C.
    """
    folder = _spec2fab._run(_experiment(experiment), None if out is None else os.fspath(out), threads, seed,
                            _origin(experiment, origin), resume, report)
    return Run(pathlib.Path(folder))


def report(folder: Union[str, os.PathLike]) -> pathlib.Path:
    """Writes report.html again for a run folder or a bench folder (as
    ``spec2fab report FOLDER``) and returns its path. Raises InputError for a
    folder that is neither."""
    return pathlib.Path(_spec2fab._report(os.fspath(folder)))


def _experiment(experiment: Experiment):
    if isinstance(experiment, (str, os.PathLike)):
        return os.fspath(experiment)
    if isinstance(experiment, Mapping):
        return dict(experiment)
    raise TypeError(f"experiment: a path or a dict, not {type(experiment).__name__}")


def validate(experiment: Experiment, *, origin: Optional[Union[str, os.PathLike]] = None) -> dict:
    """Checks an experiment without running it, as ``spec2fab validate``: loads
    its inputs, builds its translator and every part, and checks every key and
    limit. Returns what it found (name, translator, mesh, triangles,
    volume_mm3, printer, materials, tuning plan); raises InputError naming the
    first problem."""
    return _spec2fab._validate(_experiment(experiment), _origin(experiment, origin))


def simulate(simulator: str, config: Union[str, os.PathLike, Mapping[str, Any]], *,
             origin: Optional[Union[str, os.PathLike]] = None) -> np.ndarray:
    """Runs one simulator on a subtree, as ``spec2fab simulate`` (one
    evaluation, no files) and returns its observation as an array: an image
    height x width (x 3), an albedo (3,), a radial profile's coefficients
    (n x 3), displacements (probes, then mesh nodes) n x 3.

    config: a path or a dict with "materials", "printer", "subtree",
        optional "mesh" and "simulator" (its options); docs/simulate.md.
    """
    cfg = os.fspath(config) if isinstance(config, (str, os.PathLike)) else dict(config)
    return _spec2fab._simulate(simulator, cfg, _origin(config, origin))


def list(kind: Optional[str] = None) -> dict:  # noqa: A001 - the command's name
    """The registered parts, as ``spec2fab list``: {kind: {name: summary}},
    or {name: summary} for one kind ("node", "simulator", "metric", "goal",
    "optimizer", "translator", "bench", ..., "material", "printer"). Parts
    registered from Python are listed too."""
    kinds: dict = {}
    for registry_kind, _heading, entries in _spec2fab._registries():
        kinds[registry_kind] = {name: summary for name, summary in entries}
    for kind_name, classes in _parts.items():  # the summary of the class registered last
        for name, cls in classes.items():
            kinds[kind_name][name] = _summary(cls) + " (written in Python)"
    kinds["material"] = _dataset_names("materials")
    kinds["printer"] = _dataset_names("printers")
    if kind is None:
        return kinds
    key = kind[:-1] if kind.endswith("s") and kind[:-1] in kinds else kind
    if key not in kinds:
        raise InputError(f"list: unknown kind '{kind}' (known: {', '.join(kinds)})")
    return kinds[key]


def _dataset_names(folder: str) -> dict:
    names = {}
    for path in sorted((datasets / folder).glob("*.json")):
        try:
            names[path.stem] = json.loads(path.read_text()).get("description", "")
        except (OSError, ValueError):
            names[path.stem] = ""
    return names


def bench(problems: Optional[Sequence[str]] = None, optimizers: Optional[Sequence[str]] = None, seeds: int = 15,
          budget: str = "100d", out: Union[str, os.PathLike] = "out/bench", *, threads: Optional[int] = None,
          quick: bool = False, entrants: Optional[Union[str, os.PathLike]] = None) -> dict:
    """Runs the optimizer x problem matrix, as ``spec2fab bench``, writes its
    report into ``out`` (report.html, report.md, report.json, ioh/, plots/) and returns
    report.json as a dict.

    problems: registered bench problems (default: all), including those
        registered from Python (register_bench_problem).
    optimizers: entrant labels (default: every entrant and every registered
        optimizer, Python ones included).
    budget: "100d" (evaluations per dimension), "5000", "30s", or several.
    quick: a smoke test (3 seeds, 12d).
    """
    folder = _spec2fab._bench(builtins.list(problems or []), builtins.list(optimizers or []), seeds, budget,
                              os.fspath(out), threads, quick, None if entrants is None else os.fspath(entrants))
    return json.loads((pathlib.Path(folder) / "report.json").read_text())


def tuner_problem(experiment: Experiment, tuner: Optional[str] = None, *,
                  origin: Optional[Union[str, os.PathLike]] = None) -> Problem:
    """One tuner of an experiment as a plain problem for outside optimizers:
    ``problem(x) -> error``, ``problem.bounds`` [(lower, upper)],
    ``problem.dimension``, ``problem.kinds``, ``ask(n, seed)``/``tell(xs)``
    for batch methods, and ``best_x``/``best_error``.

    The tuner is the one the experiment's translator builds and binds, before
    its schedule runs (couplings from earlier phases not applied). tuner:
    its name (tuner_names lists them); needed when there are several.
    """
    return _spec2fab._tuner_problem(_experiment(experiment), tuner, _origin(experiment, origin))


def tuner_names(experiment: Experiment, *, origin: Optional[Union[str, os.PathLike]] = None) -> builtins.list:
    """The names of an experiment's tuners, for tuner_problem."""
    return _spec2fab._tuner_names(_experiment(experiment), _origin(experiment, origin))


def set_log_level(level: str) -> None:
    """'quiet' (warnings and errors), 'normal' (default) or 'verbose'."""
    if level not in ("quiet", "normal", "verbose"):
        raise ValueError(f"set_log_level: 'quiet', 'normal' or 'verbose', not {level!r}")
    _spec2fab._set_log_level(level)


# --- Parts written in Python -------------------------------------------------

class Metric:
    """An error metric written in Python: compares a simulated observation
    with a goal's target. Derive, set ``compares`` (the observation type:
    "image", "albedo", "vector", "radial_profile", "displacements", ...) and
    define ``error``. Options in the experiment's metric object (all keys but
    "type") are passed to the constructor as keyword arguments.

        class MeanSquare(spec2fab.Metric):
            compares = "image"
            def error(self, simulated, target):
                return float(np.mean((simulated - target) ** 2))
        spec2fab.register(MeanSquare, "mean_square")
    """

    compares = "image"

    def __init__(self, **options):
        self.options = options

    def error(self, simulated: np.ndarray, target: np.ndarray) -> float:
        """The error of ``simulated`` against ``target`` (arrays of the
        observation's shape, e.g. height x width x 3); smaller is better."""
        raise NotImplementedError


class Goal:
    """A goal written in Python: ``describes`` names the observation type
    ("image", "vector" or "albedo") and ``target()`` returns it as an array
    (height x width (x 3) for an image, (3,) for an albedo)."""

    describes = "image"

    def __init__(self, **options):
        self.options = options

    def target(self) -> np.ndarray:
        raise NotImplementedError


class Simulator:
    """A simulator written in Python: ``produces`` names the observation
    type ("image", "vector" or "albedo"); ``setup(subtree)`` is called once
    with the subtree in the tree format (a dict), ``simulate(parameters)`` at
    every evaluation with the subtree's parameters by path
    ({"layers/0/thickness_mm": 0.135, "layers/0/material": 1.0, ...}), and
    returns the observation as an array. A material parameter's value is an
    index into ``self.materials``, the run's material names (set before
    setup)."""

    produces = "vector"

    def __init__(self, **options):
        self.options = options

    def setup(self, subtree: dict) -> None:
        self.subtree = subtree

    def simulate(self, parameters: Mapping[str, float]) -> np.ndarray:
        raise NotImplementedError


class Optimizer:
    """An optimizer written in Python: ``minimize(problem, x, seed)`` searches
    from the start point ``x`` and returns the best point it found (or None:
    the best it evaluated). ``problem`` (a Problem, valid during the call)
    gives ``dimension``, ``lower``, ``upper``, ``kinds`` and ``problem(x)``;
    when the run must stop (the bench's budget), ``problem(x)`` raises
    OptimizationStopped — let it propagate. ``seed`` is the run's seed for
    this tuner (use it for every random draw: runs stay reproducible).
    Set ``stochastic = True`` when runs that differ in seed may differ, and
    ``requirements = ("gradient",)`` for a problem's capabilities you need."""

    stochastic = False
    requirements: Sequence[str] = ()

    def __init__(self, **options):
        self.options = options

    def minimize(self, problem: Problem, x: np.ndarray, seed: int) -> Optional[np.ndarray]:
        raise NotImplementedError


_BASES = {Metric: "metric", Goal: "goal", Simulator: "simulator", Optimizer: "optimizer"}


def register(cls: type, name: str) -> type:
    """Registers a part class written in Python under ``name``: a subclass of
    Metric, Goal, Simulator or Optimizer. The name then works like a C++
    part's in experiments run from this process, in validate and in bench
    (a registered optimizer joins bench's entrants), with the same checks
    (observation types must agree). Registering a name again replaces the
    class (a notebook cell run twice); a C++ part's name is refused.
    Returns cls. Register before a run starts, not from another thread
    during one."""
    if not inspect.isclass(cls):
        raise TypeError("register: pass the class, not an instance")
    kinds = [kind for base, kind in _BASES.items() if issubclass(cls, base)]
    if len(kinds) != 1:
        raise TypeError(f"register: {cls.__name__} must derive from one of spec2fab.Metric, Goal, Simulator, Optimizer")
    kind = kinds[0]
    if not name or not all(c.isalnum() or c in "_-." for c in name):
        raise ValueError(f"register: '{name}': use letters, digits, '_', '-' and '.'")
    if name not in _parts[kind]:
        _spec2fab._add_to_registry(kind, name, _summary(cls))
    _parts[kind][name] = cls
    return cls


def _summary(cls: type) -> str:
    """The first line of the class's own docstring (not its base's)."""
    doc = cls.__dict__.get("__doc__")
    return inspect.cleandoc(doc).splitlines()[0] if doc else cls.__name__


def register_bench_problem(name: str, spec: Mapping[str, Any], summary: str = "") -> None:
    """Adds a problem to bench's matrix: ``spec`` in the TunerBenchmark form
    (docs/benchmarking.md): "materials", "printer", "subtree" with free
    parameters, "simulator", "metric" (a Python metric's name works) and
    "reference", the hidden assignment whose simulation is the goal. Relative
    paths resolve against the datasets folder. Registering a name again
    replaces its spec."""
    if name not in _bench_problems:
        _spec2fab._add_bench_problem(name, summary or f"{name} (registered from Python)")
    _bench_problems[name] = json.loads(json.dumps(spec))
