#!/usr/bin/env bash
# The test suite's independent glTF check (CTest gltf_validator_ktx_parse): `burnish gltf` on the test
# plane (a real map as its normal texture), as .gltf with raw and BC payloads, with
# KHR_materials_anisotropy, with BURNISH_lobe_mixture (RGBA16F lobe chains) and as .glb, a material
# written from one map (`burnish gltf --normal-map`), and
# Debian's assimp-testmodels ClearCoatTest.gltf where installed; Khronos's gltf-validator reports no
# error Burnish added, ktx-parse reads every KTX2 chain back in full, and the raw plane's levels equal
# `burnish bake --preset gltf --format png8` of the same map, code for code (check_gltf.mjs). Skips
# (exit 77, with the reason) where Node or the pinned npm packages (.ci/deps installs them) are missing.
#   run_gltf_check.sh BURNISH_BIN
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
burnish="$1"
skip() { echo "SKIPPED: $*"; exit 77; }
command -v node >/dev/null || skip "node is not installed (Debian: nodejs)"
[ -d "$here/node_modules/gltf-validator" ] && [ -d "$here/node_modules/ktx-parse" ] ||
  skip "the npm packages are not installed (cd tests/threejs && npm ci)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir "$work/in"
cp "$here/../data/gltf/plane.gltf" "$work/in/"
cp "$here/../data/trak-treadplate1_nm.png" "$work/in/normal.png"
check() { node "$here/check_gltf.mjs" "$@" > "$work/check.json" || { cat "$work/check.json"; exit 1; }
  node -e 'const d=JSON.parse(require("fs").readFileSync(process.argv[1]));
    console.log(process.argv[2], "validator errors", d.validator.errors, "(of the input", d.validator.errorsOfTheInput + ")",
      "ktx2", d.ktx2.map(k => k.format + " " + k.width + "x" + k.height + "/" + k.levels).join(", "),
      "compared", JSON.stringify(d.compared), "mixtures", JSON.stringify(d.mixtures))' "$work/check.json" "$1"; }
# The plane's roughnessFactor 0.5 is Blinn-Phong power 2/0.5^4 - 2 = 30 in the gltf preset's terms.
"$burnish" gltf "$work/in/plane.gltf" --out "$work/raw" > /dev/null
"$burnish" bake "$work/in/normal.png" --preset gltf --power 30 --format png8 --out "$work/bake" > /dev/null
check "$work/raw/plane.gltf" --bake "$work/bake"
"$burnish" gltf "$work/in/plane.gltf" --out "$work/bc" --coding bc > /dev/null
check "$work/bc/plane.gltf"
"$burnish" gltf "$work/in/plane.gltf" --out "$work/aniso" --anisotropy on > /dev/null
check "$work/aniso/plane.gltf"
"$burnish" gltf "$work/in/plane.gltf" --out "$work/mixture" --method mixture > /dev/null
check "$work/mixture/plane.gltf" --bake "$work/bake"
node "$here/to_glb.mjs" "$work/in/plane.gltf" "$work/in/plane.glb"
"$burnish" gltf "$work/in/plane.glb" --out "$work/glb" > /dev/null
check "$work/glb/plane.glb" --bake "$work/bake"
# A material of one map (the studio's File ▸ Export glTF): a dielectric with its specular colour.
"$burnish" gltf --normal-map "$work/in/normal.png" --dielectric --specular 0.02,0.03,0.04 --roughness 0.4 \
  --name plastic --out "$work/material" > /dev/null
check "$work/material/plastic.gltf"
# The same with the lobe mixture (the studio's export of a mixture: its pruned and renumbered textures).
"$burnish" gltf --normal-map "$work/in/normal.png" --method mixture --lobes 2 --name mixed \
  --out "$work/material-mixture" > /dev/null
check "$work/material-mixture/mixed.gltf"
clearcoat=/usr/share/assimp/models/glTF2/ClearCoat-glTF/ClearCoatTest.gltf
if [ -f "$clearcoat" ]; then
  "$burnish" gltf "$clearcoat" --out "$work/clearcoat" > /dev/null
  check "$work/clearcoat/ClearCoatTest.gltf" --input "$clearcoat"
else
  echo "note: $clearcoat missing (Debian: assimp-testmodels): checked the test plane only"
fi
