// Copies the HDR texel under the fragment, weighted: one pass of the supersampled reference added
// into the RGBA32F accumulation target (additive blending ONE, ONE, weight 1/N), and the display
// pass of the data debug views (weight 1; their values are display values, the RGBA8 target clamps).
// Source and target must have the same size.
uniform sampler2D uSource;
uniform float uWeight;

layout(location = 0) out vec4 fragColor;

void main() {
    fragColor = texelFetch(uSource, ivec2(gl_FragCoord.xy), 0) * uWeight;
}
