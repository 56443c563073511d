#!/usr/bin/env bash
# Time seahaze under the cuda_ad_rgb variant on a machine with an NVIDIA GPU, and keep small
# renders to compare with the CPU's (scripts/compare_variants.py). Results: docs/benchmarks.md,
# "How fast is cuda_ad_rgb on a GPU, and does the suite pass there?".
#
# Usage: bash scripts/bench_gpu.sh OUT_DIR        (seahaze importable by $PYTHON, default python3)
# Writes OUT_DIR/timings.txt, OUT_DIR/*.jsonl (the renders' logs) and OUT_DIR/compare.tgz (the
# 160x90, 16 spp default-scene and 64x36 patchy-scene datasets, for the comparison).
set -u
OUT=$(realpath -m "$1"); mkdir -p "$OUT"; WORK=$(mktemp -d)
PY=${PYTHON:-python3}
render() {  # NAME ARGS...: one `seahaze render` process, wall time in ms into timings.txt
  local name=$1; shift
  local t0; t0=$(date +%s%N)
  $PY -m seahaze.cli render "$@" --variant cuda_ad_rgb --quiet --out "$WORK/$name" \
    --log "$OUT/$name.jsonl"
  echo "$name rc=$? wall_ms=$(( ($(date +%s%N) - t0) / 1000000 ))" | tee -a "$OUT/timings.txt"
}
nvidia-smi -L | tee "$OUT/timings.txt"
# Same seed and size as the CPU's comparison renders: images that should agree to noise.
render cmp_default scenes/default.yaml --vis 300..4000 --res 160x90 --spp 16
render cmp_patchy scenes/patchy.yaml --vis 300,1000,4000 --res 64x36 --spp 4
tar -czf "$OUT/compare.tgz" -C "$WORK" cmp_default cmp_patchy
# Dataset size: the default scene with an empty kernel cache for its size (cold), then again.
render full_cold scenes/default.yaml --vis 300..4000
render full_warm scenes/default.yaml --vis 300..4000
render msvd scenes/msvd.yaml --scenes "${MSVD_SCENES:-6}" --vis 300..4000
rm -rf "$WORK"
