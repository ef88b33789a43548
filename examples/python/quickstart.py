"""Maps the Intel Research Lab log with raypath's SLAM and plots the map and the trajectory.

    pip install maturin && maturin develop --release -m crates/python/Cargo.toml
    python examples/python/quickstart.py [LOG] [--out DIR]

LOG defaults to $RAYPATH_DATA/carmen/raw/intel.clf.bz2. Writes DIR/intel.pgm + DIR/intel.yaml
(ROS map_server) and, when matplotlib is installed, DIR/intel.png (map and trajectory).
"""

import argparse
import os
import pathlib
import sys

import numpy as np

import raypath


def main():
    data = os.environ.get("RAYPATH_DATA", "datasets")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", nargs="?", default=f"{data}/carmen/raw/intel.clf.bz2")
    parser.add_argument("--out", default="quickstart-out")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    log = raypath.open(args.log)
    print(f"{log.path}: {len(log)} scans")

    def progress(done, total):
        print(f"\rslam: {done}/{total} scans", end="", file=sys.stderr, flush=True)

    result = raypath.slam(log, progress=progress)
    print(file=sys.stderr)
    print(f"{len(result.poses)} poses, {len(result.loops)} loop closures, {result.seconds:.1f} s")
    pgm, yaml = result.map.save(out / "intel.pgm")
    print(f"map: {pgm} + {yaml}")

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no picture (pip install matplotlib)")
        return

    m = result.map
    h, w = m.shape
    x0, y0 = m.origin
    extent = [x0, x0 + w * m.resolution, y0, y0 + h * m.resolution]
    # Occupied dark, free light, unknown grey; row 0 of the array is the lowest y.
    picture = np.where(np.isnan(m.array), 0.5, 1.0 - m.array)
    fig, ax = plt.subplots(figsize=(8, 8))
    ax.imshow(picture, cmap="gray", origin="lower", extent=extent, vmin=0, vmax=1)
    ax.plot(result.poses[:, 0], result.poses[:, 1], lw=0.6, color="tab:blue", label="trajectory")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{pathlib.Path(args.log).name}: raypath.slam")
    ax.legend(loc="upper right")
    png = out / "intel.png"
    fig.savefig(png, dpi=150, bbox_inches="tight")
    print(f"picture: {png}")


if __name__ == "__main__":
    main()
