//! A checkpoint file's layout: `LUXCKPT1`, format version (u32 LE), payload length
//! (u64 LE), CRC-32 of the payload (u32 LE), then the payload (postcard), with the cells
//! packed ([`pack_cells`]) and the history as plain tuples.

use super::Checkpoint;
use crate::stats::forecast::HistoryPoint;
use crate::stats::verdict::CheckCounts;
use crate::tally::{CellSums, Moments, Tallies};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::io::{Seek, SeekFrom, Write};

const MAGIC: &[u8; 8] = b"LUXCKPT1";
/// Bumped whenever the payload's layout changes, the numbers a run draws for the same
/// seed (photon streams, the direct light's sampling), or the scene fingerprint: older
/// files are refused in words, so a run never continues or merges another version's
/// numbers. 2: photon streams seeded by `rng::PhotonStreams`, shadow edges refine the
/// direct light's cells. 3: the bounce cap follows the highest albedo past 100,000 (up
/// to `trace::MAX_BOUNCE_CAP`), which changes the numbers of scenes with an albedo above
/// 0.99972 or lossless materials; the cells hold central moments in a score unit
/// (`tally::Moments`), not power sums. 4: the scene fingerprint is
/// `scene::fingerprint::run`. 5: the cells gain one total slot per receiver
/// (its figures' covariance). 6: a history point carries its checks' counts (`CheckCounts`).
/// 7: the numbers and tallies say whether histories are QMC blocks.
pub const FORMAT_VERSION: u32 = 7;
const HEADER_BYTES: usize = 8 + 4 + 8 + 4;

/// A history point as saved: [`HistoryPoint`]'s fields in order (postcard cannot skip
/// fields, and summary.json's serde attributes skip some).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct SavedPoint(f64, u64, f64, Option<f64>, Option<u64>, Option<CheckCounts>);

impl SavedPoint {
    pub(super) fn saved(p: &HistoryPoint) -> SavedPoint {
        SavedPoint(
            p.elapsed_s,
            p.photons,
            p.rel_error,
            p.forecast_s,
            p.forecast_photons,
            p.checks,
        )
    }

    pub(super) fn point(&self) -> HistoryPoint {
        let SavedPoint(elapsed_s, photons, rel_error, forecast_s, forecast_photons, checks) = *self;
        HistoryPoint {
            elapsed_s,
            photons,
            rel_error,
            forecast_s,
            forecast_photons,
            checks,
        }
    }
}

/// [`Tallies`] as saved: the cells packed by [`pack_cells`]. The triangle
/// maps are borrowed from the run where the save is awaited (the last one), copied where
/// another thread writes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct SavedTallies<'a> {
    pub(super) photons: u64,
    pub(super) rays: u64,
    pub(super) killed_by_bounce_cap: u64,
    pub(super) history_hits: [u128; 4],
    pub(super) triangle_hits: Cow<'a, crate::tally::TriangleCounts>,
    /// The cells, packed by [`pack_cells`].
    pub(super) cells: Bytes,
    pub(super) direct_replicates: u64,
    pub(super) direct_rays: u64,
    pub(super) dark: bool,
    pub(super) score_unit: f64,
    pub(super) photons_per_history: u64,
}

impl<'a> SavedTallies<'a> {
    /// `t` as saved, with `maps` its triangle maps (borrowed or copied) and `cells` its
    /// cells packed (or empty, to be packed on another thread).
    pub(super) fn of(
        t: &Tallies,
        maps: Cow<'a, crate::tally::TriangleCounts>,
        cells: Bytes,
    ) -> SavedTallies<'a> {
        SavedTallies {
            photons: t.photons,
            rays: t.rays,
            killed_by_bounce_cap: t.killed_by_bounce_cap,
            history_hits: t.history_hits,
            triangle_hits: maps,
            cells,
            direct_replicates: t.direct_replicates,
            direct_rays: t.direct_rays,
            dark: t.dark,
            score_unit: t.score_unit,
            photons_per_history: t.photons_per_history,
        }
    }

    /// The tallies saved; `None` if the cells do not read back.
    pub(super) fn into_tallies(self) -> Option<Tallies> {
        Some(Tallies {
            photons: self.photons,
            rays: self.rays,
            killed_by_bounce_cap: self.killed_by_bounce_cap,
            history_hits: self.history_hits,
            triangle_hits: self.triangle_hits.into_owned(),
            cells: unpack_cells(&self.cells.0)?,
            direct_replicates: self.direct_replicates,
            direct_rays: self.direct_rays,
            dark: self.dark,
            score_unit: self.score_unit,
            photons_per_history: self.photons_per_history,
        })
    }
}

