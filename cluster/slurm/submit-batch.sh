#!/bin/bash
# A scenario suite on a Slurm cluster: an array job of N shards, then the merge once they have all
# ended (afterany: a scenario that failed its expectations still belongs in the results).
#     cluster/slurm/submit-batch.sh SCENARIOS RESULTS_DIR N [sbatch options: -p, -A, -c …]
# Prints the two job ids. RESULTS_DIR must be a folder every node sees (a shared file system).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
scenarios=${1:?scenarios}; results=${2:?results folder}; n=${3:?number of shards}; shift 3
array=$(sbatch --parsable --array="1-$n" "$@" "$here/batch.sbatch" "$scenarios" "$results" "$n")
merge=$(sbatch --parsable --dependency="afterany:$array" "$@" --cpus-per-task=1 \
    "$here/merge.sbatch" "$results")
echo "$array $merge"
