// HDR → display: exposure (a linear scale, 2^EV computed on the CPU), the filmic curve, then the
// sRGB encoding. TONEMAP_NONE 1 skips the curve (exposure and encoding only), for measurements.

#include "common_color.glsl"

#ifndef TONEMAP_NONE
#define TONEMAP_NONE 0
#endif

in vec2 vUv;
out vec4 fragColor;

uniform sampler2D uHdr;
uniform float uExposure;

void main() {
#if TONEMAP_NONE
    fragColor = vec4(linearToSrgb(clamp01(texture(uHdr, vUv).rgb * uExposure)), 1.0);
#else
    fragColor = vec4(displayFromHdr(texture(uHdr, vUv).rgb, uExposure), 1.0);
#endif
}
