#!/bin/bash
# A big frame with GNU parallel, on this machine or over ssh hosts that share this folder:
#   deploy/parallel/render.sh 16 out/frame.exr scenes/showcase.txt --size 4096 3072 --shadows
#   HOSTS=node1,node2,: deploy/parallel/render.sh 64 out/frame.exr scene.txt --size 16384 16384
# `whitted tiles` prints one render line per tile, then the merge line; parallel runs the
# tiles (HOSTS is parallel's -S list, `:` meaning this machine; every host needs whitted on its
# PATH and the same folder at the same place), then the merge line runs here.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 TILES OUT SCENE [render options]" >&2; exit 2; }
tiles=$1 out=$2 scene=$3
shift 3
WHITTED=${WHITTED:-whitted}
jobs=$(mktemp)
trap 'rm -f "$jobs"' EXIT
"$WHITTED" tiles "$tiles" "$scene" "$@" -o "$out" > "$jobs"
hosts=()
if [ -n "${HOSTS:-}" ]; then
    hosts=(-S "$HOSTS" --workdir "$PWD")
fi
head -n "$tiles" "$jobs" | parallel --will-cite --halt now,fail=1 "${hosts[@]}"
tail -n 1 "$jobs" | sh
