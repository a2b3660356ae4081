#!/usr/bin/env bash
# Renders a scene on a Slurm cluster: a job array of N shards, each on a GPU node rendering its
# share of the samples into a film file, then a merge job that starts when every shard has
# succeeded (afterok) and writes the image. The image is bit-identical to one render of all the
# samples on the same kind of device.
#
#   scripts/slurm/render-array.sh SCENE SPP N OUTPUT [rt-gpu render options...]
#   scripts/slurm/render-array.sh cornell 100000 16 cornell.png --size 1024x1024
#
# Environment: RT_GPU (the binary, default rt-gpu), FILMS (a directory every node sees, default
# ./films), SBATCH_ARGS (more sbatch options for every job, e.g. "--partition=gpu --time=2:00:00"),
# WAIT=1 (return when the merge job has finished, with its exit status).
#
# Each shard checkpoints every minute: a shard killed by its time limit or preempted (Slurm sends
# SIGTERM first) and requeued resumes where it stopped.
set -euo pipefail
if (($# < 4)); then
    sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
fi
scene=$1 spp=$2 shards=$3 output=$4
shift 4
rt_gpu=${RT_GPU:-rt-gpu}
films=$(realpath -m "${FILMS:-films}")
mkdir -p "$films"
read -r -a sbatch_args <<<"${SBATCH_ARGS:-}"
extra=$(printf ' %q' "$@")
q() { printf '%q' "$1"; }

# One shard: resume its checkpoint if an earlier attempt left one.
shard_command="k=\$SLURM_ARRAY_TASK_ID; ck=$(q "$films")/shard-\$k.ckpt.exr;
if [ -f \"\$ck\" ]; then continue_from=--resume; else continue_from=--checkpoint; fi;
exec $(q "$rt_gpu") $(q "$scene") --spp $spp --shard \$k/$shards \$continue_from \"\$ck\" \
  -o $(q "$films")/shard-\$k.exr$extra"
array=$(sbatch --parsable --requeue --array=0-$((shards - 1)) --gres=gpu:1 \
    --job-name=rt-gpu-shard --output="$films/shard-%a.log" "${sbatch_args[@]}" \
    --wrap "$shard_command")
echo "shards: job array $array ($shards tasks), films in $films"

films_list=""
for ((k = 0; k < shards; k++)); do
    films_list+=" $(q "$films/shard-$k.exr")"
done
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
    --job-name=rt-gpu-merge --output="$films/merge.log" "${sbatch_args[@]}" \
    --wrap "exec $(q "$rt_gpu") merge$films_list -o $(q "$(realpath -m "$output")")")
echo "merge: job $merge -> $output"

if [[ "${WAIT:-0}" == 1 ]]; then
    # Polled here: sbatch --wait polls at growing intervals, up to half a minute late.
    state=""
    while true; do
        state=$(scontrol show job -o "$merge" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2)
        case "$state" in
        PENDING | CONFIGURING | RUNNING | COMPLETING | REQUEUED | "") sleep 0.5 ;;
        *) break ;;
        esac
    done
    echo "merge: $state"
    [[ "$state" == COMPLETED ]]
fi
