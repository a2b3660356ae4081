#!/bin/sh
# Copies the Khronos sample models' glTF-Binary and glTF variants out of a clone of
# glTF-Sample-Assets (or a copy of it, e.g. DRx3D/glTF-Sample-Assets-OLD) into DIR, as
# conformance.py reads them. A variant with a file missing from the clone (large files are absent
# from some copies) is left out whole.
#
#     scripts/gltf-conformance/fetch-models.sh CLONE_GIT_DIR DIR [MODEL...]
set -eu
repo=$1
dir=$2
shift 2
if [ $# -eq 0 ]; then
    set -- $(git --git-dir "$repo" ls-tree --name-only HEAD Models/ | sed -n 's|^Models/||p' | grep -v '[^A-Za-z0-9_-]')
fi
for model in "$@"; do
    for variant in glTF-Binary glTF; do
        out="$dir/$model/$variant"
        rm -rf "$out"
        files=$(git --git-dir "$repo" ls-tree -r --name-only HEAD "Models/$model/$variant/") || continue
        [ -n "$files" ] || continue
        complete=yes
        for f in $files; do
            target="$dir/${f#Models/}"
            mkdir -p "$(dirname "$target")"
            git --git-dir "$repo" show "HEAD:$f" > "$target" 2>/dev/null || { complete=no; break; }
        done
        [ $complete = yes ] || rm -rf "$out"
    done
    rmdir "$dir/$model" 2>/dev/null || true
done
