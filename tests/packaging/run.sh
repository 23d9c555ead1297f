#!/usr/bin/env bash
# Installs the build into a scratch prefix P and uses it from outside the source tree:
#  1. find_package(implicit): builds and runs README.md's library example, extracted from README.md;
#  2. pkg-config: compiles and runs a consumer with `pkg-config --cflags --libs implicit`;
#  3. Python: imports the package from P with the documented PYTHONPATH and checks that
#     implicit.mcl.run gives the installed CLI's numbers (the README's acceptance command);
#  4. the CLI: P/bin/implicit --version, an MCL run on the installed data, and the error when
#     the data folder cannot be found.
# Fails (exit 1) with the step's name and output on the first step that does not work.
set -euo pipefail

source_dir="" build_dir="" work="" cmake=cmake python="" python_dir="" cli=0
while [ $# -gt 0 ]; do
  case "$1" in
    --source) source_dir="$2"; shift 2 ;;
    --build) build_dir="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --cmake) cmake="$2"; shift 2 ;;
    --python) python="$2"; shift 2 ;;
    --python-dir) python_dir="$2"; shift 2 ;;
    --cli) cli=1; shift ;;
    *) echo "run.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
here="$(cd "$(dirname "$0")" && pwd)"
fail() { echo "packaging: FAILED: $*" >&2; exit 1; }
step() { echo "packaging: $*"; }

rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
step "install into $prefix"
"$cmake" --install "$build_dir" --prefix "$prefix" > "$work/install.log" || {
  cat "$work/install.log"; fail "cmake --install"; }
for f in include/implicit/core/implicit_sampler.hpp include/implicit/build_info.hpp \
         lib/cmake/implicit/implicitConfig.cmake lib/pkgconfig/implicit.pc \
         share/implicit/data/carpark/carpark_dr.csv share/implicit/data/report/paper.json \
         share/implicit/data/report/reference.json share/implicit/plots/figure1.py; do
  [ -e "$prefix/$f" ] || fail "the install has no $f"
done
# Random123 sits in /usr/include on Debian, so a consumer would compile even if the package forgot
# it: check that the exported target carries it.
grep -q "implicit::Random123" "$prefix/lib/cmake/implicit/implicitTargets.cmake" ||
  fail "the exported target implicit::implicit does not link implicit::Random123"
# Nothing installed may point back into the source or build tree.
if grep -rlI -e "$source_dir" -e "$build_dir" "$prefix/lib" "$prefix/include" 2>/dev/null; then
  fail "installed files above name the source or build folder"
fi

# 1. README example with find_package. The program is the first C++ block after the heading
# "## The library in 15 lines", so the test follows the README as it changes.
consumer="$work/consumer"
mkdir -p "$consumer"
cp "$here/consumer/CMakeLists.txt" "$consumer/"
awk '/^## The library in/ {found = 1; next}
     found && /^```cpp/ {inside = 1; next}
     inside && /^```/ {exit}
     inside {print}' "$source_dir/README.md" > "$consumer/readme_example.cpp"
grep -q "int main" "$consumer/readme_example.cpp" ||
  fail "README.md has no C++ program under '## The library in ...'"
step "README example with find_package(implicit)"
( "$cmake" -S "$consumer" -B "$consumer/build" -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" && "$cmake" --build "$consumer/build" ) \
  > "$work/consumer.log" 2>&1 || { cat "$work/consumer.log"; fail "README example build"; }
(cd "$work" && "$consumer/build/readme_example") > "$work/readme_example.out" ||
  fail "README example run"
cat "$work/readme_example.out"
[ -s "$work/readme_example.out" ] || fail "README example printed nothing"

# 2. pkg-config consumer (exits 0 only when its log Z matches the exact value).
step "pkg-config consumer"
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
flags="$(pkg-config --cflags --libs implicit)" || fail "pkg-config --cflags --libs implicit"
echo "  pkg-config --cflags --libs implicit: $flags"
# shellcheck disable=SC2086  # the flags are words
c++ -O1 -o "$work/pkgconfig_consumer" "$here/pkgconfig_consumer.cpp" $flags ||
  fail "pkg-config consumer build"
"$work/pkgconfig_consumer" || fail "pkg-config consumer run (log Z differs from the exact value)"

# 3. The Python package, imported from the prefix only (its data found from there too).
if [ -n "$python" ]; then
  step "Python package from PYTHONPATH=$prefix/$python_dir"
  (cd "$work" && unset IMPLICIT_DATA_DIR && PYTHONPATH="$prefix/$python_dir" "$python" -c \
    'import implicit, os, sys; p = implicit.__file__; print("  imported", p); sys.exit(0 if p.startswith(sys.argv[1]) and implicit._implicit.__file__.startswith(sys.argv[1]) else 1)' \
    "$prefix/") || fail "import implicit from the prefix"
  if [ "$cli" = 1 ]; then
    step "implicit.mcl.run equals implicit mcl --json"
    py_rmse="$(cd "$work" && unset IMPLICIT_DATA_DIR && PYTHONPATH="$prefix/$python_dir" "$python" -c \
      "import implicit; r = implicit.mcl.run(method='implicit', particles=100, runs=2, seed=1); print(repr(r['rmse_m']))")" ||
      fail "implicit.mcl.run from the prefix"
    cli_rmse="$(cd "$work" && unset IMPLICIT_DATA_DIR && "$prefix/bin/implicit" mcl --method implicit -M 100 --runs 2 --seed 1 --json |
      "$python" -c 'import json, sys; print(repr(json.load(sys.stdin)["rmse_m"]))')" || fail "implicit mcl --json"
    echo "  python $py_rmse, CLI $cli_rmse"
    [ "$py_rmse" = "$cli_rmse" ] || fail "implicit.mcl.run rmse_m $py_rmse differs from the CLI's $cli_rmse"
  fi
fi

# 4. The installed CLI, run from a folder outside the source tree with no data variables set.
if [ "$cli" = 1 ]; then
  unset IMPLICIT_DATA_DIR IMPLICIT_PLOTS_DIR
  run="$work/run"
  mkdir -p "$run"
  cd "$run"
  step "$prefix/bin/implicit --version"
  "$prefix/bin/implicit" --version || fail "implicit --version"
  step "implicit mcl -M 50 --runs 1 --json on the installed data"
  "$prefix/bin/implicit" mcl -M 50 --runs 1 --json > mcl.json || fail "implicit mcl"
  grep -q '"rmse' mcl.json || { cat mcl.json; fail "implicit mcl printed no RMSE"; }
  # Without its data folder the installed CLI must say where it looked (exit 1), not crash.
  step "a missing data folder is a clear error"
  mv "$prefix/share/implicit/data" "$prefix/share/implicit/data.away"
  set +e
  "$prefix/bin/implicit" mcl -M 50 --runs 1 --json > missing.out 2> missing.err
  code=$?
  set -e
  mv "$prefix/share/implicit/data.away" "$prefix/share/implicit/data"
  cat missing.err
  [ "$code" = 1 ] || fail "implicit mcl without data exited $code, expected 1"
  grep -q "share/implicit/data" missing.err && grep -q "IMPLICIT_DATA_DIR" missing.err ||
    fail "the error does not name where it looked and IMPLICIT_DATA_DIR"
fi
step "all steps passed"
