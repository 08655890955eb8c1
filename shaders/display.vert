#version 330 core
// Display pass of the tpb viewer: one triangle that covers the whole target (no vertex buffer).
// The target is an offscreen image with exactly one fragment per film pixel (see display.frag).
void main() {
    vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
