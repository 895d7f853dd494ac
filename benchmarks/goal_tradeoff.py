#!/usr/bin/env python3
"""The trade-off a tuner of two terms reaches (issue 40): the shipped
balance_box with its limited term turned into a weighted one, at several
weights, and its core cut into CELLS cells along x (exhaustive search over
2^CELLS carvings). Prints, per weight: the grams carved (the objective), the
centre of mass's distance from the target across gravity (mm), the cells
carved and the tuning time.

  benchmarks/goal_tradeoff.py [--spec2fab build/spec2fab] [--cells 8] [--weights 0.5 1.8 8]
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHIPPED = ROOT / "datasets" / "experiments" / "balance_box.json"


def experiment(cells, weight):
    e = json.loads(SHIPPED.read_text())
    for key in ("materials", "printer"):
        e[key] = str((SHIPPED.parent / e[key]).resolve())
    e["geometry"]["mesh"] = str((SHIPPED.parent / e["geometry"]["mesh"]).resolve())
    # The core spans x = 2 … 38 mm: cells of 36/CELLS mm from x = 2 (their
    # faces on the mass sampling's 0.5 mm cell faces for 4, 8 or 9 cells, so
    # the sampled masses are the cells' own).
    e["goal"]["tree"]["core"]["size_mm"][0] = 36.0 / cells
    term = e["goal"]["tuners"][0]["terms"][0]
    if weight is not None:
        del term["at_most"]
        term["weight"] = weight
    e["output"] = {"slices": False, "stl": False, "3mf": False, "render": False}
    return e


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--spec2fab", default=str(ROOT / "build" / "spec2fab"))
    parser.add_argument("--cells", type=int, default=8)
    parser.add_argument("--weights", type=float, nargs="+", default=[0.5, 1.8, 8])
    args = parser.parse_args()
    print(f"balance_box, {args.cells} core cells along x, exhaustive over {2 ** args.cells} carvings")
    print("| term over_target | grams carved | offset (mm) | cells carved (x order) | whole run (s) |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for weight in [*args.weights, None]:
            file = pathlib.Path(tmp) / "e.json"
            file.write_text(json.dumps(experiment(args.cells, weight)))
            out = pathlib.Path(tmp) / f"out{weight}"
            start = time.time()
            run = subprocess.run([args.spec2fab, "run", "-q", str(file), "--out", str(out)], capture_output=True, text=True)
            if run.returncode != 0:
                sys.exit(f"spec2fab failed ({run.returncode}): {run.stdout}{run.stderr}")
            seconds = time.time() - start
            terms = json.loads((out / "result.json").read_text())["tuning"]["tuners"][0]["terms"]
            tree = json.loads((out / "tree.json").read_text())
            core = tree["core"]
            # tree.json writes one "child" when every cell holds the same.
            cells = core.get("children", [core.get("child")] * args.cells)
            carved = [i for i, c in enumerate(cells) if c["layers"][0]["material"]["value"] == "void"]
            rule = f"weight {weight:g} g/mm" if weight is not None else "at most 1.5 mm"
            print(f"| {rule} | {terms[0]['error']:.2f} | {terms[1]['error']:.2f} | {carved} | {seconds:.1f} |")


if __name__ == "__main__":
    main()
