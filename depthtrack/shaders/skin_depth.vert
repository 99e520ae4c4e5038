#version 430
// Candidate poses drawn instanced: gl_InstanceID picks the candidate and its tile.
#include "project.glsl"
#include "skin.glsl"
uniform int u_first;   // candidate index of instance 0 in this pass
out float v_z;

void main() {
    vec3 p = skinned_position(u_first + gl_InstanceID);
    v_z = p.z;
    place_in_tile(p, gl_InstanceID);
}
