// The traversal counts switched off: the structures note each node and
// triangle record they fetch, and these notes compile to nothing (the
// counting kernels use count_on.wgsl instead).

fn note_node(bytes: u32) {}

fn note_tri(bytes: u32) {}

fn note_bytes(bytes: u32) {}

fn flush_counts() {}
