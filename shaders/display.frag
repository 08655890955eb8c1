#version 330 core
// Display mapping of the tpb viewer. Input: raw linear radiance (GL_RGB32F), one texel per film
// pixel; texel (x, y) is written to target pixel (x, y), so the film's row order is kept.
// Output: display RGB in [0, 1]:
//   - exposure: radiance * 2^EV (uScale)
//   - either sRGB encoding (or plain clamping when uSrgb == 0),
//   - or a false-colour map of log10 luminance over uDecades decades below 1.0 (after exposure):
//     black = no energy, dark blue -> cyan -> green -> yellow -> red, white = over-exposed.
// NaN/Inf or negative values (never expected from the film) are shown in magenta.
uniform sampler2D uImage;
uniform float uScale;
uniform int uSrgb;
uniform int uFalseColor;
uniform float uDecades;

out vec4 fragColor;

float srgbEncode(float v) {
    v = clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

vec3 ramp(float t) {
    // Piecewise-linear colour ramp, t in [0, 1].
    const int N = 6;
    vec3 stops[N] = vec3[N](vec3(0.02, 0.02, 0.12), vec3(0.10, 0.15, 0.65), vec3(0.00, 0.60, 0.85),
                            vec3(0.15, 0.78, 0.30), vec3(0.98, 0.85, 0.10), vec3(0.90, 0.15, 0.05));
    float x = clamp(t, 0.0, 1.0) * float(N - 1);
    int i = min(int(floor(x)), N - 2);
    return mix(stops[i], stops[i + 1], x - float(i));
}

bool bad(float v) { return isnan(v) || isinf(v) || v < 0.0; }

void main() {
    vec3 c = texelFetch(uImage, ivec2(gl_FragCoord.xy), 0).rgb;
    if (bad(c.r) || bad(c.g) || bad(c.b)) {
        fragColor = vec4(1.0, 0.0, 1.0, 1.0);
        return;
    }
    c *= uScale;
    if (uFalseColor != 0) {
        float lum = dot(c, vec3(0.2126, 0.7152, 0.0722));
        vec3 o;
        if (lum <= 0.0) o = vec3(0.0);
        else if (lum > 1.0) o = vec3(1.0);
        else o = ramp(1.0 + log(lum) / (log(10.0) * max(uDecades, 0.1)));
        fragColor = vec4(o, 1.0);
        return;
    }
    if (uSrgb != 0) c = vec3(srgbEncode(c.r), srgbEncode(c.g), srgbEncode(c.b));
    fragColor = vec4(clamp(c, 0.0, 1.0), 1.0);
}
