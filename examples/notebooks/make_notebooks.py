"""Writes the example notebooks from the cells below (the .ipynb files are
committed, without outputs; python/tests/test_notebooks.py runs them).

    python3 examples/notebooks/make_notebooks.py
"""

import pathlib

import nbformat
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

HERE = pathlib.Path(__file__).resolve().parent

SETUP = """\
import json, pathlib
import numpy as np
import matplotlib
import matplotlib.pyplot as plt
import spec2fab

spec2fab.set_log_level("quiet")
data = spec2fab.datasets            # the shipped meshes, images, materials, printers
out = pathlib.Path("out/notebooks")  # run folders go here, beside the notebook"""

NOTEBOOKS = {
    "albedo_own_image": [
        "# Albedo: your own image on a sphere\n\n"
        "The paper's Figure 7 prints the Earth as the surface colour of a sphere: every surface column is a stack "
        "of cyan, magenta, yellow and black layers over white, chosen so that its simulated albedo matches the "
        "image. Here the image is yours: replace `my_image.png` with any picture.",
        SETUP,
        "## Your image\n\nDrawn with numpy here; any PNG or JPEG works (the longer side maps to longitude).",
        """\
h, w = 48, 96
y, x = np.mgrid[0:h, 0:w] / np.array([h, w])[:, None, None]
image = np.stack([0.2 + 0.8 * x, 0.3 + 0.6 * np.abs(np.sin(6 * y)), 1.0 - 0.8 * x * y], axis=-1)
plt.imsave("my_image.png", np.clip(image, 0, 1))
plt.imshow(image); plt.title("the goal"); plt.axis("off");""",
        "## Run the albedo translator\n\nA 20 mm sphere (the shipped 50 mm one scaled by 0.4), previews only "
        "(no slices or meshes), so that it runs in seconds.",
        """\
experiment = {
    "name": "albedo_my_image",
    "translator": "albedo",
    "geometry": {"mesh": str(data / "meshes/sphere_r25.obj"), "uv": "mesh", "scale": 0.4},
    "goal": {"image": "my_image.png"},
    "output": {"slices": False, "stl": False, "3mf": False, "render_pixels": 384},
    "materials": str(data / "materials/polyjet.json"),
    "printer": str(data / "printers/j750.json"),
}
print(spec2fab.validate(experiment)["summary"])
run = spec2fab.run(experiment, out=out / "albedo_my_image")
run""",
        "## How close is it?\n\nΔE00 (CIEDE2000) between goal and achieved colours, over the colours the "
        "printer can reach (in gamut) and those it cannot.",
        """\
figures = run.result["albedo"]
print(json.dumps({k: v for k, v in figures.items() if "delta" in k}, indent=1)[:1500])""",
        """\
fig, axes = plt.subplots(1, 2, figsize=(12, 5))
for ax, name in zip(axes, ["preview/render.png", "preview/goal_vs_achieved.png"]):
    ax.imshow(plt.imread(run.file(name))); ax.set_title(name); ax.axis("off")""",
    ],
    "smooth_caustics": [
        "# Smooth caustics: a surface that casts an image\n\n"
        "Paper Fig. 9 (after Finckh et al. 2010): the top of a clear board is a B-spline surface shaped so that "
        "collimated light from above casts the goal image on a receiver below. The surface starts where optimal "
        "transport puts it and is refined by L-BFGS on the smooth estimator's derivative. Here at a coarse "
        "24 x 24 control grid, so that it runs in well under a minute.",
        SETUP,
        """\
experiment = json.loads((data / "experiments/smooth_caustics_ring.json").read_text())
experiment["name"] = "caustics_ring_small"
experiment["goal"].update({"control": [24, 24], "print_vertices_per_span": 2})
experiment["optimizer"]["max_evaluations"] = 60
experiment["output"] = {"slices": False, "3mf": False, "render": False}
run = spec2fab.run(experiment, out=out / "caustics_ring_small", origin=data / "experiments/smooth_caustics_ring.json")
figures = run.result["caustics"]
print({k: round(figures[k], 3) for k in ("initial_ssim", "ssim", "initial_psnr_db", "psnr_db", "relative_rmse")})""",
        "## The print, traced independently\n\nThe headline is what the exported `print/surface.stl` casts, traced by `caustic_check`, a tracer that "
        "shares no code with the simulator; it says whether it agrees with the simulated figure and, if not, why.",
        """\
headline = run.headline  # result.json's "headline"
print({k: round(headline[k], 3) for k in ("ssim", "psnr_db", "relative_rmse", "simulated_ssim")})
print(headline["agreement"])""",
        """\
previews = ["goal_vs_simulated.png", "height_map.png", "print_traced.png"]
fig, axes = plt.subplots(1, 3, figsize=(18, 6))
for ax, name in zip(axes, previews):
    picture = plt.imread(run.folder / "preview" / name)
    ax.imshow(picture, cmap="gray" if picture.ndim == 2 else None); ax.set_title(name); ax.axis("off")""",
        "## Convergence\n\nconvergence.csv: every tuner run's error by evaluation.",
        """\
import csv
rows = list(csv.DictReader(open(run.folder / "convergence.csv")))
evaluations = [float(r["evaluations"]) for r in rows]
errors = [float(r["error"]) for r in rows]
plt.semilogy(evaluations, errors); plt.xlabel("evaluations"); plt.ylabel("image error"); plt.grid(True);""",
        "## The simulator on its own\n\n`spec2fab.simulate` returns the observation as an array: here the "
        "caustic of a B-spline dome (irradiance in units of the incident light).",
        """\
image = spec2fab.simulate("caustics", data / "simulations/caustics_dome.json")
plt.imshow(image, cmap="inferno"); plt.colorbar(label="irradiance / incident"); plt.title(f"{image.shape}");""",
    ],
    "elastic_book": [
        "# The elastic book: materials that bend into a shape\n\n"
        "Paper Fig. 10: a 60 x 40 x 20 mm block in 4 x 2 x 1 cells, each rigid, rubber-like or a digital "
        "material, the spine clamped and 5 N pressing the cover's edge. The goal is the deformation of a hidden "
        "reference assignment; branch and bound, with the elastic bound, must find the assignment again "
        "(co-rotational FEM on a TetGen mesh).",
        SETUP,
        """\
experiment = data / "experiments/elastic_book.json"
run = spec2fab.run(experiment, out=out / "elastic_book")
book = run.result["elastic_book"]
print(json.dumps(book, indent=1)[:1500])""",
        """\
# goal probes vs achieved, the print's materials, branch and bound's search
fig, axes = plt.subplots(1, 3, figsize=(20, 6))
for ax, name in zip(axes, ["goal_vs_achieved.png", "render.png", "search.png"]):
    ax.imshow(plt.imread(run.folder / "preview" / name)); ax.set_title(name); ax.axis("off")""",
        "## Displacements as arrays\n\nThe FEM on its own (`spec2fab.simulate`): probes first, then every "
        "mesh node, one row of (ux, uy, uz) in mm.",
        """\
u = spec2fab.simulate("fem", data / "simulations/fem_book.json")
magnitude = np.linalg.norm(u, axis=1)
print(u.shape, "largest |u| =", magnitude.max().round(3), "mm")
plt.hist(magnitude, bins=40); plt.xlabel("|u| (mm)"); plt.ylabel("nodes");""",
    ],
    "python_optimizer_bench": [
        "# A Python optimizer in the bench matrix\n\n"
        "An optimizer written in numpy, registered by name, runs beside the C++ ones on the paper's tuning "
        "problems (`spec2fab bench`, docs/benchmarking.md), under the same budgets and seeds.",
        SETUP,
        """\
class OnePlusOne(spec2fab.Optimizer):
    \"\"\"(1+1) evolution strategy with the 1/5th success rule, in numpy.\"\"\"
    stochastic = True

    def minimize(self, problem, x, seed):
        rng = np.random.default_rng(seed)
        lower, upper = np.array(problem.lower), np.array(problem.upper)
        sigma = 0.3 * (upper - lower)
        best = problem(x)
        while True:  # problem(x) raises OptimizationStopped when the budget is spent
            y = np.clip(x + sigma * rng.standard_normal(len(x)), lower, upper)
            e = problem(y)
            if e <= best:
                x, best, sigma = y, e, sigma * 1.5
            else:
                sigma = sigma * 1.5 ** -0.25

spec2fab.register(OnePlusOne, "one_plus_one")
spec2fab.list("optimizer")["one_plus_one"]""",
        """\
report = spec2fab.bench(problems=["albedo_column", "facet_aiming"], optimizers=["annealing", "spsa", "one_plus_one"],
                        seeds=5, budget="40d", out=out / "bench")
for problem in report["problems"]:
    print(problem["name"])
    for e in problem["entrants"]:
        print(f"  {e['entrant']:14s} median final error {e['final_error']['median']:.4g}")""",
        """\
fig, axes = plt.subplots(1, len(report["problems"]), figsize=(6 * len(report["problems"]), 4))
for ax, problem in zip(np.atleast_1d(axes), report["problems"]):
    for e in problem["entrants"]:
        finals = sorted(r["best_error"] for r in e["run_list"])
        ax.step(finals, np.arange(1, len(finals) + 1) / len(finals), where="post", label=e["entrant"])
    ax.set_xscale("symlog", linthresh=1e-3); ax.set_title(problem["name"])
    ax.set_xlabel("final error"); ax.set_ylabel("share of runs"); ax.legend()""",
    ],
}


def main():
    for name, cells in NOTEBOOKS.items():
        notebook = new_notebook(cells=[new_markdown_cell(c) if c.startswith("#") else new_code_cell(c) for c in cells],
                                metadata={"kernelspec": {"name": "python3", "display_name": "Python 3",
                                                         "language": "python"}})
        nbformat.write(notebook, HERE / f"{name}.ipynb")


if __name__ == "__main__":
    main()
