#!/bin/sh
# Issue 67's device checks as one run, for a session lent a GPU (its device machine has no
# network and no Rust: carry stripped release binaries). From the repository root there:
#
#     benches/gpu/issue67.sh gpu-run/rt-gpu-new gpu-run/rt-gpu-old > $OUT/issue67.txt 2>&1
#
# Here, before the call: build both binaries (`cargo build --release`, at the two commits),
# `strip -o gpu-run/rt-gpu-new target/release/rt-gpu` (and -old; the unstripped binary is over
# the 64 MiB a call carries), `echo /gpu-run/ >> .git/info/exclude`, generate the knot
# (`python3 scripts/generate-meshes.py --knot 1000 500 benches/mitsuba/knot-1m.obj`: ignored by
# git, so carry `benches/mitsuba/knot-1m.obj` too) and carry `gpu-run`. It prints the card, then
# `rt-gpu bench` of each scene at 1024x1024 and 16 spp with the new and old binaries
# alternating (by GPU time and wall, the host's share, the longest dispatch), then a 64-spp
# render's wall against its kernel time. About 5 minutes on an H100 (the CPU rows included).
set -u
new=$1
old=${2:-}
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null || true
lscpu | grep 'Model name' || true
"$new" devices
for scene in cornell cornell-empty spheres showcase scenes/materials.toml scenes/meshes.toml \
    scenes/textured.toml scenes/knots.toml benches/mitsuba/cornell-knot.toml \
    scenes/blender/worn.glb; do
    [ -e "$scene" ] || case $scene in *.*) echo "skipped $scene: not here"; continue ;; esac
    for binary in "$new" $old; do
        echo "== $scene ($binary)"
        timeout 120 "$binary" bench "$scene" --spp 16 --size 1024x1024 2>&1 |
            grep -E 'scene:|bvh:|gpu specialised|cpu  ' || echo "failed or timed out"
    done
done
for binary in "$new" $old; do
    echo "== cornell, 64 spp at 1024x1024 ($binary)"
    "$binary" cornell --backend gpu --spp 64 --size 1024x1024 -o /tmp/issue67.png 2>&1 | tail -1
done
