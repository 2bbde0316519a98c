#!/bin/sh
# Model the probe's generic and hand-specialised CartPole roll-out loops with llvm-mca
# (benches/README.md, "A model of the two roll-out loops"). Needs perf, gdb and llvm-mca.
#   benches/mca/run.sh [OUTDIR]
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-target/mca}
mkdir -p "$out"
probe=$(cargo bench --bench oracle_probe --no-run 2>&1 | grep -o 'target/release/deps/oracle_probe-[0-9a-f]*' | head -1)
trace() { # mode symbol name
    perf record -q -e cpu-clock -F 2000 -o "$out/$3.perf" "$probe" "$1" 1 50 >/dev/null 2>&1
    func=$(perf annotate -i "$out/$3.perf" --stdio -s "$2" 2>/dev/null \
        | grep -E '^ +[0-9.]+ :' | head -1 | awk '{print $3}' | tr -d :)
    [ -n "$func" ] || { echo "run.sh: $2 not found in the profile of mode $1" >&2; exit 1; }
    FUNC=$func OUT="$out/$3.trace" gdb -q -batch -x "$here/trace_loop.py" --args "$probe" "$1" 1 3 \
        >"$out/$3.gdb" 2>&1
}
trace rollout 'ilopt::task::rollout::<impl ilopt::task::problem::TaskProblem<T,P>>::rollout_into' generic
trace specroll 'oracle_probe::specialised::Specialised::rollout' specialised
python3 "$here/model.py" "$out/generic.trace" "$out/specialised.trace"
