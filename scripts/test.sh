#!/usr/bin/env bash
# All tests of the project (what CI runs, see README.md): Rust, the GPU kernels on a CPU Vulkan
# driver, ParaView output read back by VTK, sweeps submitted through a real local Slurm, and the
# Python package with pytest. The GPU kernels' tests need a Vulkan driver with 64-bit float
# shaders: on a machine without a GPU that is Mesa's lavapipe (CPU Vulkan, Debian package
# mesa-vulkan-drivers), installed here when missing. Where lavapipe (or a GPU) is present the
# GPU tests are required to run (PDAMP_REQUIRE_GPU_TESTS=1), not skipped.
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

# A Python with VTK (the library ParaView is built on) for the tests that open pdamp's ParaView
# output with VTK's own readers (crates/pdamp-cli/tests/paraview.rs), in target/test-venv.
venv=target/test-venv
has_vtk() { "$venv/bin/python" -c "import vtkmodules.vtkIOXML" >/dev/null 2>&1; }
if ! has_vtk; then
  if ! command -v python3 >/dev/null 2>&1 || ! python3 -c "import venv, ensurepip" >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
      echo "installing python3 and python3-venv for the VTK reader tests"
      apt-get update -qq >/dev/null
      DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3 python3-venv >/dev/null
    fi
  fi
  echo "making $venv (pip install -r scripts/requirements-test.txt)"
  rm -rf "$venv"
  python3 -m venv "$venv" && "$venv/bin/pip" install -q -r scripts/requirements-test.txt \
    || echo "WARNING: no Python with VTK: the VTK reader tests will be skipped" >&2
fi
if has_vtk; then
  export PDAMP_TEST_PYTHON="$PWD/$venv/bin/python"
  export PDAMP_REQUIRE_VTK_TESTS=1
fi

# A real one-node Slurm cluster on localhost for the sweep tests (crates/pdamp-cli/tests/
# sweep_slurm.rs): Debian's slurm-wlm and munge, installed when missing, started here and
# stopped when the tests end. Where it comes up the Slurm tests are required to run.
if slurm_env=$(bash scripts/slurm-local.sh start); then
  eval "$slurm_env"
  export PDAMP_REQUIRE_SLURM_TESTS=1
  trap 'bash scripts/slurm-local.sh stop' EXIT
else
  echo "WARNING: no Slurm cluster could be started: the Slurm sweep tests will be skipped" >&2
fi

# --release: the same build as the README's `cargo run --release` (built once, not twice; see
# the profiles in Cargo.toml). The test harnesses keep debug assertions ([profile.bench]).
status=0
cargo test --release --workspace --no-fail-fast "$@" || status=$?
# The Python package (python/, the PyO3 extension crates/pdamp-py): built into a virtual
# environment with maturin (reusing this build's artifacts) and tested with pytest against the
# `pdamp` binary of the same build.
pyvenv=target/py-venv
if ! "$pyvenv/bin/python" -c "import maturin, pytest, numpy, pandas, tqdm, matplotlib" >/dev/null 2>&1; then
  echo "making $pyvenv (pip install -r python/requirements-test.txt)"
  rm -rf "$pyvenv"
  python3 -m venv "$pyvenv" && "$pyvenv/bin/pip" install -q -r python/requirements-test.txt || status=1
fi
if [ -x "$pyvenv/bin/maturin" ]; then
  (cd python && VIRTUAL_ENV="$PWD/../$pyvenv" PATH="$PWD/../$pyvenv/bin:$PATH" maturin develop --release --quiet) \
    && PDAMP_BIN="$PWD/target/release/pdamp" "$pyvenv/bin/pytest" -q python/tests || status=$?
else
  echo "ERROR: no Python environment with maturin: the Python package was not tested" >&2
  status=1
fi
# Lints are part of the tests: formatting, and clippy with every warning an error (issue 30).
cargo fmt --all --check || status=$?
# Architecture limits (issue 30): no library function over 150 lines, no source file over 900
# lines of code, no module cycle.
for check in fnlen sizes modcycles; do python3 "tools/$check.py" || status=$?; done
cargo clippy --release --workspace --all-targets -- -D warnings || status=$?
# … and the API documentation builds without a warning (broken links, unclosed tags).
RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps --workspace || status=$?
exit $status
