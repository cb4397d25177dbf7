#!/bin/sh
# Submit a sharded bake and its merge: N array tasks, then the merge once all succeeded.
#   SCENE=/shared/scene.glb WORK=/shared/job SHARDS=4 sh deploy/slurm/submit.sh
# SBATCH_ARGS adds options to both submissions (e.g. --cpus-per-task=2 --partition=batch).
# A failed shard: resubmit only its index (sbatch --array=I bake.sbatch) and the merge.
set -eu
here=$(dirname "$0")
: "${SHARDS:=4}"
export SCENE="${SCENE:-scene.glb}" WORK="${WORK:-$PWD}" SHARDS LIGHTLAB="${LIGHTLAB:-lightlab}"
mkdir -p "$WORK/parts"
# shellcheck disable=SC2086  # SBATCH_ARGS is a list of options
jid=$(sbatch --parsable --export=ALL --array="0-$((SHARDS - 1))" --chdir="$WORK" \
    ${SBATCH_ARGS:-} "$here/bake.sbatch")
# shellcheck disable=SC2086
mid=$(sbatch --parsable --export=ALL --dependency="afterok:$jid" --chdir="$WORK" \
    ${SBATCH_ARGS:-} "$here/merge.sbatch")
echo "bake array $jid, merge $mid"
