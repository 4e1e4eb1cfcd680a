#!/usr/bin/env bash
# The test suite's three.js check (CTest threejs_fitted_never_worse): one real map at two distances,
# Burnish's fitted roughness chain drawn by three.js in headless Chromium, never worse than three.js's
# own result beyond the supersampled reference's noise: as a DataTexture chain, then through glTF (the
# asset `burnish gltf` writes, loaded by GLTFLoader + KTX2Loader + resources/three/burnish-gltf.js); and the
# lobe mixture (`burnish gltf --method mixture`, drawn by burnish-gltf.js's material patch) meeting its
# targets there: never worse, at most half of three.js's own error, energy within [0.9, 1.1]. Skips (exit 77, with the reason) where Chromium,
# Node or the pinned npm packages (.ci/deps installs them) are missing.
#   run_check.sh BURNISH_BIN
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
burnish="$1"
chromium="${BURNISH_CHROMIUM:-/usr/bin/chromium}"
skip() { echo "SKIPPED: $*"; exit 77; }
command -v node >/dev/null || skip "node is not installed (Debian: nodejs)"
[ -x "$chromium" ] || skip "$chromium is not installed (Debian: chromium)"
[ -d "$here/node_modules/three" ] && [ -d "$here/node_modules/puppeteer-core" ] ||
  skip "the npm packages are not installed (cd tests/threejs && npm ci)"
node "$here/compare.mjs" --burnish "$burnish" --maps "$here/../data/trak-treadplate1_nm.png" \
  --distances 8,32 --methods vmf,fitted --supersample 16 --assert-never-worse fitted
exec node "$here/compare.mjs" --burnish "$burnish" --maps "$here/../data/trak-treadplate1_nm.png" \
  --distances 8,32 --methods fitted,mixture --supersample 16 --gltf --assert-never-worse "gltf fitted" \
  --assert-mixture "gltf mixture"
