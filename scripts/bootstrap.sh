#!/usr/bin/env bash
# Install everything seahaze needs on a fresh Debian 12 machine, from the project's own files:
#   system: libLLVM 19 for Mitsuba's llvm variants (Debian's default LLVM 15 aborts inside drjit);
#   python: a virtual environment in .venv with seahaze, its test tools, the MP4 preview's
#   imageio-ffmpeg, py-motmetrics and Hugging Face datasets (pyproject.toml's test, video, mot
#   and hf extras).
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
# The video, mot and hf extras too: the MP4 preview, py-motmetrics and Hugging Face datasets
# tests run (skipped without). hf adds about 210 MB to the 1 GB .venv (170 MB of it pyarrow) and
# about 4 s to a pip install from a warm wheel cache.
.venv/bin/python -m pip install -q --disable-pip-version-check -e '.[test,video,mot,hf]'
touch .venv/.seahaze-installed