/// Cells as bytes, fast to write and small where cells are empty: per cell the hits,
/// the scoring histories and the two moment counts (LEB128), a u8 mask of which of the
/// 8 words (mean, M₂, M₃, M₄ of the photons, then of the direct light) are not +0.0,
/// and those words' bits (LE).
pub(super) fn pack_cells(cells: &[CellSums]) -> Vec<u8> {
    let mut out = Vec::with_capacity(cells.len() * 4);
    for c in cells {
        for mut h in [c.hits, c.scoring_histories, c.photons.n, c.direct.n] {
            while h >= 0x80 {
                out.push((h as u8) | 0x80);
                h >>= 7;
            }
            out.push(h as u8);
        }
        let words = [&c.photons, &c.direct]
            .map(|m| [m.mean, m.m2, m.m3, m.m4].map(f64::to_bits))
            .concat();
        let mask = words
            .iter()
            .enumerate()
            .fold(0u8, |m, (k, &w)| m | (((w != 0) as u8) << k));
        out.push(mask);
        for w in words.iter().filter(|&&w| w != 0) {
            out.extend_from_slice(&w.to_le_bytes());
        }
    }
    out
}

/// [`pack_cells`] read back; `None` if the bytes end early or run on.
fn unpack_cells(bytes: &[u8]) -> Option<Vec<CellSums>> {
    let mut cells = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let mut counts = [0u64; 4];
        for count in &mut counts {
            let mut shift = 0;
            loop {
                let b = *bytes.get(at)?;
                at += 1;
                *count |= ((b & 0x7f) as u64).checked_shl(shift)?;
                if b < 0x80 {
                    break;
                }
                shift += 7;
            }
        }
        let mask = *bytes.get(at)?;
        at += 1;
        let mut words = [0f64; 8];
        for (k, w) in words.iter_mut().enumerate() {
            if mask & (1 << k) != 0 {
                *w = f64::from_bits(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?));
                at += 8;
            }
        }
        let moments = |n: u64, w: &[f64]| Moments {
            n,
            mean: w[0],
            m2: w[1],
            m3: w[2],
            m4: w[3],
        };
        let [hits, scoring_histories, n_photons, n_direct] = counts;
        cells.push(CellSums {
            photons: moments(n_photons, &words[..4]),
            hits,
            scoring_histories,
            direct: moments(n_direct, &words[4..]),
        });
    }
    Some(cells)
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct Bytes(pub(super) Vec<u8>);

impl Serialize for Bytes {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_bytes(&self.0)
    }
}

impl<'de> Deserialize<'de> for Bytes {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Bytes, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Bytes;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("bytes")
            }
            fn visit_bytes<E>(self, v: &[u8]) -> std::result::Result<Bytes, E> {
                Ok(Bytes(v.to_vec()))
            }
            fn visit_byte_buf<E>(self, v: Vec<u8>) -> std::result::Result<Bytes, E> {
                Ok(Bytes(v))
            }
        }
        d.deserialize_byte_buf(V)
    }
}

/// Passes bytes on to `out`, counting them and their CRC-32; keeps the first I/O error
/// (postcard reports its own).
struct CrcWriter<W> {
    out: W,
    crc: crc32fast::Hasher,
    bytes: u64,
    error: Option<std::io::Error>,
}

impl<W: Write> Write for CrcWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self.out.write(buf) {
            Ok(n) => {
                self.crc.update(&buf[..n]);
                self.bytes += n as u64;
                Ok(n)
            }
            Err(e) => {
                let kind = e.kind();
                if kind != std::io::ErrorKind::Interrupted {
                    self.error.get_or_insert(e);
                }
                Err(kind.into())
            }
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

impl Checkpoint<'_> {
    /// The file's bytes, in memory.
    pub fn encode(&self) -> Result<Vec<u8>> {
        let mut out = std::io::Cursor::new(Vec::new());
        self.write_to(&mut out)
            .map_err(|e| Error::Unsupported(format!("checkpoint: {e}")))?;
        Ok(out.into_inner())
    }

