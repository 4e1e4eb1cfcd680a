// The material pass's vertex stage: world position, the shading frame (normal + tangent with its
// handedness in w) and the texture coordinate, with an optional sub-pixel jitter of the projection
// for the supersampled reference.
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec4 aTangent;
layout(location = 3) in vec2 aUv;

uniform mat4 uModel;
uniform mat3 uNormalMatrix;
uniform mat4 uViewProjection;
// Sub-pixel offset in normalized device coordinates (2·pixels/size); zero outside the reference.
uniform vec2 uJitterNdc;
// Texture tiling on top of the mesh's own UV repeat.
uniform float uUvScale;

out vec3 vWorldPosition;
out vec3 vNormal;
out vec4 vTangent;
out vec2 vUv;

void main() {
    vec4 world = uModel * vec4(aPosition, 1.0);
    vWorldPosition = world.xyz;
    vNormal = uNormalMatrix * aNormal;
    vTangent = vec4(mat3(uModel) * aTangent.xyz, aTangent.w < 0.0 ? -1.0 : 1.0);
    vUv = aUv * uUvScale;
    gl_Position = uViewProjection * world;
    // Offsetting clip xy by jitter·w moves the projected point by exactly `jitter` in NDC.
    gl_Position.xy += uJitterNdc * gl_Position.w;
}
