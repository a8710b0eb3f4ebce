//! Splitting the image into square tiles, the unit of parallel work.

use rayon::prelude::*;

/// Side of a tile in pixels.
pub const TILE_SIZE: u32 = 32;

/// A rectangle of pixels: top-left corner and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width (`TILE_SIZE` except at the right edge).
    pub width: u32,
    /// Height (`TILE_SIZE` except at the bottom edge).
    pub height: u32,
}

impl Tile {
    /// Number of pixels.
    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// The pixels `(x, y)` of the tile, row by row.
    pub fn coords(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (self.y..self.y + self.height)
            .flat_map(move |y| (self.x..self.x + self.width).map(move |x| (x, y)))
    }
}

/// Evaluate `pixel(x, y)` for every pixel of a `width` × `height` image,
/// tile by tile ([`TILE_SIZE`]²) in parallel on the rayon pool, calling
/// `progress` with each finished tile's pixel count; returns the values
/// row-major. The result does not depend on the number of threads.
pub fn map_pixels<T: Send + Clone + Default>(
    width: u32,
    height: u32,
    pixel: &(dyn Fn(u32, u32) -> T + Sync),
    progress: &(dyn Fn(u64) + Sync),
) -> Vec<T> {
    let tiles = tiles(width, height, TILE_SIZE);
    let rendered: Vec<Vec<T>> = tiles
        .par_iter()
        .map(|tile| {
            let out: Vec<T> = tile.coords().map(|(x, y)| pixel(x, y)).collect();
            progress(tile.pixels());
            out
        })
        .collect();
    let mut image = vec![T::default(); width as usize * height as usize];
    for (tile, values) in tiles.iter().zip(rendered) {
        for ((x, y), v) in tile.coords().zip(values) {
            image[y as usize * width as usize + x as usize] = v;
        }
    }
    image
}

/// The tiles covering a `width` × `height` image, row by row.
pub fn tiles(width: u32, height: u32, size: u32) -> Vec<Tile> {
    let size = size.max(1);
    (0..height.div_ceil(size))
        .flat_map(|ty| {
            (0..width.div_ceil(size)).map(move |tx| {
                let (x, y) = (tx * size, ty * size);
                Tile {
                    x,
                    y,
                    width: size.min(width - x),
                    height: size.min(height - y),
                }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_every_pixel_once() {
        for (w, h) in [(1, 1), (32, 32), (33, 31), (100, 7), (0, 5)] {
            let mut seen = vec![0u8; (w * h) as usize];
            let ts = tiles(w, h, TILE_SIZE);
            for t in &ts {
                assert!(t.width <= TILE_SIZE && t.height <= TILE_SIZE);
                for (x, y) in t.coords() {
                    seen[(y * w + x) as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{w}x{h}");
            assert_eq!(ts.iter().map(Tile::pixels).sum::<u64>(), (w * h) as u64);
        }
    }
}
