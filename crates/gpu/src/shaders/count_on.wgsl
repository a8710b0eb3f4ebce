// The traversal counts of the counting kernels: per ray, the nodes
// visited, the triangle records tested and the bytes fetched from nodes,
// index lists and triangle records, summed into 64-bit counters (group 2:
// nodes, triangles, bytes, each as low and high word) once per ray.

@group(2) @binding(0) var<storage, read_write> counters: array<atomic<u32>, 6>;

var<private> seen_nodes: u32;
var<private> seen_tris: u32;
var<private> seen_bytes: u32;

fn note_node(bytes: u32) {
    seen_nodes += 1u;
    seen_bytes += bytes;
}

fn note_tri(bytes: u32) {
    seen_tris += 1u;
    seen_bytes += bytes;
}

fn note_bytes(bytes: u32) {
    seen_bytes += bytes;
}

// Add x to the 64-bit counter at words (i, i + 1), carrying by hand.
fn add64(i: u32, x: u32) {
    let old = atomicAdd(&counters[i], x);
    if old + x < old {
        atomicAdd(&counters[i + 1u], 1u);
    }
}

fn flush_counts() {
    add64(0u, seen_nodes);
    add64(2u, seen_tris);
    add64(4u, seen_bytes);
}
