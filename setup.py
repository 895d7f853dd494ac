"""Builds the extension spec2fab._spec2fab with the project's CMake (the
target spec2fab_python) and puts it beside the package's Python files.

    pip install --no-build-isolation .      # offline, Debian's setuptools

The CMake build folder is build-python/ (not build/, which setuptools uses
for itself); SPEC2FAB_BUILD_DIR=build reuses the folder scripts/build
release made. Every option of CMakeLists.txt applies through
SPEC2FAB_CMAKE_ARGS (e.g. "-DSPEC2FAB_WITH_TETGEN=OFF" for a module without
the AGPL mesher)."""

import os
import pathlib
import shlex
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("SPEC2FAB_BUILD_DIR", ROOT / "build-python"))
        if not build_dir.is_absolute():
            build_dir = ROOT / build_dir
        configure = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-G", "Ninja", "-DSPEC2FAB_WITH_PYTHON=ON"]
        if not (build_dir / "CMakeCache.txt").exists():
            # A folder of its own: this interpreter, the library alone. A
            # folder reused keeps its interpreter (checked below).
            configure += ["-DCMAKE_BUILD_TYPE=Release", f"-DPython3_EXECUTABLE={sys.executable}",
                          "-DSPEC2FAB_BUILD_TESTS=OFF", "-DSPEC2FAB_BUILD_BENCHMARKS=OFF"]
        configure += shlex.split(os.environ.get("SPEC2FAB_CMAKE_ARGS", ""))
        subprocess.run(configure, check=True)
        jobs = os.environ.get("SPEC2FAB_JOBS", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "spec2fab_python", "-j", jobs], check=True)
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        built = build_dir / "python" / "spec2fab" / f"_spec2fab{suffix}"
        if not built.exists():
            raise RuntimeError(f"{build_dir} builds the module for another Python than {sys.executable} "
                               f"(no {built.name}); unset SPEC2FAB_BUILD_DIR to build in a folder of its own")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)
        # The mesh reader program beside the extension, where load_mesh looks for it.
        shutil.copy2(build_dir / "spec2fab-read-mesh", target.parent / "spec2fab-read-mesh")


setup(ext_modules=[CMakeExtension("spec2fab._spec2fab")], cmdclass={"build_ext": CMakeBuild})
