#!/usr/bin/env bash
# Side-by-side throughput of pdamp's GPU backend and its CPU engine on one machine (issue 29):
# GPU large beds (1e6 and 4e6 spheres), a batch of 108 × 4 500-sphere worlds (a 12 × 9 field),
# the run-to-run determinism check on the GPU, and the CPU engine's 1 → 16 thread scaling at
# N = 32 000 and 256 000 — all the shaken-box benchmark of `pdamp bench`.
#
#   PDAMP_BIN=target/release/pdamp OUT=out/gpu_bench bash bench/gpu/run_h200.sh
#
# Every result is one JSON line appended to $OUT/results.jsonl as soon as it is measured (a run
# cut short keeps what it has); the log goes to $OUT/log.txt. Knobs: GPU_STEPS, GPU_SETTLE,
# CPU_THREADS ("1 2 4 8 16"), SKIP_CPU=1, SKIP_4M=1.
set -u
BIN=${PDAMP_BIN:-target/release/pdamp}
OUT=${OUT:-out/gpu_bench}
mkdir -p "$OUT"
RES="$OUT/results.jsonl"
LOG="$OUT/log.txt"
GPU_STEPS=${GPU_STEPS:-1000}
GPU_SETTLE=${GPU_SETTLE:-2000}
CPU_THREADS=${CPU_THREADS:-"1 2 4 8 16"}
# NVIDIA's Vulkan driver where the loader does not find it by itself. The ICD
# (libGLX_nvidia.so.0) needs libglvnd (libGLdispatch) besides the Vulkan loader libvulkan.so.1:
# on a bare image install libvulkan1 libglvnd0 libgl1 libglx0 libegl1 (Debian/Ubuntu).
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
log() { echo "[$(date +%T)] $*" | tee -a "$LOG"; }
run() { # label, command...
  local label=$1; shift
  log "$label: $*"
  local t0=$(date +%s.%N)
  local line
  # (pdamp prints one pretty-printed JSON object; without its newlines it is one JSON line)
  line=$("$@" 2>>"$LOG" | tr -d '\n')
  local rc=$?
  local t1=$(date +%s.%N)
  if [ -n "$line" ] && [ "${line:0:1}" = "{" ]; then
    echo "{\"label\":\"$label\",\"command_wall_s\":$(awk "BEGIN{print $t1 - $t0}"),\"result\":$line}" >>"$RES"
    log "  -> $line"
  else
    echo "{\"label\":\"$label\",\"failed\":true}" >>"$RES"
    log "  -> failed (rc $rc)"
  fi
}
log "machine: $(nproc) cores; $(nvidia-smi -L 2>/dev/null | head -1)"
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv,noheader >>"$LOG" 2>&1
# GPU: determinism (two identical runs), large beds, batched field.
run gpu_32k_a "$BIN" bench --device gpu --particles 32000 --steps "$GPU_STEPS" --settle-steps "$GPU_SETTLE"
run gpu_32k_b "$BIN" bench --device gpu --particles 32000 --steps "$GPU_STEPS" --settle-steps "$GPU_SETTLE"
run gpu_batch_108x4500 "$BIN" bench --device gpu --particles 4500 --batch 108 --steps "$GPU_STEPS" --settle-steps "$GPU_SETTLE"
run gpu_1m "$BIN" bench --device gpu --particles 1000000 --steps "$GPU_STEPS" --settle-steps "$GPU_SETTLE"
if [ "${SKIP_4M:-0}" != 1 ]; then
  run gpu_4m "$BIN" --threads 16 bench --device gpu --particles 4000000 --steps $((GPU_STEPS / 2)) --settle-steps $((GPU_SETTLE / 2))
fi
# CPU engine: 1 → 16 threads on one settled bed per size.
if [ "${SKIP_CPU:-0}" != 1 ]; then
  for n in 32000 256000; do
    steps=$(( n >= 256000 ? 100 : 400 ))
    bed="$OUT/bed_$n.bin"
    log "settling the CPU bed of $n spheres (16 threads, not timed)"
    "$BIN" --threads 16 bench --particles "$n" --steps 1 --settled "$bed" >>"$LOG" 2>&1
    for t in $CPU_THREADS; do
      run "cpu_${n}_t$t" "$BIN" --threads "$t" bench --particles "$n" --steps "$steps" --settled "$bed"
    done
    rm -f "$bed"
  done
fi
log "done"
