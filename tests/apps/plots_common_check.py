"""Checks python/plots/common.py: bad figure data fails loudly, naming file, line and column.

Usage: plots_common_check.py PLOTS_DIR TMP_DIR   (exit 0 when every check passes)
"""
import subprocess
import sys
from pathlib import Path

plots, tmp = Path(sys.argv[1]), Path(sys.argv[2])
sys.path.insert(0, str(plots))
from common import DataError, load_csv  # noqa: E402

(tmp / "good.csv").write_text("t,x,method\n0,1.5,implicit\n1,,standard\n")
(tmp / "bad_number.csv").write_text("t,x\n0,1\n1,oops\n")
(tmp / "short_row.csv").write_text("t,x\n0,1\n1\n")
(tmp / "header_only.csv").write_text("t,x\n")

good = load_csv(tmp, "good.csv", ["t", "x"], ["method"])
assert list(good["t"]) == [0.0, 1.0], good
assert good["x"][0] == 1.5 and good["x"][1] != good["x"][1], "empty cell must read as NaN"
assert list(good["method"]) == ["implicit", "standard"], good

cases = [
    ("missing.csv", ["t"], ["missing.csv", "not found"]),
    ("good.csv", ["y"], ["good.csv", "y"]),
    ("bad_number.csv", ["x"], ["bad_number.csv:3", "'x'", "oops"]),
    ("short_row.csv", ["t"], ["short_row.csv:3", "expected 2 fields"]),
    ("header_only.csv", ["t"], ["header_only.csv", "data row"]),
]
for name, columns, words in cases:
    try:
        load_csv(tmp, name, columns)
    except DataError as e:
        for w in words:
            assert w in str(e), f"{name}: message {e!r} lacks {w!r}"
    else:
        raise AssertionError(f"{name}: no DataError")

# figure_main: DataError -> exit 1 with the message on stderr; no folder -> exit 2.
script = tmp / "figure99.py"
script.write_text(
    "import sys\n"
    f"sys.path.insert(0, {str(plots)!r})\n"
    "from common import figure_main, load_csv\n"
    "figure_main(lambda d: load_csv(d, 'bad_number.csv', ['x']))\n")
r = subprocess.run([sys.executable, str(script), str(tmp)], capture_output=True, text=True)
assert r.returncode == 1, (r.returncode, r.stderr)
assert "bad_number.csv:3" in r.stderr and "figure99.py: error" in r.stderr, r.stderr
r = subprocess.run([sys.executable, str(script), str(tmp / "nope")], capture_output=True, text=True)
assert r.returncode == 2, (r.returncode, r.stderr)
print("ok")
