#!/usr/bin/env bash
# The acceptance run of the install: `P/bin/implicit reproduce --quick --out Q` from a folder
# outside the source tree, with the prefix that packaging_install left (its fixture). Every
# experiment and figure must succeed (the tool exits non-zero otherwise) using only the installed
# data and plot scripts.
set -euo pipefail
work="$1"
prefix="$work/prefix"
[ -x "$prefix/bin/implicit" ] || { echo "reproduce: no installed $prefix/bin/implicit" >&2; exit 1; }
unset IMPLICIT_DATA_DIR IMPLICIT_PLOTS_DIR
run="$work/reproduce"
rm -rf "$run"
mkdir -p "$run"
cd "$run"
start=$(date +%s)
"$prefix/bin/implicit" reproduce --quick --out Q --quiet
echo "reproduce: $(($(date +%s) - start)) s"
for f in Q/report.md Q/results.json Q/figure1.png Q/figure7.png; do
  [ -s "$f" ] || { echo "reproduce: FAILED: no $f" >&2; exit 1; }
done
if grep -q '"status": "failed"' Q/results.json; then
  echo "reproduce: FAILED: results.json records a failure" >&2
  exit 1
fi
echo "reproduce: all experiments and figures ok"
