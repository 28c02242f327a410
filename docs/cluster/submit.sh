#!/bin/bash
# Submits a sharded `hostctl map` sweep and its merge to Slurm (see docs/cluster.md):
#   SHARDS=8 HOSTCTL=/path/to/hostctl MAP_ARGS='--mu 1:1000:7:log …' docs/cluster/submit.sh
# Prints "<array job id> <merge job id>". Every variable of map-array.sbatch and
# map-merge.sbatch is passed through (sbatch exports the environment).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
export SHARDS=${SHARDS:-8}
if ! [ "$SHARDS" -ge 1 ] 2>/dev/null; then
    echo "submit.sh: SHARDS=$SHARDS: need an integer >= 1" >&2
    exit 2
fi
array=$(sbatch --parsable --array=0-$((SHARDS - 1)) "$here/map-array.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes "$here/map-merge.sbatch")
echo "$array ${merge%%;*}"
