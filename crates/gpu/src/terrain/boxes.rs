//! per-frame quadtree boxes for the GPU: the CPU's one quadtree
//! traversal per frame (`raykit_terrain::boxes::select_boxes`) flattened
//! into box records and per-row lists for `shaders/terrain_boxes.wgsl`.

use raykit_terrain::boxes::NodeBox;

/// Box records (8 floats: lo, first pixel column, hi, end column; grid
/// units) as words.
pub fn box_words(boxes: &[NodeBox]) -> Vec<u32> {
    let mut words = Vec::with_capacity(boxes.len() * 8);
    for b in boxes {
        words.extend(
            [
                b.lo[0] as f32,
                b.lo[1] as f32,
                b.lo[2] as f32,
                b.rect[0] as f32,
                b.hi[0] as f32,
                b.hi[1] as f32,
                b.hi[2] as f32,
                b.rect[2] as f32,
            ]
            .map(f32::to_bits),
        );
    }
    words
}

/// For each of the image's `height` rows the boxes whose pixel rectangle
/// covers it: `height + 1` offsets into the same array, then the box
/// indices, row after row.
pub fn row_lists(boxes: &[NodeBox], height: u32) -> Vec<u32> {
    let h = height as usize;
    let mut counts = vec![0u32; h];
    for b in boxes {
        for c in &mut counts[(b.rect[1] as usize).min(h)..(b.rect[3] as usize).min(h)] {
            *c += 1;
        }
    }
    let mut out = Vec::with_capacity(h + 1 + counts.iter().sum::<u32>() as usize);
    let mut at = (h + 1) as u32;
    for c in &counts {
        out.push(at);
        at += c;
    }
    out.push(at);
    let mut next: Vec<u32> = out[..h].to_vec();
    out.resize(at as usize, 0);
    for (k, b) in boxes.iter().enumerate() {
        for row in (b.rect[1] as usize).min(h)..(b.rect[3] as usize).min(h) {
            out[next[row] as usize] = k as u32;
            next[row] += 1;
        }
    }
    out
}
