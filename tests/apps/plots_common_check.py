"""Checks python/plots/common.py: bad figure data fails loudly, naming file, line and column; and
figure10.py (the laser figure) on synthetic data.

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

# figure10.py on a small synthetic laser run: it draws both panels (an exact zero error included,
# which the log axis must survive); a map whose cells disagree on the resolution is an error
# naming the file and the column.
laser = tmp / "figure10"
laser.mkdir()
(laser / "laser_mcl_map.csv").write_text(
    "x_m,y_m,resolution_m\n" +
    "".join(f"{0.05 * i:.3f},{y},0.05\n" for i in range(40) for y in (0.0, 1.0)))
(laser / "laser_mcl_reference.csv").write_text(
    "update,time_s,x_m,y_m,heading_rad\n" +
    "".join(f"{k},{0.5 * k},{0.1 * k},0.5,0\n" for k in range(20)))
for proposal, m, scale in (("implicit", 100, 0.01), ("bootstrap", 1000, 0.2)):
    (laser / f"laser_mcl_track_{proposal}.csv").write_text(
        "update,time_s,x_m,y_m,heading_rad,error_m,particles\n" +
        "".join(f"{k},{0.5 * k},{0.1 * k},{0.5 + scale * k / 20},0,{scale * k / 20},{m}\n"
                for k in range(20)))
figure10 = plots / "figure10.py"
r = subprocess.run([sys.executable, str(figure10), str(laser)], capture_output=True, text=True)
assert r.returncode == 0, (r.returncode, r.stderr)
assert (laser / "figure10.png").is_file() and (laser / "figure10.svg").is_file()
(laser / "figure10.png").unlink()
with open(laser / "laser_mcl_map.csv", "a") as f:
    f.write("3.0,0.0,0.1\n")
r = subprocess.run([sys.executable, str(figure10), str(laser)], capture_output=True, text=True)
assert r.returncode == 1, (r.returncode, r.stderr)
assert "laser_mcl_map.csv" in r.stderr and "resolution_m" in r.stderr, r.stderr
assert not (laser / "figure10.png").exists()
print("ok")
