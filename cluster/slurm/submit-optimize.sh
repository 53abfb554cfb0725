#!/bin/bash
# A gait search on a Slurm cluster. CMA-ES needs a whole generation's results before it asks for
# the next, so each generation is an array job of N shards waiting for the last (afterok), and a
# last job joins them:
#     cluster/slurm/submit-optimize.sh SPEC OUTPUT N GENERATIONS [sbatch options: -p, -A, -c …]
# GENERATIONS is the spec's `generations`. Prints the job ids. OUTPUT must be shared by the nodes.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
spec=${1:?spec}; output=${2:?output folder}; n=${3:?number of shards}
generations=${4:?generations: the number in the spec}; shift 4
prev=""
for _ in $(seq "$generations"); do
    prev=$(sbatch --parsable ${prev:+--dependency=afterok:$prev} --array="1-$n" "$@" \
        "$here/optimize-step.sbatch" "$spec" "$output" "$n")
    echo -n "$prev "
done
sbatch --parsable --dependency="afterok:$prev" "$@" "$here/optimize-finish.sbatch" "$spec" "$output"
