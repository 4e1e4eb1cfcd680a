#!/usr/bin/env bash
# The studio's peak memory and time to its first frame with a normal map of each size: the map is a
# real one resized (oiiotool), opened from the command line, drawn once off screen and saved as a
# screenshot (`burnish-studio --screenshot`). The budget the studio keeps: under 4 GB for an 8192²
# map. Figures, not a pass/fail test.
#
#   core/bench/studio_memory.sh STUDIO MAP [SIZES...]      (default sizes: 512 2048 8192)
set -euo pipefail
studio=$1
map=$2
shift 2
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(512 2048 8192)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/home"

echo "| map | seconds to the first frame (exit) | peak resident MB |"
echo "| --- | ---: | ---: |"
for size in "${sizes[@]}"; do
    # Unassociated alpha: OpenImageIO would otherwise premultiply an RGBA map's normals by its alpha.
    oiiotool --iconfig oiio:UnassociatedAlpha 1 "$map" --ch R,G,B --resize:filter=triangle "${size}x${size}" \
        -o "$work/map.png"
    HOME="$work/home" QT_QPA_PLATFORM=offscreen /usr/bin/time -f "%e %M" -o "$work/time" \
        "$studio" --screenshot "$work/shot.png" "$work/map.png" >/dev/null 2>&1
    read -r seconds kb <"$work/time"
    echo "| ${size}² | $seconds | $((kb / 1024)) |"
done
echo
echo "Budget: under 4096 MB for 8192²."
