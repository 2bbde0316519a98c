"""A built-in task through the Python package against `ilopt run` on the same config.

    python python/bench/run_speed.py [CONFIG] [--repeats N] [--threads T] [--bin PATH]

Times `ilopt run --config CONFIG --out DIR --threads T` (a subprocess: process start and file
writes included) and `ilopt.run(CONFIG, out=DIR, threads=T)` (the same files written), each
N times alternately, and prints the medians and the package's speed as a share of the CLI's.
Both must be release builds (`pip install ./python` builds the package in release).
"""

import argparse
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import ilopt

REPO = Path(__file__).resolve().parents[2]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("config", nargs="?", default=str(REPO / "examples/run/obstacle-adam.toml"))
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--bin", default=str(REPO / "target/release/ilopt"))
    a = p.parse_args()
    cli, py = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(a.repeats):
            out = Path(tmp) / f"cli-{i}"
            t = time.perf_counter()
            subprocess.run(
                [a.bin, "run", "--config", a.config, "--out", str(out), "--threads", str(a.threads)],
                check=True,
                stdout=subprocess.DEVNULL,
            )
            cli.append(time.perf_counter() - t)
            t = time.perf_counter()
            result = ilopt.run(a.config, out=Path(tmp) / f"py-{i}", threads=a.threads)
            py.append(time.perf_counter() - t)
    c, q = statistics.median(cli), statistics.median(py)
    print(f"config: {a.config} ({len(result.summary['seeds'])} seeds, "
          f"{result.summary['budget_calls']} calls each), threads {a.threads}, {a.repeats} repeats")
    print(f"ilopt run:  median {c:.3f} s  (min {min(cli):.3f})")
    print(f"ilopt.run:  median {q:.3f} s  (min {min(py):.3f})")
    print(f"package speed / CLI speed: {c / q:.1%}")


if __name__ == "__main__":
    main()
