// The environment behind the mesh: in each pixel's view direction, level 0 of uEnvironment (the
// background's own cube, or the lighting's: the prefiltered cube's top lobe, or the source for FIS),
// turned and scaled as the lighting (uEnvironmentRotation, uEnvironmentIntensity as the renderer's
// setEnvironmentTurnAndScale sets them). Written as linear HDR, or with DISPLAY_OUTPUT as display values (tonemap.frag's transform),
// before the mesh is drawn over it.

#include "common_color.glsl"

#ifndef DISPLAY_OUTPUT
#define DISPLAY_OUTPUT 0
#endif

in vec2 vUv;
out vec4 fragColor;

uniform samplerCube uEnvironment;
uniform mat3 uEnvironmentRotation;    // world direction → environment direction
uniform float uEnvironmentIntensity;
uniform mat4 uInverseViewProjection;  // clip → world, of the material pass's camera
uniform float uExposure;              // the linear scale 2^EV (DISPLAY_OUTPUT)

void main() {
    vec2 ndc = vUv * 2.0 - 1.0;
    vec4 nearPoint = uInverseViewProjection * vec4(ndc, -1.0, 1.0);
    vec4 farPoint = uInverseViewProjection * vec4(ndc, 1.0, 1.0);
    vec3 direction = normalize(farPoint.xyz / farPoint.w - nearPoint.xyz / nearPoint.w);
    vec3 radiance = textureLod(uEnvironment, uEnvironmentRotation * direction, 0.0).rgb * uEnvironmentIntensity;
#if DISPLAY_OUTPUT
    fragColor = vec4(displayFromHdr(radiance, uExposure), 1.0);
#else
    fragColor = vec4(radiance, 1.0);
#endif
}
