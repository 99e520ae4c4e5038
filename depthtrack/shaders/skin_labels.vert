#version 430
// One pose; passes every vertex's skinning weights per joint (up to 16 joints) on to the
// fragment shader, which labels each pixel with the joint of largest interpolated weight.
#include "project.glsl"
#include "skin.glsl"
out vec4 v_parts[4];

void main() {
    vec4 parts[4] = vec4[4](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
    for (int k = 0; k < 4; ++k) {
        int j = in_joints[k];
        parts[j / 4][j % 4] += in_weights[k];
    }
    v_parts = parts;
    place_in_tile(skinned_position(0), 0);
}
