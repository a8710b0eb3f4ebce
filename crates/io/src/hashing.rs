//! A fast hash map key and hasher for welding vertices (STL) and de-duplicating
//! OBJ `v/vt/vn` triples.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};

/// Multiply-rotate hasher (FxHash) with a final avalanche step, for small
/// integer keys from trusted-shape data.
#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher {
    hash: u64,
}

impl FxHasher {
    #[inline]
    fn add(&mut self, word: u64) {
        self.hash = (self.hash.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            let mut w = [0u8; 8];
            w.copy_from_slice(c);
            self.add(u64::from_le_bytes(w));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut w = [0u8; 8];
            w[..rest.len()].copy_from_slice(rest);
            self.add(u64::from_le_bytes(w));
        }
    }

    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.add(i as u64);
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }

    #[inline]
    fn finish(&self) -> u64 {
        // murmur3 fmix64, so that all bits of the key reach the top bits.
        let mut h = self.hash;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }
}

/// Three 32-bit words as a hash key (vertex bit patterns or index triples).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) struct Key3(pub [u32; 3]);

impl Hash for Key3 {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.0[0] as u64 | ((self.0[1] as u64) << 32));
        state.write_u32(self.0[2]);
    }
}

/// A hash map from [`Key3`] to a vertex index.
pub(crate) type Key3Map = HashMap<Key3, u32, BuildHasherDefault<FxHasher>>;

/// An empty map with room for `n` keys.
pub(crate) fn key3_map(n: usize) -> Key3Map {
    HashMap::with_capacity_and_hasher(n, Default::default())
}

/// Welds identical positions into one vertex: bit-identical coordinates (with
/// -0 treated as +0) map to the same index.
pub(crate) struct Welder {
    map: Key3Map,
    /// The distinct positions, in order of first appearance.
    pub positions: Vec<raykit_core::Vec3>,
}

impl Welder {
    /// A welder expecting about `n` distinct vertices.
    pub(crate) fn with_capacity(n: usize) -> Self {
        Welder {
            map: key3_map(n),
            positions: Vec::with_capacity(n),
        }
    }

    /// The index of `p`, adding it if new. Fails (None) past u32 indices.
    #[inline]
    pub(crate) fn insert(&mut self, p: raykit_core::Vec3) -> Option<u32> {
        let key = Key3([
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ]);
        let next = u32::try_from(self.positions.len()).ok()?;
        let idx = *self.map.entry(key).or_insert(next);
        if idx == next {
            self.positions.push(p);
        }
        Some(idx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::Vec3;

    #[test]
    fn welder_merges_identical_and_signed_zero() {
        let mut w = Welder::with_capacity(4);
        assert_eq!(w.insert(Vec3::new(1.0, 2.0, 3.0)), Some(0));
        assert_eq!(w.insert(Vec3::new(0.0, 2.0, 3.0)), Some(1));
        assert_eq!(w.insert(Vec3::new(-0.0, 2.0, 3.0)), Some(1));
        assert_eq!(w.insert(Vec3::new(1.0, 2.0, 3.0)), Some(0));
        assert_eq!(w.insert(Vec3::new(1.0, 2.0, 3.0000002)), Some(2));
        assert_eq!(w.positions.len(), 3);
    }

    #[test]
    fn many_keys_spread() {
        let mut m = key3_map(0);
        for i in 0..10_000u32 {
            m.insert(Key3([i, i * 7, 3]), i);
        }
        assert_eq!(m.len(), 10_000);
        assert_eq!(m.get(&Key3([5, 35, 3])), Some(&5));
    }
}
