#!/usr/bin/env bash
# All tests of the project (what CI runs, see README.md). The GPU kernels' tests need a Vulkan
# driver with 64-bit float shaders: on a machine without a GPU that is Mesa's lavapipe (CPU
# Vulkan, Debian package mesa-vulkan-drivers), installed here when missing. Where lavapipe (or a
# GPU) is present the GPU tests are required to run (PDAMP_REQUIRE_GPU_TESTS=1), not skipped.
set -euo pipefail
cd "$(dirname "$0")/.."
have_vulkan() {
  # (no `grep -q` in a pipe: under pipefail its early exit fails the pipeline)
  local libs icds
  libs=$(ldconfig -p 2>/dev/null || true)
  icds=$(ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json 2>/dev/null || true)
  [[ "$libs" == *libvulkan.so.1* ]] && [ -n "$icds" ]
}
if ! have_vulkan; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    echo "installing Mesa's lavapipe (mesa-vulkan-drivers) for the GPU kernel tests"
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
  fi
fi
if have_vulkan; then
  export PDAMP_REQUIRE_GPU_TESTS=1
else
  echo "WARNING: no Vulkan driver and none could be installed: the GPU kernel tests will be skipped" >&2
fi
# lavapipe's window-system layer complains without it
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
cargo test --workspace "$@"
