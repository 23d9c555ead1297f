"""Builds the Python package `implicit` for pip: `pip install --no-build-isolation .`

The compiled part (implicit._implicit) is the CMake target implicit_python, so the build is
CMake's: build_ext below configures the library and the module only (no tests, benchmarks,
examples or tool) and copies the module into the wheel beside python/implicit/*.py. The bundled
data go to <prefix>/share/implicit/data, where the package looks for them (implicit/_paths.py).

IMPLICIT_CMAKE_BUILD_DIR=<folder> takes the module from an existing CMake build folder instead
(configured and built with the same interpreter, e.g. the project's build/): nothing is compiled,
which is how the packaging test checks this path in seconds.
"""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def project_version():
    """The version of project() in CMakeLists.txt: one version for the library, tool and package."""
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    m = re.search(r"project\(\s*implicit\s+VERSION\s+([0-9.]+)", text)
    if not m:
        sys.exit("setup.py: no 'project(implicit VERSION x.y.z' in CMakeLists.txt")
    return m.group(1)


class CMakeBuild(build_ext):
    """Puts the CMake-built module where setuptools packs the extension implicit._implicit."""

    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        existing = os.environ.get("IMPLICIT_CMAKE_BUILD_DIR")
        if existing:
            cmake_build = Path(existing).resolve()
        else:
            cmake_build = Path(self.build_temp).resolve() / "cmake"
            self.run_cmake(cmake_build)
        module = cmake_build / "python" / "implicit" / target.name
        if not module.is_file():
            hint = " (IMPLICIT_CMAKE_BUILD_DIR)" if existing else ""
            sys.exit(f"setup.py: {module} does not exist: build the target implicit_python in "
                     f"{cmake_build}{hint} with this interpreter ({sys.executable}) first")
        target.parent.mkdir(parents=True, exist_ok=True)
        # A copy, not the build tree's link: the wheel must hold the file itself.
        shutil.copyfile(module, target)

    def run_cmake(self, cmake_build):
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(cmake_build), "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}", "-DIMPLICIT_BUILD_PYTHON=ON",
            "-DIMPLICIT_BUILD_TESTS=OFF", "-DIMPLICIT_BUILD_BENCHMARKS=OFF",
            "-DIMPLICIT_BUILD_EXAMPLES=OFF", "-DIMPLICIT_BUILD_APPS=OFF",
        ]
        # CMAKE_BUILD_PARALLEL_LEVEL, when set, is honoured by cmake --build itself.
        build = ["cmake", "--build", str(cmake_build), "--target", "implicit_python"]
        if "CMAKE_BUILD_PARALLEL_LEVEL" not in os.environ:
            build += ["-j", str(os.cpu_count() or 1)]
        for command in (configure, build):
            print(" ".join(command), flush=True)
            subprocess.run(command, check=True)


def data_files():
    """The bundled data sets, installed as <prefix>/share/implicit/data/... (folders kept)."""
    groups = {}
    for path in sorted((ROOT / "data").rglob("*")):
        if path.is_file():
            rel = path.relative_to(ROOT)
            groups.setdefault(str(Path("share/implicit") / rel.parent), []).append(str(rel))
    return sorted(groups.items())


setup(
    version=project_version(),
    packages=["implicit"],
    package_dir={"": "python"},
    package_data={"implicit": ["*.pyi", "py.typed"]},
    ext_modules=[Extension("implicit._implicit", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    data_files=data_files(),
    # setuptools' own scratch files go under build/pip (ignored by git), not into the sources.
    options={"build": {"build_base": "build/pip"}, "egg_info": {"egg_base": "build/pip"}},
    zip_safe=False,
)
