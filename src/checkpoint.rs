//! Checkpoints, resume, shards and their merge (docs/distributed.md).
//!
//! A checkpoint is a run's whole state after an epoch: every tally as raw bits
//! (compensated sums with their compensation terms), the counters, the history, the
//! direct light's schedule, the options that change the numbers and a fingerprint of the
//! scene. Tallies at N photons are chunk partials folded in chunk order, and the direct
//! light is a function of N alone (`run::top_up_direct`), so a run resumed from a
//! checkpoint ends bit-identical to one never stopped.
//!
//! Shards: shard I of N traces a contiguous range of whole chunks and keeps each chunk's
//! receiver partials (compensated sums are not associative bit for bit, so shard totals
//! cannot be added); the merge folds every chunk again in global chunk order, adding the
//! integer counters as totals, and computes the direct light from the total photon
//! count, exactly as one run would.
//!
//! File layout: `LUXCKPT1`, format version (u32 LE), payload length (u64 LE), CRC-32 of
//! the payload (u32 LE), then the payload (postcard).

use crate::accel::RayCaster;
use crate::run::{ChunkRecord, Engine, Resumed, RunOptions, RunResult, RunState, ShardRange};
use crate::scene::Scene;
use crate::stats::forecast::HistoryPoint;
use crate::stats::stop::{StopReason, Target};
use crate::tally::{CellSums, ChunkTally, Moments, Tallies};
use crate::trace::direct::{DirectSchedule, PILOT_REPLICATES};
use crate::trace::CHUNK_PHOTONS;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub mod resume;

/// The checkpoint in an output directory, and the one before it.
pub const FILE: &str = "checkpoint.bin";
pub const PREVIOUS_FILE: &str = "checkpoint.prev";
const MAGIC: &[u8; 8] = b"LUXCKPT1";
/// Bumped whenever the payload's layout changes, or the numbers a run draws for the same
/// seed (photon streams, the direct light's sampling): older files are refused, so a run
/// never continues or merges another version's numbers. 2: photon streams seeded by
/// `rng::PhotonStreams`, shadow edges refine the direct light's cells. 3: the bounce cap
/// follows the highest albedo past the old 100,000 (up to `trace::MAX_BOUNCE_CAP`), which
/// changes the numbers of scenes with an albedo above 0.99972 or lossless materials; the
/// cells hold central moments in a score unit (`tally::Moments`), not power sums.
pub const FORMAT_VERSION: u32 = 3;
const HEADER_BYTES: usize = 8 + 4 + 8 + 4;
/// Seconds between checkpoints unless `--checkpoint-every` says otherwise.
pub const DEFAULT_PERIOD_S: f64 = 60.0;

/// The options that change the numbers: a checkpoint is only continued, or merged,
/// with the same ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Numbers {
    pub seed: u64,
    /// `--estimator`, if any.
    pub estimator: Option<String>,
    /// The backend casts the rays: another one gives other bits.
    pub backend: String,
}

impl Numbers {
    pub fn of(options: &RunOptions) -> Numbers {
        Numbers {
            seed: options.seed,
            estimator: options.estimator.map(|e| format!("{e:?}")),
            backend: options.backend.name().to_string(),
        }
    }

    /// What differs from `other` (the run asked for), in words; `None` if nothing.
    pub fn difference(&self, now: &Numbers) -> Option<String> {
        if self.seed != now.seed {
            return Some(format!(
                "the seed differs (checkpoint {}, now {})",
                self.seed, now.seed
            ));
        }
        if self.estimator != now.estimator {
            let show = |e: &Option<String>| e.clone().unwrap_or_else(|| "none".into());
            return Some(format!(
                "--estimator differs (checkpoint {}, now {})",
                show(&self.estimator),
                show(&now.estimator)
            ));
        }
        if self.backend != now.backend {
            return Some(format!(
                "the backend differs (checkpoint {}, now {})",
                self.backend, now.backend
            ));
        }
        None
    }
}

