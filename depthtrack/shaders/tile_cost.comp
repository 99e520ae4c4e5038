#version 430
// Per-pixel sensor cost of every rendered tile against the observed tile, reduced to the
// tile's mean in the same pass: one work group per candidate tile, one float written back.
// The numpy twin of this file is depthtrack/likelihood.py (pixel_costs, smoothed_costs,
// tile_costs); the rules for missing readings and background are documented there.
//
// Compile-time constants (prepended as #define lines): TILE (tile side, pixels),
// SMOOTHED (0 = pixel-wise cost, 1 = min over the 3x3 neighbourhood plus penalty),
// GROUP (invocations per work group, a power of two), RUN (pixels of a row handled by one
// invocation, so that neighbouring windows share their texel fetches; divides TILE), and
// the sensor model from likelihood.SENSOR_MODEL (likelihood.shader_constants): the codes
// NO_READING_CODE and BACKGROUND_CODE of the observation texture, DEPTH_SCALE (|observed -
// rendered| at which the cost saturates, m), SILHOUETTE_COST (model drawn where the
// observation is background), NO_READING_COST (observed pixel without a reading, any
// rendering), NEIGHBOR_PENALTY (explaining a pixel by one of its 8 neighbours).
layout(local_size_x = GROUP) in;

layout(binding = 0) uniform sampler2D u_atlas;     // R32F rendered z, 0 = nothing drawn
layout(binding = 1) uniform sampler2D u_observed;  // RG32F (z | NO_READING_CODE | BACKGROUND_CODE, absent cost)
layout(std430, binding = 1) writeonly buffer Costs { float costs[]; };

uniform int u_first;     // candidate index of tile 0 in this pass
uniform int u_grid;      // tiles per atlas side

shared float partial[GROUP];

float pair_cost(vec2 observed, float rendered) {
    if (rendered <= 0.0) return observed.y;           // model absent: precomputed per pixel
    if (observed.x == BACKGROUND_CODE) return SILHOUETTE_COST;   // model over observed background
    return smoothstep(0.0, 1.0, abs(observed.x - rendered) / DEPTH_SCALE);
}

void main() {
    int tile = int(gl_WorkGroupID.x);
    ivec2 origin = ivec2(tile % u_grid, tile / u_grid) * TILE;
    const int runs_per_row = TILE / RUN;
    float sum = 0.0;
    for (int run = int(gl_LocalInvocationID.x); run < TILE * runs_per_row; run += GROUP) {
        int y = run / runs_per_row;
        int x0 = (run % runs_per_row) * RUN;
        vec2 observed[RUN];
        float rendered[RUN + 2];      // row y, columns x0-1 .. x0+RUN (clamped to the tile)
        float c[RUN];
        bool any_above_penalty = false;
        for (int i = 0; i < RUN + 2; ++i) {
            rendered[i] = texelFetch(u_atlas, origin + ivec2(clamp(x0 + i - 1, 0, TILE - 1), y), 0).r;
        }
        for (int i = 0; i < RUN; ++i) {
            observed[i] = texelFetch(u_observed, ivec2(x0 + i, y), 0).xy;
            c[i] = observed[i].x == NO_READING_CODE ? NO_READING_COST : pair_cost(observed[i], rendered[i + 1]);
#if SMOOTHED
            any_above_penalty = any_above_penalty || (observed[i].x != NO_READING_CODE && c[i] > NEIGHBOR_PENALTY);
#endif
        }
#if SMOOTHED
        // A neighbour can only win where a pixel's own cost exceeds the penalty; then look at
        // the rows above and below too. Coordinates are clamped to the tile, which leaves the
        // minimum unchanged: a clamped neighbour is the pixel itself (its cost plus the
        // penalty never wins) or another of its true neighbours.
        if (any_above_penalty) {
            float above[RUN + 2];
            float below[RUN + 2];
            int ya = max(y - 1, 0);
            int yb = min(y + 1, TILE - 1);
            for (int i = 0; i < RUN + 2; ++i) {
                int x = clamp(x0 + i - 1, 0, TILE - 1);
                above[i] = texelFetch(u_atlas, origin + ivec2(x, ya), 0).r;
                below[i] = texelFetch(u_atlas, origin + ivec2(x, yb), 0).r;
            }
            for (int i = 0; i < RUN; ++i) {
                if (observed[i].x == NO_READING_CODE || c[i] <= NEIGHBOR_PENALTY) continue;
                vec2 o = observed[i];
                // pair_cost rises with |observed - rendered| where the model is drawn, so the
                // neighbours' minimum is one smoothstep of the nearest drawn depth
                float nb[8] = float[8](above[i], above[i + 1], above[i + 2], rendered[i],
                                       rendered[i + 2], below[i], below[i + 1], below[i + 2]);
                float nearest = 3.0e38;
                bool absent = false;
                for (int k = 0; k < 8; ++k) {
                    if (nb[k] <= 0.0) absent = true;
                    else nearest = min(nearest, abs(o.x - nb[k]));
                }
                float n = absent ? o.y : 3.0e38;
                if (nearest < 3.0e38) {
                    n = min(n, o.x == BACKGROUND_CODE ? SILHOUETTE_COST
                                                      : smoothstep(0.0, 1.0, nearest / DEPTH_SCALE));
                }
                c[i] = min(c[i], n + NEIGHBOR_PENALTY);
            }
        }
#endif
        for (int i = 0; i < RUN; ++i) {
            sum += c[i];
        }
    }
    partial[gl_LocalInvocationID.x] = sum;
    barrier();
    for (int stride = GROUP / 2; stride > 0; stride /= 2) {
        if (int(gl_LocalInvocationID.x) < stride) {
            partial[gl_LocalInvocationID.x] += partial[gl_LocalInvocationID.x + stride];
        }
        barrier();
    }
    if (gl_LocalInvocationID.x == 0u) {
        costs[u_first + tile] = partial[0] / float(TILE * TILE);
    }
}
