#!/usr/bin/env bash
# Regenerate the appendix on a Slurm cluster: N shards as a job array, run PASSES times one after
# the other (each pass advances every row's tuning by one rung of successive halving, an edge
# extension starts the rungs again, and the report runs need every row's tuning: PASSES defaults
# to 1 + rungs × (extensions + 1) of the full profile, 17), the theorem table as one job beside
# the passes (`paper-checks theory`; the shards leave it to this job), then one merge job after
# both. A pass with nothing left to compute ends at once. The output directory must be on a file
# system every node sees. Usage (from the repository root, after `cargo build --release -p paper-checks`):
#
#   paper-checks/scripts/slurm-shards.sh 16 out/appendix --full
#
# Each array task runs `paper-checks --shard K/N`; the theory job `paper-checks theory`; the merge
# job `paper-checks merge`.
set -euo pipefail
n="${1:?number of shards}"
out="${2:?output directory}"
shift 2
bin="${PAPER_CHECKS:-target/release/paper-checks}"
shard="$bin $* --quiet --out $out --shard \$((SLURM_ARRAY_TASK_ID))/$n"
passes="${PASSES:-17}"
theory=$(sbatch --parsable --job-name=ilopt-theory --wrap "$bin $* --quiet --out $out theory")
previous=""
for pass in $(seq "$passes"); do
  previous=$(sbatch --parsable --array=1-"$n" --job-name=ilopt-pass-"$pass" \
    ${previous:+--dependency=afterok:"$previous"} --wrap "$shard")
done
sbatch --dependency=afterok:"$previous":"$theory" --job-name=ilopt-merge --wrap "$bin $* --out $out merge"
