#!/usr/bin/env bash
# Merges the Table 5.1 array's shards into out/table-5-1/merged, once the array is over however
# its tasks ended (submit with --dependency=afterany:JOB, not afterok: afterok never runs once a
# task failed or was cancelled, even after it is run again and succeeds). A shard that did not
# finish is named with the command that runs it again; run this script again afterwards.
#SBATCH --job-name=table-5-1-merge
#SBATCH --cpus-per-task=1
#SBATCH --mem=1G
#SBATCH --time=00:10:00
#SBATCH --output=out/table-5-1/merge-%j.log
set -euo pipefail
SHARDS=${TABLE_5_1_SHARDS:-16}
OUT=${TABLE_5_1_OUT:-out/table-5-1}
missing=()
for ((k = 0; k < SHARDS; k++)); do
  # A shard is done when its trials.csv is written (the last file a run writes).
  [ -s "$OUT/shard-$k/trials.csv" ] || missing+=("$k")
done
if [ "${#missing[@]}" -gt 0 ]; then
  list=$(IFS=,; echo "${missing[*]}")
  echo "shards not finished: ${list} of 0-$((SHARDS - 1))" >&2
  echo "run them again:  sbatch --array=${list} studies/cluster/slurm-table-5-1.sh" >&2
  echo "then merge:      sbatch --dependency=afterany:JOBID studies/cluster/slurm-table-5-1-merge.sh" >&2
  exit 1
fi
shards=()
for ((k = 0; k < SHARDS; k++)); do shards+=("$OUT/shard-$k"); done
exec target/release/twin montecarlo merge "${shards[@]}" --out "$OUT/merged"
