// Linear-blend skinning from per-candidate bone matrices kept in an RGBA32F texture:
// row `candidate`, texels 4*joint .. 4*joint+3 hold the rows of
// body.skin_matrices(poses)[candidate, joint] (row-major numpy). The matrices are affine,
// so only the first three rows are read. (A float texture, not a storage buffer: llvmpipe
// fetches texels several times faster than it reads SSBOs in vertex shaders.)
layout(binding = 3) uniform sampler2D u_bones;

in vec3 in_position;
in ivec4 in_joints;
in vec4 in_weights;

vec4 bone_transform(vec4 p, int candidate, int joint) {
    int x = 4 * joint;
    return vec4(dot(texelFetch(u_bones, ivec2(x, candidate), 0), p),
                dot(texelFetch(u_bones, ivec2(x + 1, candidate), 0), p),
                dot(texelFetch(u_bones, ivec2(x + 2, candidate), 0), p), 1.0);
}

vec3 skinned_position(int candidate) {
    vec4 rest = vec4(in_position, 1.0);
    vec4 p = in_weights.x * bone_transform(rest, candidate, in_joints.x)
           + in_weights.y * bone_transform(rest, candidate, in_joints.y);
    // most vertices have at most two influences: skip the fetches of zero weights
    if (in_weights.z != 0.0) p += in_weights.z * bone_transform(rest, candidate, in_joints.z);
    if (in_weights.w != 0.0) p += in_weights.w * bone_transform(rest, candidate, in_joints.w);
    return p.xyz;
}
