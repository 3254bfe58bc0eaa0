"""The build of `pip install --no-build-isolation .`: CMake builds the module's two shared
objects (the pybind11 core knotwork/_core and the PETSc module it loads on demand) in
build/pip/, and they are installed next to knotwork/__init__.py. Offline: nothing is
downloaded, and the libraries come from Debian (scripts/install-deps.sh). The metadata is in
pyproject.toml.

KNOTWORK_PIP_BUILD_DIR chooses another build folder.
"""
import os
import pathlib
import shutil
import subprocess

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = pathlib.Path(os.environ.get("KNOTWORK_PIP_BUILD_DIR") or ROOT / "build" / "pip")
        # Paths relative to the checkout in ccache's keys, as scripts/build.sh does.
        env = dict(os.environ, CCACHE_BASEDIR=str(ROOT))
        if not (build / "build.ninja").exists():
            subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                            "-DKNOTWORK_BUILD_TESTS=OFF", "-DKNOTWORK_BUILD_BENCH=OFF"], check=True, env=env)
        subprocess.run(["cmake", "--build", str(build), "--parallel", str(os.cpu_count() or 1), "--target",
                        "knotwork_python", "knotwork_petsc_module"], check=True, env=env)
        core = pathlib.Path(self.get_ext_fullpath(ext.name))
        core.parent.mkdir(parents=True, exist_ok=True)
        built = next((build / "python" / "knotwork").glob("_core*.so"))
        shutil.copy2(built, core)
        shutil.copy2(build / "solver" / "libknotwork_petsc.so", core.parent / "libknotwork_petsc.so")


setup(ext_modules=[Extension("knotwork._core", sources=[])], cmdclass={"build_ext": CMakeBuild})
