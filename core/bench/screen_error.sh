#!/usr/bin/env bash
# Issue 14's screen-space figures: each method's image against the supersampled ground truth
# (`burnish render --compare N`: relative L1 of linear HDR luminance over the pixels the object
# covers, and the energy ratio), on the plane and the sphere at several distances. A metal of
# constant F0 (no diffuse, no Fresnel), so only the specular lobes differ. On the plane the light is
# the camera's direction mirrored in it, so the flat-mirror highlight sits on the target. Figures,
# not a pass/fail test.
#
#   core/bench/screen_error.sh BURNISH MAP [POWER] [SAMPLES] [METHODS]
#
# METHODS defaults to naive,lean,mixture (mixture-shaded: the mixture with --shaded-fit;
# mixture-stochastic: filtered after shading, --mixture-filtering stochastic with 64 passes averaged); the reference's own noise (as the same ratio) is printed
# beside each row: an error not well above it is noise. A second table gives the shimmer of a slow
# orbit at distance 4 (`render --sequence 8`, 0.5° a frame, mean |ΔY| of linear HDR luminance per
# pixel between frames) for each method and the reference.
set -euo pipefail
bin=$1
map=$2
power=${3:-256}
samples=${4:-256}
methods=${5:-naive,lean,mixture}
common=(--metal --specular 0.9 --fresnel none --power "$power" --size 256x256 --uv-scale 2
        --compare "$samples" --json)
# Camera yaw 30°, pitch 30°: the direction to the camera is (0.433, 0.5, 0.75); mirrored in the plane.
plane=(--mesh plane --pitch 30 --light-dir=-0.433,0.5,-0.75)
sphere=(--mesh sphere)

# A method's render arguments: mixture-shaded is the mixture fitted to the shaded truth too,
# mixture-stochastic the mixture filtered after shading.
method_args() {
  case "$1" in
    mixture-shaded) echo "--method mixture --shaded-fit" ;;
    mixture-stochastic) echo "--method mixture --mixture-filtering stochastic --mixture-samples 64" ;;
    *) echo "--method $1" ;;
  esac
}

field() { python3 -c "import json,sys; j=json.load(sys.stdin); print(' '.join('%.4f' % j[k] for k in sys.argv[1:]))" "$@"; }

echo "$(basename "$map"), power $power, reference $samples samples per pixel, 256x256, uv scale 2"
echo
header="| mesh | distance |"
rule="| --- | ---: |"
IFS=, read -r -a list <<< "$methods"
for m in "${list[@]}"; do header+=" $m rel. L1 (energy) |"; rule+=" ---: |"; done
echo "$header reference noise |"
echo "$rule ---: |"
for mesh in plane sphere; do
  for distance in 2 4 8; do
    row="| $mesh | $distance |"
    noise=""
    for m in "${list[@]}"; do
      if [ "$mesh" = plane ]; then extra=("${plane[@]}"); else extra=("${sphere[@]}"); fi
      read -r l1 energy n < <("$bin" render "$map" $(method_args "$m") --distance "$distance" "${extra[@]}" \
                                "${common[@]}" 2>/dev/null | field relative_l1 energy_ratio reference_noise_l1)
      row+=" $l1 ($energy) |"
      noise=$n
    done
    echo "$row $noise |"
  done
done

echo
echo "Shimmer at distance 4 (8 frames, 0.5 degrees a frame, reference $samples samples):"
echo
header="| mesh |"
rule="| --- |"
for m in "${list[@]}"; do header+=" $m |"; rule+=" ---: |"; done
echo "$header reference |"
echo "$rule ---: |"
for mesh in plane sphere; do
  row="| $mesh |"
  reference=""
  for m in "${list[@]}"; do
    if [ "$mesh" = plane ]; then extra=("${plane[@]}"); else extra=("${sphere[@]}"); fi
    read -r mine theirs < <("$bin" render "$map" $(method_args "$m") --distance 4 "${extra[@]}" --metal \
        --specular 0.9 --fresnel none --power "$power" --size 256x256 --uv-scale 2 --sequence 8 \
        --reference "$samples" --json 2>/dev/null | field method_mean reference_mean)
    row+=" $mine |"
    reference=$theirs
  done
  echo "$row $reference |"
done
