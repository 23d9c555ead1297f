#!/usr/bin/env bash
# The pip path as a user takes it, in a scratch venv: pyproject.toml -> setup.py's build_ext ->
# wheel -> install -> import from outside the source tree -> `python -m implicit --version`.
# The module is taken from the existing CMake build (IMPLICIT_CMAKE_BUILD_DIR), so nothing is
# compiled and the test takes seconds; the from-scratch build (which compiles the library) is
# the same setup.py with that variable unset.
#   pip_install.sh --python P --source S --build B --work W --version X.Y.Z
# Fails (exit 1) with the step's name on the first step that does not work.
set -euo pipefail

python="" source_dir="" build_dir="" work="" version=""
while [ $# -gt 0 ]; do
  case "$1" in
    --python) python="$2"; shift 2 ;;
    --source) source_dir="$2"; shift 2 ;;
    --build) build_dir="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --version) version="$2"; shift 2 ;;
    *) echo "pip_install.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
fail() { echo "pip_install: FAILED: $*" >&2; exit 1; }
step() { echo "pip_install: $*"; }
# The build tree's package must not be the one imported.
unset PYTHONPATH IMPLICIT_DATA_DIR

rm -rf "$work"
mkdir -p "$work"
venv="$work/venv"
step "venv $venv (--system-site-packages: Debian's numpy, setuptools and wheel serve)"
"$python" -m venv --system-site-packages "$venv" || fail "python -m venv"

step "pip install --no-build-isolation --no-index $source_dir"
IMPLICIT_CMAKE_BUILD_DIR="$build_dir" "$venv/bin/python" -m pip install --no-build-isolation \
  --no-index --no-cache-dir --disable-pip-version-check "$source_dir" > "$work/pip.log" 2>&1 || {
  cat "$work/pip.log"; fail "pip install"; }

step "IMPLICIT_CMAKE_BUILD_DIR without a built module: pip fails and names the missing file"
mkdir -p "$work/empty"
if IMPLICIT_CMAKE_BUILD_DIR="$work/empty" "$venv/bin/python" -m pip install --no-build-isolation \
  --no-index --no-cache-dir --disable-pip-version-check --force-reinstall --no-deps \
  "$source_dir" > "$work/pip_empty.log" 2>&1; then
  fail "pip install succeeded with IMPLICIT_CMAKE_BUILD_DIR=$work/empty"
fi
grep -q "$work/empty/python/implicit/_implicit.*does not exist" "$work/pip_empty.log" || {
  cat "$work/pip_empty.log"; fail "the error does not name the missing module"; }

cd "$work"  # outside the source tree: only the venv can provide the package
step "import implicit from the venv"
"$venv/bin/python" - "$venv" <<'PY' || fail "import implicit"
import os, sys
import numpy as np
import implicit
venv = os.path.realpath(sys.argv[1])
where = os.path.realpath(implicit.__file__)
assert where.startswith(venv + os.sep), f"implicit imported from {where}, not from {venv}"
core = implicit._implicit.__file__
assert not os.path.islink(core), f"{core} is a link into the build tree, not a copy"
# The bundled data, installed to <venv>/share/implicit/data, are found without IMPLICIT_DATA_DIR.
data = os.path.realpath(os.environ.get("IMPLICIT_DATA_DIR", ""))
assert data == os.path.join(venv, "share", "implicit", "data"), f"data folder {data!r}"
log = implicit.data.carpark()
r = implicit.sample(lambda x: 0.5 * x @ x, x0=np.zeros(2), n=200, seed=1)
assert abs(r.weights.sum() - 1.0) < 1e-12
print(f"pip_install: imported {where}; data in {data}")
PY

step "python -m implicit --version"
got="$("$venv/bin/python" -m implicit --version)" || fail "python -m implicit --version"
[ "$got" = "$version" ] || fail "python -m implicit --version printed '$got', the project is $version"
step "ok: implicit $got installed by pip into a scratch venv"
