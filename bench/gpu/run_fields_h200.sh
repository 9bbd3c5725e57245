#!/usr/bin/env bash
# Effective fields on the GPU backend (issue 29, must-show 3): the softened 12 × 9 baseline
# field of D Sect. 8.1.2 and one column (96.2 Hz × 9 intensities) at the dissertation's moduli,
# each with `pdamp fields --device gpu` (beds prepared on the CPU, points as one batch of worlds
# on the GPU). Writes $OUT/{softened,column}_fields.csv, the JSON summaries and log.txt.
#
#   PDAMP_BIN=target/release/pdamp OUT=out/gpu_fields bash bench/gpu/run_fields_h200.sh
set -u
BIN=${PDAMP_BIN:-target/release/pdamp}
OUT=${OUT:-out/gpu_fields}
WORK=${WORK:-/tmp/pdamp_gpu_fields}
mkdir -p "$OUT" "$WORK"
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
log() { echo "[$(date +%T)] $*" | tee -a "$OUT/log.txt"; }
field() { # name, scenario
  local name=$1 sc=$2 t0 t1
  log "$name: $BIN fields $sc --device gpu"
  t0=$(date +%s.%N)
  "$BIN" fields "$sc" --out "$WORK/$name" --device gpu >"$OUT/$name.json" 2>>"$OUT/log.txt"
  local rc=$?
  t1=$(date +%s.%N)
  log "$name: rc $rc, $(awk "BEGIN{print $t1 - $t0}") s"
  cp "$WORK/$name/fields.csv" "$OUT/${name}_fields.csv" 2>/dev/null
}
log "machine: $(nproc) cores; $(nvidia-smi -L 2>/dev/null | head -1)"
field softened examples/damper_cylinder_baseline_softened.toml
field column examples/damper_cylinder_baseline_column.toml
log done
