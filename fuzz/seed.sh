#!/usr/bin/env bash
# Copies seed inputs into the git-ignored corpus folders: our own scenes/ and, when the course
# data is there, the MIT 6.837 scenes and meshes (never committed to this repository).
#   fuzz/seed.sh [COURSE_DIR]     (default: ../shared/scenes-6837 beside the repository)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
course="${1:-$here/../../shared/scenes-6837}"
mkdir -p "$here/corpus/parse_scene" "$here/corpus/render_tiny" "$here/corpus/parse_obj"
scenes=("$here"/../scenes/*.txt)
meshes=("$here"/../scenes/*.obj)
if [ -d "$course" ]; then
    scenes+=("$course"/assignment*/*.txt)
    # Small meshes only: libFuzzer mutates inputs of a few KiB best.
    while IFS= read -r f; do meshes+=("$f"); done < <(find "$course" -name '*.obj' -size -64k)
else
    echo "note: no course data at $course; seeding from scenes/ only" >&2
fi
for f in "${scenes[@]}"; do
    cp "$f" "$here/corpus/parse_scene/"
    cp "$f" "$here/corpus/render_tiny/"
done
for f in "${meshes[@]}"; do
    cp "$f" "$here/corpus/parse_obj/"
done
echo "seeded: ${#scenes[@]} scenes, ${#meshes[@]} meshes" >&2
