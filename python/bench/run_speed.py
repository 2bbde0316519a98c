"""A built-in task through the Python package against `ilopt run` on the same config.

    python python/bench/run_speed.py [CONFIG] [--repeats N] [--threads T] [--bin PATH]

Times `ilopt run --config CONFIG --out DIR --threads T --quiet` (a subprocess: process start and
file writes included) and `ilopt.run(CONFIG, out=DIR, threads=T, quiet=True)` (the same files
written, no log lines on stderr from either), each
N times alternately, and prints the medians of the wall times and of the CPU times (user +
system: the child's for the CLI, this process's for the package; less sensitive than wall time
to other load on the machine) and the package's speed as a share of the CLI's.
Both must be release builds (`pip install ./python` builds the package in release).
"""

import argparse
import resource
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
    cli, py, cli_cpu, py_cpu = [], [], [], []

    def cpu(who):
        r = resource.getrusage(who)
        return r.ru_utime + r.ru_stime

    with tempfile.TemporaryDirectory() as tmp:
        for i in range(a.repeats):
            out = Path(tmp) / f"cli-{i}"
            t, c = time.perf_counter(), cpu(resource.RUSAGE_CHILDREN)
            subprocess.run(
                [a.bin, "run", "--config", a.config, "--out", str(out), "--threads", str(a.threads),
                 "--quiet"],
                check=True,
                stdout=subprocess.DEVNULL,
            )
            cli.append(time.perf_counter() - t)
            cli_cpu.append(cpu(resource.RUSAGE_CHILDREN) - c)
            t, c = time.perf_counter(), cpu(resource.RUSAGE_SELF)
            result = ilopt.run(a.config, out=Path(tmp) / f"py-{i}", threads=a.threads, quiet=True)
            py.append(time.perf_counter() - t)
            py_cpu.append(cpu(resource.RUSAGE_SELF) - c)
    med = statistics.median
    print(f"config: {a.config} ({len(result.summary['seeds'])} seeds, "
          f"{result.summary['budget_calls']} calls each), threads {a.threads}, {a.repeats} repeats")
    print(f"ilopt run:  wall median {med(cli):.3f} s (min {min(cli):.3f}), CPU median {med(cli_cpu):.3f} s")
    print(f"ilopt.run:  wall median {med(py):.3f} s (min {min(py):.3f}), CPU median {med(py_cpu):.3f} s")
    print(f"package speed / CLI speed: wall {med(cli) / med(py):.1%}, CPU {med(cli_cpu) / med(py_cpu):.1%}")

if __name__ == "__main__":
    main()
