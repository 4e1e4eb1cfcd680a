// The error heatmap: the absolute difference of linear luminance between the method's HDR image
// and the supersampled reference, as a colour ramp (black = equal, white = uFullScale or more).
// Both textures have the target's size; the texel under the fragment is compared.
#include "common_math.glsl"

uniform sampler2D uCurrent;
uniform sampler2D uReference;
uniform float uFullScale;

layout(location = 0) out vec4 fragColor;

// ITU-R BT.709: Y = 0.2126 R + 0.7152 G + 0.0722 B (core's luminance, color.h)
float luminance709(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Black → blue → green → yellow → red → white for t in [0, 1].
vec3 errorRamp(float t) {
    float x = saturate(t) * 5.0;
    if (x < 1.0) return mix(vec3(0.0), vec3(0.0, 0.0, 1.0), x);
    if (x < 2.0) return mix(vec3(0.0, 0.0, 1.0), vec3(0.0, 1.0, 0.0), x - 1.0);
    if (x < 3.0) return mix(vec3(0.0, 1.0, 0.0), vec3(1.0, 1.0, 0.0), x - 2.0);
    if (x < 4.0) return mix(vec3(1.0, 1.0, 0.0), vec3(1.0, 0.0, 0.0), x - 3.0);
    return mix(vec3(1.0, 0.0, 0.0), vec3(1.0), x - 4.0);
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float current = luminance709(texelFetch(uCurrent, p, 0).rgb);
    float error = abs(current - luminance709(texelFetch(uReference, p, 0).rgb));
    // A full scale below 1e-6 would divide by (nearly) zero; it means "any error is full scale".
    fragColor = vec4(errorRamp(error / max(uFullScale, 1e-6)), 1.0);
}
