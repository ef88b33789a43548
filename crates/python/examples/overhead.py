"""Python call overhead against the Rust call, side by side in one run: pole extraction on a
real KITTI frame and SLAM on the intel log.

    cargo build --release -p raypath-python --example overhead
    maturin develop --release -m crates/python/Cargo.toml
    RAYPATH_DATA=/path/to/data python crates/python/examples/overhead.py [--rounds 3]

    # the same in instructions (valgrind --tool=callgrind), independent of the machine's load:
    RAYPATH_DATA=/path/to/data python crates/python/examples/overhead.py --instructions

Each round runs the Rust example (`examples/overhead.rs`: the library calls the bindings make,
input read before the clock starts) and then the same calls through `raypath`, so both see the
same machine load; the table gives the median seconds of each and the overhead of Python.
With `--instructions`, each side runs under callgrind once with one call and once with two (one
rayon thread, so counts repeat); the difference is the instructions of one call, start-up and
input reading cancel out. SLAM is then run on the first `--slam-scans` scans.
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import raypath

REPO = pathlib.Path(__file__).resolve().parents[3]


def rust(exe, task, path, reps):
    out = subprocess.run([str(exe), task, str(path), str(reps)], check=True,
                         capture_output=True, text=True).stdout
    return [json.loads(line)["seconds"] for line in out.splitlines() if line.strip()]


PY_CALL = {
    "poles": "import raypath\n"
             "s = raypath.open({path!r}); p, q = s[0].points, s.poses[0]\n"
             "for _ in range({reps}): raypath.poles.extract(p, pose=q)\n",
    "slam": "import raypath\n"
            "log = raypath.open({path!r})\n"
            "for _ in range({reps}): raypath.slam(log, scans={scans})\n",
}


def instructions(command):
    """Instructions callgrind counts for `command` (all threads)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "callgrind.out"
        env = dict(os.environ, RAYON_NUM_THREADS="1")
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *command],
                       check=True, capture_output=True, env=env)
        for line in out.read_text().splitlines():
            if line.startswith("summary:") or line.startswith("totals:"):
                return int(line.split()[1])
    raise RuntimeError("no totals in the callgrind output")


def per_call(command_of):
    return instructions(command_of(2)) - instructions(command_of(1))


def count_instructions(exe, kitti, intel, slam_scans):
    py = sys.executable
    rows = []
    for task, path, extra in (("poles", kitti, []), ("slam", intel, [str(slam_scans)])):
        rust_n = per_call(lambda reps: [str(exe), task, str(path), str(reps), *extra])
        code = lambda reps: PY_CALL[task].format(path=str(path), reps=reps, scans=slam_scans)
        py_n = per_call(lambda reps: [py, "-c", code(reps)])
        rows.append((task, rust_n, py_n))
    label = {"poles": "poles (KITTI 00, frame 0)", "slam": f"slam (intel, first {slam_scans} scans)"}
    print(f"{'task':<32} {'Rust instr.':>14} {'Python instr.':>14} {'overhead':>9}")
    for task, r, p in rows:
        print(f"{label[task]:<32} {r:>14} {p:>14} {100 * (p / r - 1):>8.2f} %")


def timed(call, reps):
    times = []
    for _ in range(reps):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--pole-reps", type=int, default=5, help="pole extractions per round and side")
    parser.add_argument("--exe", default=REPO / "target/release/examples/overhead")
    parser.add_argument("--instructions", action="store_true", help="count instructions (callgrind)")
    parser.add_argument("--slam-scans", type=int, default=500, help="with --instructions")
    args = parser.parse_args()
    data = pathlib.Path(os.environ["RAYPATH_DATA"])
    kitti = data / "kitti/sequences/00"
    intel = data / "carmen/raw/intel.clf.bz2"
    if args.instructions:
        count_instructions(args.exe, kitti, intel, args.slam_scans)
        return

    seq = raypath.open(kitti)
    points, pose = seq[0].points, seq.poses[0]
    log = raypath.open(intel)
    results = {"poles (KITTI 00, frame 0)": ([], []), "slam (intel, 13631 scans)": ([], [])}
    for _ in range(args.rounds):
        r, p = results["poles (KITTI 00, frame 0)"]
        r += rust(args.exe, "poles", kitti, args.pole_reps)
        p += timed(lambda: raypath.poles.extract(points, pose=pose), args.pole_reps)
        r, p = results["slam (intel, 13631 scans)"]
        r += rust(args.exe, "slam", intel, 1)
        p += timed(lambda: raypath.slam(log), 1)
    print(f"{'task':<28} {'runs':>4} {'Rust s':>9} {'Python s':>9} {'overhead':>9}")
    for task, (r, p) in results.items():
        mr, mp = statistics.median(r), statistics.median(p)
        print(f"{task:<28} {len(r):>4} {mr:>9.3f} {mp:>9.3f} {100 * (mp / mr - 1):>8.1f} %")


if __name__ == "__main__":
    main()
