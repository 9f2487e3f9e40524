#!/bin/bash
# A truth spread over a Slurm job array: array task I of N renders samples [I*B, (I+1)*B) of the
# scene's truth (B = SPP / N, rounded up to a multiple of 4) as a partial truth; `mesolab truth merge` joins the parts
# into the truth one machine would have rendered, the same bytes (every node running the same build
# on the same instruction set: each part records its build, and parts of two builds are refused).
#
#   mesolab preset pack my-scene.json -o my-scene.zip          # the scene and every file it names
#   jid=$(sbatch --parsable --array=0-15 examples/slurm/truth-array.sh my-scene.zip 1024 parts)
#   sbatch --dependency=afterok:$jid --wrap 'mesolab truth merge parts/*.truth -o truth'
#
# Arguments: SCENE (a preset or a pack), SPP (the truth's samples per pixel), OUT (the parts'
# folder, default truth-parts). Environment: SIZE (default 512x512), SEED (default 1), MESOLAB (the
# program, default `mesolab` on the PATH), MESOLAB_CACHE_DIR (where each node unpacks the pack).
#SBATCH --job-name=mesolab-truth
#SBATCH --cpus-per-task=16
#SBATCH --time=04:00:00
set -euo pipefail
scene=${1:?usage: truth-array.sh SCENE SPP [OUT]}
spp=${2:?usage: truth-array.sh SCENE SPP [OUT]}
out=${3:-truth-parts}
n=${SLURM_ARRAY_TASK_COUNT:?run it as a job array: sbatch --array=0-N-1 ...}
i=${SLURM_ARRAY_TASK_ID:?run it as a job array: sbatch --array=0-N-1 ...}
block=$(( ((spp + n - 1) / n + 3) / 4 * 4 ))  # a multiple of 4: the path tracer's own block of samples
first=$(( i * block ))
end=$(( first + block < spp ? first + block : spp ))
if [ "$first" -ge "$end" ]; then exit 0; fi  # more tasks than samples: this one has none
exec "${MESOLAB:-mesolab}" capture "$scene" --backend truth --samples "$first:$end" \
    --size "${SIZE:-512x512}" --seed "${SEED:-1}" -o "$out"
