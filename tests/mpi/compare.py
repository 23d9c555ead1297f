#!/usr/bin/env python3
"""The MPI build of `implicit` against the build without MPI: the same JSON and CSV files, every
number but the timings, for 1, 2 and 3 ranks, static and dynamic assignment; and a failed run is
named, the other runs are kept and `--resume` completes the result.

  compare.py IMPLICIT_MPI IMPLICIT_SERIAL MPIEXEC WORKDIR
"""
import csv
import json
import os
import shutil
import subprocess
import sys

# Fields that measure the machine or name the output folder, not the result.
TIMING = {"seconds", "seconds_total", "cpu_ms_per_step", "cpu_ms_per_step_median",
          "cpu_ms_per_step_std", "peak_memory_mb",
          "threads", "wall_ms_per_step", "started_utc", "run_id", "command"}

# Small settings of every subcommand whose runs are spread over the ranks, and the launches each
# is compared in: "plain" is the MPI executable without a launcher, nS/nD N ranks with static or
# dynamic assignment.
ALL = ["plain", "n1S", "n1D", "n2S", "n2D", "n3S", "n3D"]
COMMANDS = {
    "slam": (["slam", "--method", "fastslam1", "-M", "20", "--datasets", "5"], ALL),
    "slam_consistent": (["slam", "--method", "implicit-rb", "-M", "10", "--datasets", "4",
                         "--truth", "consistent"], ["n2D", "n3S"]),
    "mcl": (["mcl", "--method", "implicit", "-M", "20", "--runs", "4"], ["plain", "n2S", "n3D"]),
    "slit": (["slit", "--samples", "10", "--runs", "30"], ["n2D", "n3S"]),
    "himmelblau": (["himmelblau", "--samples", "10", "--runs", "7"], ["n2D", "n3S"]),
    "reproduce": (["reproduce", "--quick", "--only", "slit,himmelblau", "--no-figures"], ["n2D"]),
}

def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if k not in TIMING}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if name not in TIMING]
    return [[row[i] for i in keep if i < len(row)] for row in rows]


def outputs(folder):
    found = {}
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if d != ".resume"]
        for name in files:
            if name.endswith(".csv"):
                path = os.path.join(root, name)
                found[os.path.relpath(path, folder)] = read_csv(path)
    return found


def run(command, env=None, expect=0):
    result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
    if result.returncode != expect:
        sys.exit(f"FAIL: {' '.join(command)} exited {result.returncode}, expected {expect}\n"
                 f"{result.stderr[-3000:]}")
    return result


def main():
    implicit_mpi, implicit_serial, mpiexec, work = sys.argv[1:5]
    shutil.rmtree(work, ignore_errors=True)
    launch = [mpiexec, "--oversubscribe", "--allow-run-as-root", "--bind-to", "none"]
    failures = 0
    for name, (args, launches) in COMMANDS.items():
        ref_out = os.path.join(work, name, "serial")
        ref = strip(json.loads(run([implicit_serial] + args + ["--json", "--threads", "2",
                                                             "--out", ref_out]).stdout))
        ref_files = outputs(ref_out)
        variants = []
        for launch_name in launches:
            if launch_name == "plain":
                variants.append(("plain", [implicit_mpi], "dynamic"))
            else:
                schedule = "static" if launch_name[2] == "S" else "dynamic"
                variants.append((f"n{launch_name[1]}-{schedule}",
                                 launch + ["-n", launch_name[1], implicit_mpi], schedule))
        for label, prefix, schedule in variants:
            out = os.path.join(work, name, label)
            env = dict(os.environ, IMPLICIT_SCHEDULE=schedule)
            got = strip(json.loads(run(prefix + args + ["--json", "--threads", "1", "--out", out],
                                       env).stdout))
            files = outputs(out)
            same = got == ref and files == ref_files
            print(f"{name} {label}: {'same' if same else 'DIFFERENT'}")
            if not same:
                failures += 1
                for k in sorted(set(got) | set(ref)):
                    if got.get(k) != ref.get(k):
                        print(f"  {k}: {got.get(k)} vs {ref.get(k)}")
                for k in sorted(set(files) | set(ref_files)):
                    if files.get(k) != ref_files.get(k):
                        print(f"  file {k} differs")
    failures += check_failure_and_resume(implicit_mpi, implicit_serial, launch, work)
    # The build without MPI under a launcher would run everything twice: it refuses (exit 2).
    refused = run(launch + ["-n", "2", implicit_serial, "himmelblau", "--runs", "2", "--quiet"],
                  expect=2)
    if "this build has no MPI" not in refused.stderr:
        failures += 1
        print(f"serial build under mpirun: no explanation\n{refused.stderr[-2000:]}")
    else:
        print("serial build under mpirun: refused with a message")
    if failures:
        sys.exit(f"FAIL: {failures} comparisons differ")
    print("all comparisons equal")


def check_failure_and_resume(implicit_mpi, implicit_serial, launch, work):
    """Run 3 of 5 fails on one rank: exit 1, the message names it, the others are kept; the
    rerun with --resume computes only run 3 and gives the one-process result."""
    args = COMMANDS["slam"][0]
    ref = strip(json.loads(run([implicit_serial] + args + ["--json"]).stdout))
    out = os.path.join(work, "resume")
    env = dict(os.environ, IMPLICIT_FAIL_RUN="3")
    failed = run(launch + ["-n", "2", implicit_mpi] + args + ["--json", "--out", out], env,
                 expect=1)
    problems = 0
    if "1 of 5 runs failed" not in failed.stderr or "run 3:" not in failed.stderr:
        print(f"failure message does not name the failed run:\n{failed.stderr}")
        problems += 1
    records = {}
    for root, _, files in os.walk(os.path.join(out, ".resume")):
        for f in files:
            records[f] = os.stat(os.path.join(root, f)).st_mtime_ns
    if sorted(records) != ["0.rec", "1.rec", "2.rec", "4.rec"]:
        print(f"kept records: {sorted(records)}, expected runs 0, 1, 2 and 4")
        problems += 1
    resumed = run(launch + ["-n", "2", implicit_mpi] + args + ["--json", "--out", out,
                                                               "--resume"])
    if strip(json.loads(resumed.stdout)) != ref:
        print("the resumed result differs from the one-process result")
        problems += 1
    for root, _, files in os.walk(os.path.join(out, ".resume")):
        for f in files:
            if f in records and os.stat(os.path.join(root, f)).st_mtime_ns != records[f]:
                print(f"run {f} was recomputed on --resume")
                problems += 1
    print(f"failure and resume: {'ok' if problems == 0 else 'PROBLEMS'}")
    return problems


if __name__ == "__main__":
    main()
