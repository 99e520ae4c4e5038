#version 430
// Joint label + 1 of the dominant interpolated skinning weight (0 is left for background).
in vec4 v_parts[4];
layout(location = 0) out float f_value;

void main() {
    float best = -1.0;
    int label = 0;
    for (int j = 0; j < 16; ++j) {
        float w = v_parts[j / 4][j % 4];
        if (w > best) { best = w; label = j; }
    }
    f_value = float(label + 1);
}