/// A history point as saved: [`HistoryPoint`]'s fields in order (postcard cannot skip
/// fields, and summary.json's serde attributes skip some).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct SavedPoint(f64, u64, f64, Option<f64>, Option<u64>);

impl SavedPoint {
    fn saved(p: &HistoryPoint) -> SavedPoint {
        SavedPoint(
            p.elapsed_s,
            p.photons,
            p.rel_error,
            p.forecast_s,
            p.forecast_photons,
        )
    }

    fn point(&self) -> HistoryPoint {
        let SavedPoint(elapsed_s, photons, rel_error, forecast_s, forecast_photons) = *self;
        HistoryPoint {
            elapsed_s,
            photons,
            rel_error,
            forecast_s,
            forecast_photons,
        }
    }
}

/// [`Tallies`] as saved: the cells packed by [`pack_cells`]. The triangle
/// maps are borrowed from the run where the save is awaited (the last one), copied where
/// another thread writes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SavedTallies<'a> {
    photons: u64,
    rays: u64,
    killed_by_bounce_cap: u64,
    history_hits: [u128; 4],
    triangle_hits: Cow<'a, crate::tally::TriangleCounts>,
    /// The cells, packed by [`pack_cells`].
    cells: Bytes,
    direct_replicates: u64,
    direct_rays: u64,
    dark: bool,
    score_unit: f64,
}

impl<'a> SavedTallies<'a> {
    /// `t` as saved, with `maps` its triangle maps (borrowed or copied) and `cells` its
    /// cells packed (or empty, to be packed on another thread).
    fn of(
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
        }
    }

    fn tallies(&self) -> Option<Tallies> {
        Some(Tallies {
            photons: self.photons,
            rays: self.rays,
            killed_by_bounce_cap: self.killed_by_bounce_cap,
            history_hits: self.history_hits,
            triangle_hits: self.triangle_hits.clone().into_owned(),
            cells: unpack_cells(&self.cells.0)?,
            direct_replicates: self.direct_replicates,
            direct_rays: self.direct_rays,
            dark: self.dark,
            score_unit: self.score_unit,
        })
    }
}

/// Cells as bytes, fast to write and small where cells are empty: per cell the hits,
/// the scoring histories and the two moment counts (LEB128), a u8 mask of which of the
/// 8 words (mean, M₂, M₃, M₄ of the photons, then of the direct light) are not +0.0,
/// and those words' bits (LE).
fn pack_cells(cells: &[CellSums]) -> Vec<u8> {
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
struct Bytes(Vec<u8>);

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

/// Everything a checkpoint file holds (`'a`: the run's tallies, when it borrows them;
/// a checkpoint read from a file owns everything).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint<'a> {
    /// The scene file, for `merge` (which loads it again and checks the fingerprint).
    pub scene_path: String,
    pub scene_fingerprint: u64,
    pub numbers: Numbers,
    /// `--photons` of the run (a shard's total over all shards).
    pub photons_goal: Option<u64>,
    pub shard: Option<ShardRange>,
    /// The run stopped on a criterion (not interrupted).
    pub finished: bool,
    tallies: SavedTallies<'a>,
    direct_per_photon: f64,
    history: Vec<SavedPoint>,
    /// Seconds: photon pass, statistics, merging, direct light.
    times_s: [f64; 4],
    chunks: Vec<ChunkRecord>,
}

