// Pinhole projection of camera-frame points (OpenCV: x right, y down, z forward, metres)
// into one square tile of an atlas of u_grid x u_grid tiles.
//
// The tile view has u_view_size pixels and intrinsics u_intrinsics = (fx, fy, cx, cy) in
// that view's pixels, with the centre of pixel (0, 0) at (0, 0). Image row v is written to
// framebuffer row v (no flip), so a read-back in GL's bottom-up order gives rows top-down.
// gl_ClipDistance[0..3] clip every primitive to its own tile: nothing a candidate draws can
// land in a neighbouring tile.
uniform vec4 u_intrinsics;
uniform vec2 u_view_size;
uniform vec2 u_depth_range;   // near, far (metres)
uniform int u_grid;           // tiles per atlas side (1 for a single full view)

out gl_PerVertex {
    vec4 gl_Position;
    float gl_ClipDistance[4];
};

void place_in_tile(vec3 p, int tile_index) {
    // ndc = (u + 0.5) / width * 2 - 1 with u = fx x / z + cx; clip = ndc * z (w = z)
    float x = 2.0 * (u_intrinsics.x * p.x + (u_intrinsics.z + 0.5) * p.z) / u_view_size.x - p.z;
    float y = 2.0 * (u_intrinsics.y * p.y + (u_intrinsics.w + 0.5) * p.z) / u_view_size.y - p.z;
    float n = u_depth_range.x;
    float f = u_depth_range.y;
    float zc = (f + n) / (f - n) * p.z - 2.0 * f * n / (f - n);
    gl_ClipDistance[0] = p.z + x;
    gl_ClipDistance[1] = p.z - x;
    gl_ClipDistance[2] = p.z + y;
    gl_ClipDistance[3] = p.z - y;
    float col = float(tile_index % u_grid);
    float row = float(tile_index / u_grid);
    float g = float(u_grid);
    gl_Position = vec4((x + p.z * (2.0 * col + 1.0 - g)) / g,
                       (y + p.z * (2.0 * row + 1.0 - g)) / g,
                       zc, p.z);
}
