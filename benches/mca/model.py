"""llvm-mca's cycles per iteration for loop traces written by trace_loop.py, per CPU model.

    python3 model.py [--cpus skylake,znver3] TRACE...

Calls are left out (llvm-mca cannot follow them; the callees are the same in the loops compared),
so the figures model the loop's own instructions only: compare loops with each other on one CPU
model, not with measured times.
"""
import argparse
import re
import subprocess
import sys
import tempfile


def body(trace):
    """The trace's instructions without calls, symbols or comments."""
    lines = []
    with open(trace) as f:
        for line in f:
            ins = line.rstrip("\n").split("\t", 1)[1]
            if ins.startswith("call"):
                continue
            ins = re.sub(r"\s+#.*", "", ins)
            lines.append(re.sub(r" <[^>]*>", "", ins))
    return lines


def model(lines, cpu, iterations=400):
    """(cycles per iteration, uops per iteration, block reciprocal throughput)."""
    with tempfile.NamedTemporaryFile("w", suffix=".s") as f:
        f.write("\n".join(lines) + "\n")
        f.flush()
        run = subprocess.run(
            ["llvm-mca", "-mtriple=x86_64", f"-mcpu={cpu}", f"-iterations={iterations}", f.name],
            capture_output=True,
            text=True,
            check=True,
        )
    field = lambda name: float(re.search(name + r":\s+([\d.]+)", run.stdout).group(1))
    return (
        field("Total Cycles") / iterations,
        field("Total uOps") / iterations,
        field("Block RThroughput"),
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cpus", default="haswell,skylake,icelake-server,znver2,znver3")
    parser.add_argument("traces", nargs="+")
    args = parser.parse_args()
    for trace in args.traces:
        try:
            lines = body(trace)
        except (OSError, IndexError) as e:
            sys.exit(f"model.py: {trace}: not a trace of trace_loop.py ({e})")
        for cpu in args.cpus.split(","):
            try:
                cycles, uops, rthroughput = model(lines, cpu)
            except FileNotFoundError:
                sys.exit("model.py: llvm-mca not found (Debian: apt install llvm)")
            except subprocess.CalledProcessError as e:
                sys.exit(f"model.py: llvm-mca failed on {trace} for {cpu}: {e.stderr.strip()}")
            print(
                f"{trace}\t{cpu}\t{len(lines)} instructions\t{uops:.0f} uops"
                f"\t{cycles:.1f} cycles/iteration\tthroughput bound {rthroughput}"
            )


if __name__ == "__main__":
    main()