impl<'a> Checkpoint<'a> {
    /// The checkpoint of a run's state after an epoch, borrowing its triangle maps.
    pub fn of(state: &RunState<'a>, scene_fingerprint: u64) -> Checkpoint<'a> {
        let maps = Cow::Borrowed(&state.tallies.triangle_hits);
        let mut c = Checkpoint::unpacked(state, scene_fingerprint, maps);
        c.tallies.cells = Bytes(pack_cells(&state.tallies.cells));
        c
    }

    /// [`Checkpoint::of`] with the triangle maps `maps` and the cells still to pack.
    fn unpacked(
        state: &RunState<'_>,
        scene_fingerprint: u64,
        maps: Cow<'a, crate::tally::TriangleCounts>,
    ) -> Checkpoint<'a> {
        let tallies = SavedTallies::of(state.tallies, maps, Bytes(Vec::new()));
        Checkpoint {
            scene_path: state.scene.path.display().to_string(),
            scene_fingerprint,
            numbers: Numbers::of(state.options),
            photons_goal: state.options.stop.photons,
            shard: state.resumable.shard,
            finished: state
                .stop_reason
                .is_some_and(|r| r != StopReason::Interrupted),
            tallies,
            direct_per_photon: state.resumable.direct_per_photon,
            history: state.history.iter().map(SavedPoint::saved).collect(),
            times_s: [
                state.elapsed_s,
                state.stats_s,
                state.merge_s,
                state.direct_s,
            ],
            chunks: state.resumable.chunks.to_vec(),
        }
    }

    /// [`Checkpoint::of`] owning a copy of everything, with the cells still to pack: for
    /// another thread to pack and write while the run goes on.
    fn deferred(
        state: &RunState<'_>,
        scene_fingerprint: u64,
    ) -> (Checkpoint<'static>, Vec<CellSums>) {
        let maps = Cow::Owned(state.tallies.triangle_hits.clone());
        let c = Checkpoint::unpacked(state, scene_fingerprint, maps);
        (c, state.tallies.cells.clone())
    }

    /// Photons traced so far (a shard's own).
    pub fn photons(&self) -> u64 {
        self.tallies.photons
    }

    /// The state to go on from; `None` if the cells do not read back.
    pub fn resumed(&self) -> Option<Resumed> {
        Some(Resumed {
            tallies: self.tallies.tallies()?,
            history: self.history.iter().map(SavedPoint::point).collect(),
            direct_per_photon: self.direct_per_photon,
            elapsed_s: self.times_s[0],
            stats_s: self.times_s[1],
            merge_s: self.times_s[2],
            direct_s: self.times_s[3],
            chunks: self.chunks.clone(),
        })
    }

    /// Refuses a scene or options that would change the numbers; `what` names the file.
    pub fn check(&self, what: &Path, scene: &Scene, options: &RunOptions) -> Result<()> {
        let refuse = |m: String| Err(Error::input(what.display().to_string(), m));
        if self.scene_fingerprint != fingerprint(scene) {
            return refuse(format!(
                "the scene differs from the checkpoint's ({} or a file it loads changed)",
                scene.path.display()
            ));
        }
        if let Some(d) = self.numbers.difference(&Numbers::of(options)) {
            return refuse(d);
        }
        Ok(())
    }

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
    fn write_to(&self, out: &mut (impl Write + Seek)) -> std::io::Result<u64> {
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

    /// Writes `dir/checkpoint.bin` atomically: a temporary file in `dir`, synced, the
    /// old checkpoint renamed to checkpoint.prev, the new one renamed into place, the
    /// directory synced. Returns the bytes written.
    pub fn save(&self, dir: &Path) -> Result<u64> {
        let path = dir.join(FILE);
        let tmp = dir.join(format!("{FILE}.tmp"));
        let write = || -> std::io::Result<u64> {
            let mut f = std::fs::File::create(&tmp)?;
            let bytes = self.write_to(&mut f)?;
            f.sync_all()?;
            Ok(bytes)
        };
        let bytes = write().map_err(|e| {
            // A partial file would only take room (the disk may be full).
            let _ = std::fs::remove_file(&tmp);
            Error::io(&tmp, e)
        })?;
        if path.exists() {
            let prev = dir.join(PREVIOUS_FILE);
            std::fs::rename(&path, &prev).map_err(|e| Error::io(&prev, e))?;
        }
        std::fs::rename(&tmp, &path).map_err(|e| Error::io(&path, e))?;
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(bytes)
    }

    /// Reads `dir/checkpoint.bin` (or checkpoint.prev when a save was cut between its
    /// two renames).
    pub fn load(dir: &Path) -> Result<(Checkpoint<'static>, PathBuf)> {
        let mut path = dir.join(FILE);
        if !path.exists() && dir.join(PREVIOUS_FILE).exists() {
            path = dir.join(PREVIOUS_FILE);
        }
        let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
        Ok((
            Checkpoint::decode(&bytes, &path.display().to_string())?,
            path,
        ))
    }
}

/// 64-bit FNV-1a over everything of a loaded scene that changes the photons' numbers:
/// geometry bit for bit, materials, lights (photometry included) and receivers.
pub fn fingerprint(scene: &Scene) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let g = &scene.geometry;
    for v in [g.origin.x, g.origin.y, g.origin.z] {
        h.eat(&v.to_le_bytes());
    }
    for v in &g.vertices {
        for x in v.to_array() {
            h.eat(&x.to_le_bytes());
        }
    }
    for t in &g.triangles {
        for i in t {
            h.eat(&i.to_le_bytes());
        }
    }
    for m in g.material.iter().chain(g.object.iter()) {
        h.eat(&m.to_le_bytes());
    }
    // Debug prints every f64 so that it reads back to the same bits.
    h.eat(
        format!(
            "{:?}{:?}{:?}{:?}",
            scene.materials, scene.lights, scene.receivers, g.instanced
        )
        .as_bytes(),
    );
    h.0
}

