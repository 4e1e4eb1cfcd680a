#!/usr/bin/env bash
# How long the studio keeps an artist waiting, for a real normal map resized to each size
# (oiiotool): load to the first frame with the map's bake, a method change and a base-gloss change
# to the first frame that draws them, the viewport frame that takes a bake in, and the process's
# peak memory (the budget the studio keeps: under 4 GB for an 8192² map); then Paint switched on (how
# long the GUI thread is held, and until the live bake is ready) and a gloss stroke painted
# on the texture view: time to 2D, to 3D, from its release to the frame that draws it, the longest GUI
# stall, and the peak memory with a painted layer. The whole main window runs
# (offscreen unless QT_QPA_PLATFORM says otherwise), with its background loads and bakes. Figures, not
# a pass/fail test.
#
#   core/bench/studio_latency.sh LATENCY_BINARY MAP [SIZES...]   (default sizes: 512 2048 8192)
#   LATENCY_BINARY: build/bin/burnish_studio_latency
#   PRESET=gltf core/bench/studio_latency.sh ...   paints under that preset's method (default blackops)
set -euo pipefail
binary=$1
map=$2
shift 2
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(512 2048 8192)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/home"

echo "| map | load to first frame, ms | method change, ms | gloss change, ms: median (range) | landing frame, ms | peak resident MB | Paint on: GUI held, ms | live bake ready, ms | stroke: to 2D, ms | to 3D, ms | after release, ms | longest GUI stall, ms | peak resident MB with paint |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
for size in "${sizes[@]}"; do
    # Unassociated alpha: OpenImageIO would otherwise premultiply an RGBA map's normals by its alpha.
    oiiotool --iconfig oiio:UnassociatedAlpha 1 "$map" --ch R,G,B --resize:filter=triangle "${size}x${size}" \
        -o "$work/map.png"
    HOME="$work/home" QT_QPA_PLATFORM="${QT_QPA_PLATFORM:-offscreen}" "$binary" --preset "${PRESET:-blackops}" \
        "$work/map.png"
done
