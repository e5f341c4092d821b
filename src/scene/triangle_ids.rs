//! A small integer per triangle (material, object) stored in as few bytes as exact
//! storage allows: runs where the values come in long runs (the triangles of one object
//! are contiguous), else one u8, u16 or u32 per triangle. At 10⁷ triangles the two
//! arrays took 8 B per triangle as `Vec<u32>`; they are why a flattened triangle fits in
//! the 120 B with the fast BVH.

/// One u32 per triangle, stored compactly (see the module doc); read with
/// [`TriangleIds::get`], which every representation answers exactly.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TriangleIds {
    len: usize,
    repr: Repr,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Repr {
    /// `value[r]` from triangle `start[r]` up to the next start; `start[0] == 0`.
    Runs {
        start: Vec<u32>,
        value: Vec<u32>,
    },
    U8(Vec<u8>),
    U16(Vec<u16>),
    U32(Vec<u32>),
}

impl Default for TriangleIds {
    fn default() -> Self {
        TriangleIds {
            len: 0,
            repr: Repr::U8(Vec::new()),
        }
    }
}

impl TriangleIds {
    /// `ids`, in whichever representation takes fewest bytes (per triangle on a tie:
    /// one load to read). Triangle indices are u32 everywhere, so runs start in u32.
    pub fn new(ids: &[u32]) -> TriangleIds {
        let len = ids.len();
        let max = ids.iter().copied().max().unwrap_or(0);
        let width = match max {
            0..=0xff => 1,
            0x100..=0xffff => 2,
            _ => 4,
        };
        let runs = 1 + ids.windows(2).filter(|w| w[0] != w[1]).count();
        let repr = if len > 0 && runs * 8 < len * width {
            let mut start = Vec::with_capacity(runs);
            let mut value = Vec::with_capacity(runs);
            for (k, &id) in ids.iter().enumerate() {
                if value.last() != Some(&id) {
                    start.push(k as u32);
                    value.push(id);
                }
            }
            Repr::Runs { start, value }
        } else {
            match width {
                1 => Repr::U8(ids.iter().map(|&x| x as u8).collect()),
                2 => Repr::U16(ids.iter().map(|&x| x as u16).collect()),
                _ => Repr::U32(ids.to_vec()),
            }
        };
        TriangleIds { len, repr }
    }

    /// `id` for each of `len` triangles.
    pub fn constant(id: u32, len: usize) -> TriangleIds {
        if len == 0 {
            return TriangleIds::default();
        }
        TriangleIds {
            len,
            repr: Repr::Runs {
                start: vec![0],
                value: vec![id],
            },
        }
    }

    /// The id of triangle `k` (`k < len()`).
    #[inline(always)]
    pub fn get(&self, k: usize) -> u32 {
        match &self.repr {
            Repr::U8(v) => v[k] as u32,
            Repr::U16(v) => v[k] as u32,
            Repr::U32(v) => v[k],
            Repr::Runs { start, value } => {
                debug_assert!(k < self.len);
                value[start.partition_point(|&s| s as usize <= k) - 1]
            }
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The ids in triangle order.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.len).map(|k| self.get(k))
    }

    /// Bytes held (for the memory figures).
    pub fn heap_bytes(&self) -> usize {
        match &self.repr {
            Repr::U8(v) => v.capacity(),
            Repr::U16(v) => 2 * v.capacity(),
            Repr::U32(v) => 4 * v.capacity(),
            Repr::Runs { start, value } => 4 * (start.capacity() + value.capacity()),
        }
    }
}

impl From<Vec<u32>> for TriangleIds {
    fn from(ids: Vec<u32>) -> Self {
        TriangleIds::new(&ids)
    }
}

impl FromIterator<u32> for TriangleIds {
    fn from_iter<I: IntoIterator<Item = u32>>(iter: I) -> Self {
        TriangleIds::new(&iter.into_iter().collect::<Vec<_>>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(ids: &[u32]) -> TriangleIds {
        let t = TriangleIds::new(ids);
        assert_eq!(t.len(), ids.len());
        assert_eq!(t.iter().collect::<Vec<_>>(), ids);
        t
    }

    #[test]
    fn every_representation_reads_back_exactly() {
        assert!(matches!(round_trip(&[]).repr, Repr::U8(_)));
        assert!(matches!(round_trip(&[3, 1, 4, 1, 5]).repr, Repr::U8(_)));
        let wide: Vec<u32> = (0..40).map(|k| (k % 3) * 1000).collect();
        assert!(matches!(round_trip(&wide).repr, Repr::U16(_)));
        let widest: Vec<u32> = (0..40).map(|k| (k % 2) * u32::MAX).collect();
        assert!(matches!(round_trip(&widest).repr, Repr::U32(_)));
        let mut runs = vec![7u32; 100];
        runs.extend([u32::MAX; 50]);
        runs.extend([0; 30]);
        let t = round_trip(&runs);
        assert!(matches!(t.repr, Repr::Runs { .. }));
        assert!(t.heap_bytes() < runs.len());
        assert_eq!(
            TriangleIds::constant(9, 5).iter().collect::<Vec<_>>(),
            [9; 5]
        );
    }
}