struct Fnv(u64);

impl Fnv {
    fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Saves a running state's checkpoint every `period_s` and on the last epoch. For a
/// periodic save the run waits only for a copy of the state, packed and written on
/// another thread; the last save is written from the run's own tallies.
pub struct Checkpointer {
    pub dir: PathBuf,
    pub period_s: f64,
    pub fingerprint: u64,
    last: Instant,
    pending: Option<PendingSave>,
    /// The latest save on disk.
    pub last_cost: Option<SaveCost>,
    /// Seconds the run waited for saves, in all.
    pub total_s: f64,
    /// Saves done.
    pub saves: u64,
}

/// A save being packed and written on another thread (returns seconds and bytes).
struct PendingSave {
    writer: std::thread::JoinHandle<Result<(f64, u64)>>,
    /// Seconds the run waited for the state's copy.
    copy_s: f64,
}

/// What one save cost.
#[derive(Clone, Copy, Debug)]
pub struct SaveCost {
    /// Seconds the run waited for it: the copy, then joining its writer.
    pub waited_s: f64,
    /// Seconds its packing and writing took on the writer's thread.
    pub written_s: f64,
    pub bytes: u64,
}

impl Checkpointer {
    pub fn new(dir: &Path, period_s: f64, scene: &Scene) -> Checkpointer {
        Checkpointer {
            dir: dir.to_path_buf(),
            period_s,
            fingerprint: fingerprint(scene),
            last: Instant::now(),
            pending: None,
            last_cost: None,
            total_s: 0.0,
            saves: 0,
        }
    }

    /// Waits for the save under way, which becomes `last_cost`.
    fn finish_pending(&mut self) -> Result<()> {
        let Some(save) = self.pending.take() else {
            return Ok(());
        };
        let t = Instant::now();
        let (written_s, bytes) = save
            .writer
            .join()
            .map_err(|_| Error::Unsupported("the checkpoint writer panicked".into()))??;
        let joined_s = t.elapsed().as_secs_f64();
        self.total_s += joined_s;
        self.last_cost = Some(SaveCost {
            waited_s: save.copy_s + joined_s,
            written_s,
            bytes,
        });
        Ok(())
    }

