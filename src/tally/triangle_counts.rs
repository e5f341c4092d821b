//! The triangle maps' photon counts per slot: u32 until a count would pass u32::MAX,
//! u64 from then on, exact either way, and saved as u64 whichever width they are held in.

use super::CODES_PER_TRIANGLE;

/// Photon counts per triangle slot, held as u32 (half the memory of the triangle maps,
/// which dominate it in large scenes) until one count would pass u32::MAX, then as u64
/// from that moment on: exact either way.
#[derive(Clone, Debug, PartialEq)]
pub enum TriangleCounts {
    Narrow(Vec<u32>),
    Wide(Vec<u64>),
}

impl Default for TriangleCounts {
    fn default() -> Self {
        TriangleCounts::Narrow(Vec::new())
    }
}

impl TriangleCounts {
    /// `n` zero counts (the zeroed pages are only touched where photons land).
    pub fn zeros(n: usize) -> TriangleCounts {
        TriangleCounts::Narrow(vec![0; n])
    }

    pub fn len(&self) -> usize {
        match self {
            TriangleCounts::Narrow(v) => v.len(),
            TriangleCounts::Wide(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Count `i`.
    #[inline]
    pub fn get(&self, i: usize) -> u64 {
        match self {
            TriangleCounts::Narrow(v) => v[i] as u64,
            TriangleCounts::Wide(v) => v[i],
        }
    }

    /// Adds one to count `i`.
    #[inline]
    pub fn increment(&mut self, i: usize) {
        self.add_at(i, 1);
    }

    /// Adds one to count `code` for each of `codes` ([`Self::increment`] for each, the
    /// same counts), with the width matched once rather than per code: a chunk's
    /// deposits, folded into the run's tallies (0.5 ns per ray of the office's photon
    /// pass).
    pub fn increment_each(&mut self, mut codes: &[u32]) {
        if let TriangleCounts::Narrow(v) = self {
            let mut done = codes.len();
            for (k, &code) in codes.iter().enumerate() {
                let c = &mut v[code as usize];
                if *c == u32::MAX {
                    done = k;
                    break;
                }
                *c += 1;
            }
            if done == codes.len() {
                return;
            }
            self.widen();
            codes = &codes[done..];
        }
        if let TriangleCounts::Wide(v) = self {
            for &code in codes {
                v[code as usize] += 1;
            }
        }
    }

    /// Adds `n` to count `i`, widening every count first if it would not fit in u32.
    #[inline]
    pub fn add_at(&mut self, i: usize, n: u64) {
        if let TriangleCounts::Narrow(v) = self {
            match u32::try_from(v[i] as u64 + n) {
                Ok(sum) => {
                    v[i] = sum;
                    return;
                }
                Err(_) => self.widen(),
            }
        }
        if let TriangleCounts::Wide(v) = self {
            v[i] += n;
        }
    }

    /// Switches to u64 counts.
    #[cold]
    fn widen(&mut self) {
        if let TriangleCounts::Narrow(v) = self {
            *self = TriangleCounts::Wide(v.iter().map(|&c| c as u64).collect());
        }
    }

    /// Adds `other` count by count (integers: any order gives the same sums), widening
    /// at the first sum past u32.
    pub fn add(&mut self, other: &TriangleCounts) {
        use TriangleCounts::{Narrow, Wide};
        let done = match (&mut *self, other) {
            (Narrow(a), Narrow(b)) => add_narrow(a, b),
            (Narrow(a), Wide(b)) => add_narrow(a, b),
            (Wide(_), _) => 0,
        };
        if done == self.len().min(other.len()) {
            return;
        }
        self.widen();
        let Wide(a) = self else {
            unreachable!("widened above")
        };
        match other {
            Narrow(b) => add_wide(&mut a[done..], &b[done..]),
            Wide(b) => add_wide(&mut a[done..], &b[done..]),
        }
    }

    /// Triangle `k`'s [`CODES_PER_TRIANGLE`] counts.
    #[inline]
    pub fn slots(&self, k: usize) -> [u64; CODES_PER_TRIANGLE] {
        let range = k * CODES_PER_TRIANGLE..(k + 1) * CODES_PER_TRIANGLE;
        match self {
            TriangleCounts::Narrow(v) => {
                let s = &v[range];
                std::array::from_fn(|i| s[i] as u64)
            }
            TriangleCounts::Wide(v) => {
                let s = &v[range];
                std::array::from_fn(|i| s[i])
            }
        }
    }

    /// Every count as u64 (checkpoints).
    pub fn to_vec(&self) -> Vec<u64> {
        (0..self.len()).map(|i| self.get(i)).collect()
    }
}

/// Adds `b` to `a` while the sums fit in u32; returns how many counts were added.
/// Zero counts are skipped: `a`'s zeroed pages stay untouched.
fn add_narrow<T: Copy + Into<u64>>(a: &mut [u32], b: &[T]) -> usize {
    for (i, (x, &y)) in a.iter_mut().zip(b).enumerate() {
        let y = y.into();
        if y > 0 {
            match u32::try_from(*x as u64 + y) {
                Ok(sum) => *x = sum,
                Err(_) => return i,
            }
        }
    }
    a.len().min(b.len())
}

/// Adds `b` to `a`, skipping zeros as [`add_narrow`] does.
fn add_wide<T: Copy + Into<u64>>(a: &mut [u64], b: &[T]) {
    for (x, &y) in a.iter_mut().zip(b) {
        let y = y.into();
        if y > 0 {
            *x += y;
        }
    }
}

/// Saved as the sequence of u64 counts, so the bytes are those of a `Vec<u64>`
/// whichever width the counts are held in.
impl serde::Serialize for TriangleCounts {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq((0..self.len()).map(|i| self.get(i)))
    }
}

impl<'de> serde::Deserialize<'de> for TriangleCounts {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        Vec::<u64>::deserialize(deserializer).map(TriangleCounts::from)
    }
}

impl From<Vec<u64>> for TriangleCounts {
    /// Narrow when every count fits in u32.
    fn from(counts: Vec<u64>) -> Self {
        if counts.iter().all(|&c| c <= u32::MAX as u64) {
            TriangleCounts::Narrow(counts.iter().map(|&c| c as u32).collect())
        } else {
            TriangleCounts::Wide(counts)
        }
    }
}