    /// Writes the file to `out` from its start: the header, the payload streamed out
    /// (no copy of the maps' bytes in memory), then the payload's length and CRC in the
    /// header. Returns the bytes written.
    pub(super) fn write_to(&self, out: &mut (impl Write + Seek)) -> std::io::Result<u64> {
        let mut header = [0u8; HEADER_BYTES];
        header[..8].copy_from_slice(MAGIC);
        header[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.write_all(&header)?;
        let mut payload = CrcWriter {
            out: &mut *out,
            crc: crc32fast::Hasher::new(),
            bytes: 0,
            error: None,
        };
        // Buffered before the CRC: postcard writes a few bytes at a time.
        let mut buffered = std::io::BufWriter::with_capacity(1 << 20, &mut payload);
        let written = postcard::to_io(self, &mut buffered).map(|_| ());
        let flushed = match written {
            Ok(()) => buffered
                .into_inner()
                .map(|_| ())
                .map_err(|e| e.into_error()),
            Err(e) => {
                drop(buffered.into_parts());
                Err(std::io::Error::other(e))
            }
        };
        if let Err(e) = flushed {
            return Err(payload.error.take().unwrap_or(e));
        }
        let (bytes, crc) = (payload.bytes, payload.crc.finalize());
        out.seek(SeekFrom::Start(12))?;
        out.write_all(&bytes.to_le_bytes())?;
        out.write_all(&crc.to_le_bytes())?;
        out.seek(SeekFrom::End(0))?;
        Ok(HEADER_BYTES as u64 + bytes)
    }

    /// Reads a checkpoint; `origin` names it in errors.
    pub fn decode(bytes: &[u8], origin: &str) -> Result<Checkpoint<'static>> {
        let bad = |m: String| Err(Error::input(origin, m));
        if bytes.len() < 8 || &bytes[..8] != MAGIC {
            return bad("not a luxtally checkpoint".into());
        }
        if bytes.len() < HEADER_BYTES {
            return bad(format!("truncated: {} bytes", bytes.len()));
        }
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4"));
        let version = word(8);
        if version != FORMAT_VERSION {
            return bad(format!(
                "checkpoint format {version}; this luxtally reads format {FORMAT_VERSION} \
                 (another layout or other random numbers): start the run anew"
            ));
        }
        let length = u64::from_le_bytes(bytes[12..20].try_into().expect("8"));
        let payload = &bytes[HEADER_BYTES..];
        if payload.len() as u64 != length {
            return bad(format!(
                "truncated or damaged: {} of {} payload bytes",
                payload.len(),
                length
            ));
        }
        if crc32fast::hash(payload) != word(20) {
            return bad("corrupt: checksum mismatch".into());
        }
        postcard::from_bytes(payload).or_else(|e| bad(format!("corrupt: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::Numbers;

    /// Length and CRC-32 of the fixed checkpoint below, encoded by format 7.
    const GOLDEN_LEN: usize = 163;
    const GOLDEN_CRC: u32 = 3_389_627_411;

    #[test]
    fn a_damaged_checkpoint_is_refused_in_one_line() {
        let t = Tallies::new(2, 3, 1.0);
        let counts = CheckCounts {
            pass: 1,
            fail: 2,
            undecided: 3,
        };
        let c = Checkpoint {
            scene_path: "s.toml".into(),
            scene_fingerprint: 7,
            numbers: Numbers {
                seed: 1,
                estimator: None,
                backend: "embree".into(),
                qmc: false,
            },
            photons_goal: Some(10),
            shard: None,
            finished: false,
            tallies: SavedTallies::of(
                &t,
                Cow::Borrowed(&t.triangle_hits),
                Bytes(pack_cells(&t.cells)),
            ),
            direct_per_photon: 0.25,
            history: vec![SavedPoint(0.5, 10, 0.1, None, None, Some(counts))],
            times_s: [1.0; 4],
            chunks: vec![],
        };
        let bytes = c.encode().unwrap();
        assert_eq!(Checkpoint::decode(&bytes, "c").unwrap(), c);
        // Format 7's encoding of this checkpoint: a change here needs FORMAT_VERSION bumped.
        assert_eq!(
            (bytes.len(), crc32fast::hash(&bytes)),
            (GOLDEN_LEN, GOLDEN_CRC),
            "the checkpoint's encoding changed"
        );
        let truncated = Checkpoint::decode(&bytes[..bytes.len() - 3], "c").unwrap_err();
        assert!(truncated.to_string().contains("truncated"), "{truncated}");
        let mut flipped = bytes.clone();
        *flipped.last_mut().unwrap() ^= 1;
        let corrupt = Checkpoint::decode(&flipped, "c").unwrap_err();
        assert!(corrupt.to_string().contains("checksum"), "{corrupt}");
        let mut old = bytes.clone();
        old[8] = 9;
        assert!(Checkpoint::decode(&old, "c")
            .unwrap_err()
            .to_string()
            .contains("format 9"));
        assert!(Checkpoint::decode(b"hello", "c").is_err());
    }
}