    /// Saves if due (or on the last epoch, then waiting until it is on disk: written
    /// from the run's own tallies, without the copy a save on another thread needs).
    pub fn epoch(&mut self, state: &RunState<'_>) -> Result<()> {
        let last = state.stop_reason.is_some();
        if !last && self.last.elapsed().as_secs_f64() < self.period_s {
            return Ok(());
        }
        self.finish_pending()?;
        let t = Instant::now();
        if last {
            let bytes = Checkpoint::of(state, self.fingerprint).save(&self.dir)?;
            let seconds = t.elapsed().as_secs_f64();
            self.last_cost = Some(SaveCost {
                waited_s: seconds,
                written_s: seconds,
                bytes,
            });
            self.count_save(seconds);
            return Ok(());
        }
        let (mut c, cells) = Checkpoint::deferred(state, self.fingerprint);
        let dir = self.dir.clone();
        let handle = std::thread::spawn(move || {
            let t = Instant::now();
            c.tallies.cells = Bytes(pack_cells(&cells));
            drop(cells);
            let bytes = c.save(&dir)?;
            Ok((t.elapsed().as_secs_f64(), bytes))
        });
        let copy_s = t.elapsed().as_secs_f64();
        self.pending = Some(PendingSave {
            writer: handle,
            copy_s,
        });
        self.count_save(copy_s);
        Ok(())
    }

