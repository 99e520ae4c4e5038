#version 430
// Static scenery in the label pass: occludes the body but is labelled background (0).
in float v_z;
layout(location = 0) out float f_value;

void main() {
    f_value = 0.0;
}
