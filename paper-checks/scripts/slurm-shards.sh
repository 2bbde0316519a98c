#!/usr/bin/env bash
# Regenerate the appendix on a Slurm cluster: N shards as a job array, run twice (the report runs
# need every row's tuning), then one merge job. The output directory must be on a file system
# every node sees. Usage (from the repository root, after `cargo build --release -p paper-checks`):
#
#   paper-checks/scripts/slurm-shards.sh 16 out/appendix --full
#
# Each array task runs `paper-checks --shard K/N`; the merge job runs `paper-checks merge`.
set -euo pipefail
n="${1:?number of shards}"
out="${2:?output directory}"
shift 2
bin="${PAPER_CHECKS:-target/release/paper-checks}"
shard="$bin $* --quiet --out $out --shard \$((SLURM_ARRAY_TASK_ID))/$n"
tuning=$(sbatch --parsable --array=1-"$n" --job-name=ilopt-tune --wrap "$shard")
report=$(sbatch --parsable --array=1-"$n" --job-name=ilopt-report \
  --dependency=afterok:"$tuning" --wrap "$shard")
sbatch --dependency=afterok:"$report" --job-name=ilopt-merge --wrap "$bin $* --out $out merge"
