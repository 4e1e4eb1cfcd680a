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
    vec3 hdr = texture(uHdr, vUv).rgb * uExposure;
#if TONEMAP_NONE
    vec3 display = clamp01(hdr);
#else
    vec3 display = tonemapFilmic(hdr);
#endif
    fragColor = vec4(linearToSrgb(display), 1.0);
}
