"""Shared fixtures: the repository root (tests run from it), the spec2fab
command built beside the module, and comparison of run folders."""

import filecmp
import os
import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def _from_root(monkeypatch):
    monkeypatch.chdir(ROOT)


@pytest.fixture(scope="session")
def cli():
    """Runs the spec2fab command (the build's: $SPEC2FAB_CLI or build/spec2fab)."""
    command = os.environ.get("SPEC2FAB_CLI", str(ROOT / "build" / "spec2fab"))

    def call(*arguments, check=True):
        done = subprocess.run([command, "-q", *map(str, arguments)], cwd=ROOT, capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"spec2fab {' '.join(map(str, arguments))}: exit {done.returncode}\n{done.stderr}")
        return done

    return call


def folder_files(folder: pathlib.Path):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def assert_same_folders(a: pathlib.Path, b: pathlib.Path, ignore=("timing.json",)):
    """Every file of a and b byte-identical (wall times aside)."""
    files_a = [f for f in folder_files(a) if f not in ignore]
    files_b = [f for f in folder_files(b) if f not in ignore]
    assert files_a == files_b
    different = [f for f in files_a if not same_file(a / f, b / f)]
    assert different == [], f"differ: {different[:10]}"


TIMING_BLOCK = re.compile(rb'(<script type="application/json" id="spec2fab-timing">).*?(</script>)', re.S)


def same_file(a: pathlib.Path, b: pathlib.Path) -> bool:
    """Byte-identical; report.html apart from its copy of timing.json."""
    if a.name == "report.html":
        return TIMING_BLOCK.sub(rb"\1\2", a.read_bytes()) == TIMING_BLOCK.sub(rb"\1\2", b.read_bytes())
    return filecmp.cmp(a, b, shallow=False)
