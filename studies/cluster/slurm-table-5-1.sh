#!/usr/bin/env bash
# The Table 5.1 study as a Slurm job array: 16 shards of 1,250 trials, each on 2 cores.
# From the repository's root, with `twin` built (cargo build --release) on a shared file system:
#
#   mkdir -p out/table-5-1
#   JOB=$(sbatch --parsable studies/cluster/slurm-table-5-1.sh)
#   sbatch --dependency=afterok:$JOB --wrap \
#     'target/release/twin montecarlo merge out/table-5-1/shard-* --out out/table-5-1/merged'
#
# A task that is preempted or requeued starts again with the same --out and only runs the trials
# its shard is still missing. The merged files equal a single run's byte for byte.
#SBATCH --job-name=table-5-1
#SBATCH --array=0-15
#SBATCH --cpus-per-task=2
#SBATCH --mem=1G
#SBATCH --time=00:30:00
#SBATCH --requeue
#SBATCH --output=out/table-5-1/slurm-%A_%a.log
set -euo pipefail
SHARDS=${SLURM_ARRAY_TASK_COUNT:-16}
exec target/release/twin montecarlo studies/table-5-1.toml \
  --shard "${SLURM_ARRAY_TASK_ID}/${SHARDS}" \
  --threads "${SLURM_CPUS_PER_TASK:-2}" \
  --out "out/table-5-1/shard-${SLURM_ARRAY_TASK_ID}" \
  --quiet