    /// Counts a save begun (or done) that the run waited `waited_s` for.
    fn count_save(&mut self, waited_s: f64) {
        self.total_s += waited_s;
        self.saves += 1;
        self.last = Instant::now();
    }
}

/// Merges complete shards (any order) into the run they split: every chunk folded in
/// global chunk order, then the direct light computed for the total photon count.
/// `options` must carry the shards' numbers (seed, estimator, backend).
pub fn merge(
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    mut shards: Vec<(PathBuf, Checkpoint)>,
) -> Result<RunResult> {
    check_shards(scene, options, &mut shards)?;
    let target = Target::chosen(options.stop.target.as_deref(), &scene.receivers)?;
    let engine = Engine::new(scene, options, caster)?;
    let mut tallies = engine.tracer.new_tallies();
    let mut schedule = DirectSchedule { per_photon: 0.0 };
    let mut direct_s = engine.add_direct(&mut tallies, PILOT_REPLICATES);
    let run_setup = engine.setup(setup);
    let start = Instant::now();
    let mut chunk = ChunkTally::default();
    let (mut elapsed_s, mut stats_s) = (0.0, 0.0);
    for (_, c) in &shards {
        direct_s += fold_shard(&engine, c, &mut chunk, &mut tallies, &mut schedule);
        elapsed_s += c.times_s[0];
        stats_s += c.times_s[1];
    }
    direct_s += engine.top_up_direct(&mut tallies, &mut schedule);
    let error = crate::run::target_error(
        scene,
        &target,
        &tallies,
        run_setup.total_flux_lm,
        options.stop.absolute,
    );
    let history = vec![HistoryPoint {
        elapsed_s,
        photons: tallies.photons,
        rel_error: error,
        forecast_s: None,
        forecast_photons: None,
    }];
    Ok(RunResult {
        setup: run_setup,
        tallies,
        history,
        forecast: None,
        target,
        stop_reason: StopReason::Photons,
        // The shards' photon passes added up (machine seconds), plus the merge.
        elapsed_s: elapsed_s + start.elapsed().as_secs_f64(),
        stats_s,
        merge_s: start.elapsed().as_secs_f64(),
        direct_s,
        direct_per_photon: schedule.per_photon,
        shard: None,
        chunks: Vec::new(),
    })
}

/// Folds shard `c` into `tallies`: its integer counters as totals (they add in any
/// order), its chunks one by one in chunk order, with the direct light topped up at
/// every schedule point on the way. Returns the direct light's seconds.
fn fold_shard(
    engine: &Engine<'_>,
    c: &Checkpoint,
    chunk: &mut ChunkTally,
    tallies: &mut Tallies,
    schedule: &mut DirectSchedule,
) -> f64 {
    let t = &c.tallies;
    tallies.killed_by_bounce_cap += t.killed_by_bounce_cap;
    for (a, b) in tallies.history_hits.iter_mut().zip(t.history_hits) {
        *a += b;
    }
    tallies.triangle_hits.add(&t.triangle_hits);
    let mut direct_s = 0.0;
    for record in &c.chunks {
        record.to_chunk(chunk);
        tallies.accumulate(chunk, record.photons as u64);
        if tallies.photons.is_power_of_two() && tallies.photons >= CHUNK_PHOTONS {
            direct_s += engine.top_up_direct(tallies, schedule);
        }
    }
    direct_s
}

/// Refuses shards that do not make one whole run of `scene` with `options`' numbers
/// (one line naming the shard at fault); sorts them by index.
fn check_shards(
    scene: &Scene,
    options: &RunOptions,
    shards: &mut [(PathBuf, Checkpoint)],
) -> Result<()> {
    let Some((first_path, first)) = shards.first() else {
        return Err(Error::input("merge", "no shard directories given"));
    };
    let origin = |p: &Path| p.display().to_string();
    let count = match first.shard {
        Some(s) => s.count,
        None => {
            return Err(Error::input(
                origin(first_path),
                "not a shard's checkpoint (run with --shard I/N)",
            ))
        }
    };
    let goal = first.photons_goal;
    let print = fingerprint(scene);
    for (path, c) in shards.iter() {
        let Some(s) = c.shard else {
            return Err(Error::input(origin(path), "not a shard's checkpoint"));
        };
        if s.count != count || c.photons_goal != goal {
            return Err(Error::input(
                origin(path),
                format!(
                    "shard {}/{} of {:?} photons does not belong with shard {}/{count} of {goal:?}",
                    s.index, s.count, c.photons_goal, 0
                ),
            ));
        }
        if c.scene_fingerprint != print {
            return Err(Error::input(
                origin(path),
                format!("was made from another scene than {}", scene.path.display()),
            ));
        }
        if let Some(d) = c.numbers.difference(&Numbers::of(options)) {
            return Err(Error::input(origin(path), d));
        }
        if c.photons() != s.end_photon - s.first_photon {
            return Err(Error::input(
                origin(path),
                format!(
                    "shard {}/{} is incomplete: {} of {} photons (resume it first)",
                    s.index,
                    s.count,
                    c.photons(),
                    s.end_photon - s.first_photon
                ),
            ));
        }
    }
    shards.sort_by_key(|(_, c)| c.shard.map(|s| s.index));
    for (k, (path, c)) in shards.iter().enumerate() {
        let index = c.shard.map_or(0, |s| s.index);
        if index as usize != k {
            let missing = if (index as usize) < k {
                index
            } else {
                k as u32
            };
            return Err(Error::input(
                origin(path),
                format!(
                    "shard {missing}/{count} is {}",
                    if (index as usize) < k {
                        "given twice"
                    } else {
                        "missing"
                    }
                ),
            ));
        }
    }
    if shards.len() != count as usize {
        return Err(Error::input(
            "merge",
            format!("{} of {count} shards given", shards.len()),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Length and CRC-32 of the fixed checkpoint below, encoded by format 3.
    const GOLDEN_LEN: usize = 138;
    const GOLDEN_CRC: u32 = 3_647_330_284;

    #[test]
    fn a_damaged_checkpoint_is_refused_in_one_line() {
        let t = Tallies::new(2, 3, 1.0);
        let c = Checkpoint {
            scene_path: "s.toml".into(),
            scene_fingerprint: 7,
            numbers: Numbers {
                seed: 1,
                estimator: None,
                backend: "embree".into(),
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
            history: vec![],
            times_s: [1.0; 4],
            chunks: vec![],
        };
        let bytes = c.encode().unwrap();
        assert_eq!(Checkpoint::decode(&bytes, "c").unwrap(), c);
        // Format 3's encoding of this checkpoint: a change here needs FORMAT_VERSION bumped.
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
