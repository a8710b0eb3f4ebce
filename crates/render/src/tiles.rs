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
    /// The whole `width` × `height` frame.
    pub fn whole(width: u32, height: u32) -> Tile {
        Tile {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// Band `index` of `count` horizontal bands of a `width` × `height`
    /// frame: rows `index·height/count` up to `(index+1)·height/count`
    /// (rounded down), so the bands cover the frame without overlap and
    /// differ in height by at most one row. `None` when `index ≥ count`.
    pub fn band(index: u32, count: u32, width: u32, height: u32) -> Option<Tile> {
        if index >= count {
            return None;
        }
        let row = |i: u32| (i as u64 * height as u64 / count as u64) as u32;
        let (y0, y1) = (row(index), row(index + 1));
        Some(Tile {
            x: 0,
            y: y0,
            width,
            height: y1 - y0,
        })
    }

    /// This rectangle clipped to a `width` × `height` frame (possibly empty).
    pub fn clipped(&self, width: u32, height: u32) -> Tile {
        let x = self.x.min(width);
        let y = self.y.min(height);
        Tile {
            x,
            y,
            width: self.width.min(width - x),
            height: self.height.min(height - y),
        }
    }

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

    #[test]
    fn bands_cover_every_row_once() {
        for (h, n) in [(1, 1), (7, 3), (600, 4), (5, 8), (480, 7)] {
            let mut seen = vec![0u8; h as usize];
            for i in 0..n {
                let b = Tile::band(i, n, 3, h).unwrap();
                assert_eq!((b.x, b.width), (0, 3));
                assert!(b.height >= h / n && b.height <= h.div_ceil(n), "{h} {n}");
                for y in b.y..b.y + b.height {
                    seen[y as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "{h} rows in {n} bands");
            assert_eq!(Tile::band(n, n, 3, h), None);
        }
    }

    #[test]
    fn clipping_keeps_the_rectangle_inside_the_frame() {
        let t = Tile {
            x: 30,
            y: 5,
            width: 20,
            height: 100,
        };
        assert_eq!(
            t.clipped(40, 50),
            Tile {
                x: 30,
                y: 5,
                width: 10,
                height: 45
            }
        );
        assert_eq!(t.clipped(10, 10).pixels(), 0);
        assert_eq!(Tile::whole(4, 3).clipped(4, 3), Tile::whole(4, 3));
    }
}
