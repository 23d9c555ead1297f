#!/usr/bin/env python3
"""A motion model added through the registry alone runs in every command that takes --model.

`implicit-toy` is the tool plus tests/registry/toy_motion_model.cpp, which registers "toy": the
unicycle written again from its equations. So each command must give, on a log that declares
the toy, exactly the numbers the built-in unicycle gives on the same log declaring the unicycle
(times aside); and the plain tool, which does not know the toy, must refuse that log by name.
"""
import argparse
import json
import pathlib
import re
import subprocess
import sys

# Keys that measure time or memory, or name the input: not results.
NOT_RESULTS = re.compile(r"cpu|memory|seconds|time_s|_ms|_us|elapsed|wall|^file$|^data$|^model$|commit")


def run(argv, expect=0):
    r = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    if r.returncode != expect:
        sys.exit(f"{' '.join(argv)}: exit {r.returncode}, expected {expect}\n{r.stderr}")
    return r


def results(value, path=""):
    """{path: leaf} over the JSON, without the keys that are not results."""
    out = {}
    if isinstance(value, dict):
        for k, v in value.items():
            if not NOT_RESULTS.search(k):
                out.update(results(v, f"{path}.{k}"))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out.update(results(v, f"{path}[{i}]"))
    else:
        out[path] = value
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--toy", required=True)
    parser.add_argument("--cli", required=True)
    parser.add_argument("--work", required=True)
    a = parser.parse_args()
    for program in (a.toy, a.cli):
        if not pathlib.Path(program).is_file():
            sys.exit(f"{program} was not built: build the targets implicit_toy and implicit_cli "
                     f"(make test-sanitize's SANITIZE_TARGETS lists both)")
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    unicycle, toy = work / "unicycle.log", work / "toy.log"
    for model, path in (("unicycle", unicycle), ("toy", toy)):
        run([a.toy, "simulate", "--model", model, "--seed", "3", "--steps", "400", "--out",
             str(path)])
    # The toy drives the unicycle's route with the same noise: the same log but for its name.
    u_lines, t_lines = unicycle.read_text().splitlines(), toy.read_text().splitlines()
    differ = [(x, y) for x, y in zip(u_lines, t_lines) if x != y]
    if (len(u_lines) != len(t_lines) or len(differ) != 1
            or differ[0][1] != differ[0][0].replace("vehicle unicycle ", "vehicle toy ")):
        sys.exit(f"the simulated logs differ beyond the vehicle record: {differ[:3]}")
    failures = 0
    for command in (["mcl", "--method", "implicit", "-M", "40", "--runs", "3"],
                    ["mcl", "--method", "standard", "-M", "40", "--runs", "3"],
                    ["mcl", "--method", "implicit", "-M", "40", "--runs", "2", "--init", "global"],
                    ["slam", "--method", "implicit-rb", "-M", "10"],
                    ["slam", "--method", "ekf"]):
        by_model = {}
        for model, path in (("unicycle", unicycle), ("toy", toy)):
            out = run([a.toy, *command, "--data", str(path), "--json", "--threads", "2"]).stdout
            by_model[model] = json.loads(out)
        if by_model["toy"].get("model") != "toy":
            sys.exit(f"{' '.join(command)}: the toy log ran as {by_model['toy'].get('model')!r}")
        u, t = results(by_model["unicycle"]), results(by_model["toy"])
        if u != t or len(u) < 5:
            failures += 1
            diff = [(k, u.get(k), t.get(k)) for k in sorted(set(u) | set(t)) if u.get(k) != t.get(k)]
            print(f"FAIL {' '.join(command)}: {len(diff)} results differ, e.g. {diff[:4]}")
        else:
            print(f"ok {' '.join(command)}: {len(u)} results equal")
    # The model's own checks, and its name in the choices of every command that takes --model.
    bad = work / "toy_bad_key.log"
    bad.write_text(re.sub(r"^(vehicle toy .*)$", r"\1 L=2", toy.read_text(), flags=re.M))
    r = run([a.toy, "mcl", "--data", str(bad), "--json"], expect=1)
    if "vehicle 'toy': expected parameters among dt, got 'L'" not in r.stderr:
        failures += 1
        print(f"FAIL an unknown vehicle key: {r.stderr.strip()}")
    for sub in ("mcl", "slam", "simulate"):
        if "toy" not in run([a.toy, sub, "--help"]).stdout:
            failures += 1
            print(f"FAIL implicit-toy {sub} --help does not offer the toy")
    # The tool without the registration refuses the log, naming the vehicle and what it runs.
    r = run([a.cli, "mcl", "--data", str(toy), "--json"], expect=1)
    if "declares vehicle 'toy'; this program runs 'ute', 'unicycle'" not in r.stderr:
        failures += 1
        print(f"FAIL the plain tool on the toy log: {r.stderr.strip()}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
