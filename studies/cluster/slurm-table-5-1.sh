#!/usr/bin/env bash
# The Table 5.1 study as a Slurm job array: 16 shards of 1,250 trials, each on 2 cores.
# From the repository's root, with `twin` built (cargo build --release) on a shared file system:
#
#   mkdir -p out/table-5-1
#   JOB=$(sbatch --parsable studies/cluster/slurm-table-5-1.sh)
#   sbatch --dependency=afterany:$JOB studies/cluster/slurm-table-5-1-merge.sh
#
# A task that is preempted or requeued starts again with the same --out and only runs the trials
# its shard is still missing; Slurm holds a requeued task until its BeginTime (about two and a
# half minutes on a default configuration). A failed or cancelled task is run again on its own,
# `sbatch --array=K studies/cluster/slurm-table-5-1.sh`: the shard count is the study's (16, or
# TABLE_5_1_SHARDS), never the number of tasks a submission happens to have. The merge (its log
# in out/table-5-1/merge-JOBID.log) names the shards still missing and the command that runs them.
# The merged files equal a single run's byte for byte.
#SBATCH --job-name=table-5-1
#SBATCH --array=0-15
#SBATCH --cpus-per-task=2
#SBATCH --mem=1G
#SBATCH --time=00:30:00
#SBATCH --requeue
#SBATCH --output=out/table-5-1/slurm-%A_%a.log
set -euo pipefail
SHARDS=${TABLE_5_1_SHARDS:-16}
STUDY=${TABLE_5_1_STUDY:-studies/table-5-1.toml}
OUT=${TABLE_5_1_OUT:-out/table-5-1}
TASK=${SLURM_ARRAY_TASK_ID:?run as a task of a job array (sbatch --array=0-$((SHARDS - 1)))}
if ! [ "$TASK" -ge 0 ] 2>/dev/null || [ "$TASK" -ge "$SHARDS" ]; then
  echo "task $TASK is not a shard of $SHARDS: expected 0 to $((SHARDS - 1))" >&2
  exit 2
fi
exec target/release/twin montecarlo "$STUDY" \
  --shard "${TASK}/${SHARDS}" \
  --threads "${SLURM_CPUS_PER_TASK:-2}" \
  --out "$OUT/shard-${TASK}" \
  --quiet
