#version 430
// Camera-frame z of the nearest surface (perspective-correct, so exact on the triangle's plane).
in float v_z;
layout(location = 0) out float f_value;

void main() {
    f_value = v_z;
}
