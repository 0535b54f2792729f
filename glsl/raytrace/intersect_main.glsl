// The body of every intersection kernel: one invocation per query, INTERSECT(q) defined
// by the scheme's kernel before this include.
layout(local_size_x = 64) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= ray_count || (queries[i].flags & RAY_HIT_KNOWN) != 0u) return;
    hits[i] = INTERSECT(queries[i]);
}
