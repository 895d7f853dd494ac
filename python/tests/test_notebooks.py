"""The example notebooks run top to bottom (nbclient), each within 2 minutes;
the executed copies, figures included, are kept under out/notebooks/ as the
test's artefacts."""

import os
import time

import pytest

from conftest import ROOT

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOKS = sorted((ROOT / "examples" / "notebooks").glob("*.ipynb"))
ARTEFACTS = ROOT / "out" / "notebooks"
os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # the kernel's debugger note about frozen modules


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path):
    notebook = nbformat.read(path, as_version=4)
    start = time.monotonic()
    nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    seconds = time.monotonic() - start
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    nbformat.write(notebook, ARTEFACTS / path.name)
    figures = sum(1 for cell in notebook.cells if cell.cell_type == "code"
                  for output in cell.get("outputs", []) if "image/png" in output.get("data", {}))
    assert figures >= 1, "a notebook shows what it made"
    assert seconds <= 120, f"{path.name} took {seconds:.0f} s"
