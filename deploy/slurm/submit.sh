#!/bin/bash
# Submits a big frame as a Slurm array of tiles and a merge job that waits for all of them:
#   SCENE=/shared/scene.txt OUT_DIR=/shared/out TILES=64 deploy/slurm/submit.sh
# (OPTIONS and WHITTED are passed on as render-tiles.sbatch documents.)
set -euo pipefail
here=$(dirname "$0")
: "${SCENE:?set SCENE}" "${OUT_DIR:?set OUT_DIR}"
export SCENE OUT_DIR TILES=${TILES:-64}
mkdir -p "$OUT_DIR"
array=$(sbatch --parsable --export=ALL --array=0-$((TILES - 1)) "$here/render-tiles.sbatch")
sbatch --export=ALL --dependency=afterok:"$array" "$here/merge.sbatch"
