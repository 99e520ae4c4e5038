#version 430
// A static triangle mesh given in the camera frame (floor, wall) in a single full view.
#include "project.glsl"
in vec3 in_position;
out float v_z;

void main() {
    v_z = in_position.z;
    place_in_tile(in_position, 0);
}
