"""Builds the Python module with CMake for `pip install --no-build-isolation .` (pyproject.toml).

The extension _cullide is CMake's target of that name (python/CMakeLists.txt), configured in
build-pip/ for the interpreter running pip; the package gets the bundled data and scripts in
cullide/share/ (data/, tools/), where cullide/__init__.py looks first. Extra CMake arguments:
the environment variable CMAKE_ARGS (space-separated).
"""

import glob
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        package = os.path.dirname(os.path.abspath(self.get_ext_fullpath(ext.name)))
        build = os.path.join(SOURCE, "build-pip")
        configure = ["cmake", "-S", SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                     "-DPython3_EXECUTABLE=" + sys.executable, "-DCULLIDE_PYTHON=ON",
                     "-DCULLIDE_BUILD_TESTS=OFF", "-DCULLIDE_BUILD_BENCH=OFF"]
        if shutil.which("ccache"):
            configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
        configure += os.environ.get("CMAKE_ARGS", "").split()
        subprocess.check_call(configure)
        subprocess.check_call(["cmake", "--build", build, "--target", "_cullide", "-j", str(os.cpu_count() or 2)])
        os.makedirs(package, exist_ok=True)
        (built,) = glob.glob(os.path.join(build, "python", "cullide", "_cullide*.so"))
        shutil.copy2(built, self.get_ext_fullpath(ext.name))
        share = os.path.join(package, "share")
        shutil.rmtree(share, ignore_errors=True)
        shutil.copytree(os.path.join(SOURCE, "data"), os.path.join(share, "data"))
        os.makedirs(os.path.join(share, "tools", "trace"))
        shutil.copy2(os.path.join(SOURCE, "tools", "plot.py"), os.path.join(share, "tools"))
        shutil.copytree(os.path.join(SOURCE, "tools", "plotting"), os.path.join(share, "tools", "plotting"),
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        shutil.copy2(os.path.join(SOURCE, "tools", "trace", "replay_reference.py"),
                     os.path.join(share, "tools", "trace"))


setup(
    packages=["cullide"],
    package_dir={"cullide": "python/cullide"},
    ext_modules=[Extension("cullide._cullide", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
    # setuptools' own build folders beside CMake's, not inside the CMake build tree build/.
    options={"build": {"build_base": "build-pip/setuptools"}},
)
