#!/usr/bin/env python3
"""The cost of a metric written in Python, per evaluation, against the same
metric in C++, on real tuners (benchmarks/RESULTS.md, issue 38).

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_metric_overhead.py [--evaluations N] [--repeats R]

Each tuner's problem (spec2fab.tuner_problem) is evaluated at the same random
points with the C++ metric and with its numpy twin, alternating, side by
side in one process; the table gives the median seconds per evaluation of R
repeats and the difference, which is the Python metric's overhead (the GIL
taken, two observations copied into arrays, the call, numpy's work).
"""

import argparse
import json
import pathlib
import statistics
import time

import numpy as np

import spec2fab

ROOT = pathlib.Path(__file__).resolve().parents[1]


class NumpyRgbMse(spec2fab.Metric):
    """rgb_mse in numpy."""
    compares = "albedo"

    def error(self, simulated, target):
        return float(np.mean((simulated - target) ** 2))


class NumpyImageMse(spec2fab.Metric):
    """image_mse in numpy."""
    compares = "image"

    def error(self, simulated, target):
        return float(np.mean((simulated - target) ** 2))


def colour_patches(metric):
    experiment = json.loads((ROOT / "datasets/experiments/colour_patches_box.json").read_text())
    for tuner in experiment["goal"]["tuners"]:
        tuner["metric"] = {"type": metric}
    return experiment


def caustic_slab(metric):
    """One tuner: the 8 x 8 B-spline top of a 60 x 60 mm clear board, its
    64 x 64-pixel caustic 200 mm below against the ring."""
    return {
        "name": "caustic_slab", "translator": "tree",
        "geometry": {"mesh": "../meshes/board_60x60x8.stl", "uv": "planar"},
        "goal": {
            "tree": {"type": "bspline", "control": [8, 8], "heights_mm": {"value": 6, "min": 2, "max": 8},
                     "below": {"type": "layered", "material": "VeroClear"},
                     "above": {"type": "layered", "material": "void"}},
            "tuners": [{"name": "slab", "node": "", "metric": {"type": metric},
                        "simulator": {"type": "caustics", "size_mm": [60, 60], "thickness_mm": 8,
                                      "vertices": [33, 33], "distance_mm": 200, "image": [64, 64]},
                        "goal": {"type": "caustic_image", "image": "../images/caustic_ring_120.png",
                                 "size": [64, 64], "receiver_mm": [60, 60], "flux_mm2": 3600},
                        "optimizer": {"type": "spsa"}}],
        },
        "output": {"slices": False, "stl": False, "3mf": False, "render": False},
        "materials": "../materials/polyjet.json", "printer": "../printers/j750.json",
    }


def per_evaluation(problem, points):
    start = time.perf_counter()
    for x in points:
        problem(x)
    return (time.perf_counter() - start) / len(points)


def measure(label, make, cpp_metric, python_metric, tuner, evaluations, repeats):
    origin = ROOT / "datasets/experiments/colour_patches_box.json"
    cpp = spec2fab.tuner_problem(make(cpp_metric), tuner=tuner, origin=origin)
    python = spec2fab.tuner_problem(make(python_metric), tuner=tuner, origin=origin)
    points = cpp.ask(evaluations, seed=1)
    assert abs(cpp(points[0]) - python(points[0])) <= 1e-12 * max(1.0, abs(cpp(points[0])))
    cpp_times, python_times = [], []
    for _ in range(repeats):
        cpp_times.append(per_evaluation(cpp, points))
        python_times.append(per_evaluation(python, points))
    c, p = statistics.median(cpp_times), statistics.median(python_times)
    print(f"| {label} | {c * 1e6:.2f} | {p * 1e6:.2f} | {(p - c) * 1e6:.2f} | {p / c:.2f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--evaluations", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    spec2fab.set_log_level("quiet")
    spec2fab.register(NumpyRgbMse, "numpy_rgb_mse")
    spec2fab.register(NumpyImageMse, "numpy_image_mse")
    print("| tuner | C++ metric (µs/eval) | Python metric (µs/eval) | overhead (µs/eval) | ratio |")
    print("|---|---|---|---|---|")
    measure("colour_patches_box 'sky': albedo of a 1-ink stack, rgb_mse", colour_patches, "rgb_mse",
            "numpy_rgb_mse", "sky", args.evaluations, args.repeats)
    measure("8 x 8 B-spline slab: 64 x 64 caustic image, image_mse", caustic_slab, "image_mse",
            "numpy_image_mse", "slab", max(args.evaluations // 50, 20), args.repeats)


if __name__ == "__main__":
    main()
