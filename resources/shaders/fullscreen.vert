// One triangle that covers the viewport, made from gl_VertexID alone (draw 3 vertices with an empty
// VAO: FullscreenTriangle). Clip-space corners (-1,-1), (3,-1), (-1,3): the part outside the
// viewport is clipped, and every pixel is shaded once, with no diagonal seam.
// vUv is 0 at the bottom-left and 1 at the top-right of the viewport (v up, like texture v).

out vec2 vUv;

void main() {
    vec2 clip = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    vUv = clip * 0.5 + 0.5;
    gl_Position = vec4(clip, 0.0, 1.0);
}
