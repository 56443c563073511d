#!/usr/bin/env bash
# Install everything seahaze needs on a fresh Debian 12 machine, from the project's own files:
#   system: libLLVM 19 for Mitsuba's llvm variants (Debian's default LLVM 15 aborts inside drjit);
#   python: a virtual environment in .venv with seahaze, its test tools and the MP4 preview's
#   imageio-ffmpeg (pyproject.toml's test and video extras).
# Safe to run again: it only installs what is missing. Called by `make render` and `make test`.
set -euo pipefail
cd "$(dirname "$0")/.."

have_llvm() { compgen -G "/usr/lib/*/libLLVM.so.19*" >/dev/null || compgen -G "/usr/lib/*/libLLVM-19.so*" >/dev/null; }

if ! have_llvm; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "[bootstrap] installing libllvm19 (apt-get)"
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19 >/dev/null
  else
    echo "[bootstrap] warning: libLLVM 19 not found and cannot apt-get install it;" \
         "seahaze cannot render without it (or an NVIDIA GPU); install libllvm19" >&2
  fi
fi

PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "[bootstrap] creating .venv with $($PYTHON --version)"
  "$PYTHON" -m venv .venv
fi
echo "[bootstrap] installing seahaze and test tools into .venv"
.venv/bin/python -m pip install -q --disable-pip-version-check --upgrade pip
# The video and mot extras too: the MP4 preview and py-motmetrics tests run (skipped without).
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[test,video,mot]'
touch .venv/.seahaze-installed
