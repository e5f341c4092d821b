//! Huge pages for a large BVH without paying for fresh ones during its build.
//!
//! Embree asks the kernel for transparent huge pages (`madvise(MADV_HUGEPAGE)`) for all it
//! allocates: its BVH and its temporary build arrays (98 B per triangle at the build's
//! peak, 66 of them the BVH). In 4 KiB pages, rays through a BVH of 10⁷ triangles lose
//! about a quarter of their rate (TLB misses), but a fresh huge page is slow to fault in
//! where freed memory goes back to a hypervisor (free page reporting: measured 0.7 GB/s
//! on this project's VM, 1–3 s of a 10⁷-triangle build). So a large build runs with huge
//! pages off for the process (`PR_SET_THP_DISABLE`: recycled 4 KiB pages, for the
//! temporary arrays too), and afterwards a background thread collapses what is left of
//! the memory Embree asked huge pages for — the BVH — into huge pages (`MADV_COLLAPSE`,
//! Linux ≥ 6.1) while the first photons trace. Rays are right either way: collapsing
//! moves pages, never their contents. Where the process already had huge pages off, or
//! the kernel cannot collapse (checked once, on a scratch page), nothing changes. The
//! obvhs backend allocates its BVH without asking for huge pages: [`advise`] asks for
//! them after its build and collapses them the same way (10⁷ triangles: its rays
//! 0.29 → 0.36 Mrays/s on one thread).
//!
//! The module's `unsafe` (two `prctl`s, `madvise`, `mmap`) is the one exception to
//! "`unsafe` only in the Embree wrapper": it is about the BVHs' memory, not Embree's API.

use std::sync::{Mutex, OnceLock};
use std::thread::JoinHandle;
use std::time::Instant;

/// Builds of at least this many triangles defer their huge pages (a BVH of ≈ 16 MiB and
/// more; 10⁶ triangles set up in 0.29–0.33 s deferred against 0.28–0.53 s not);
/// smaller ones fault them in at once, which costs little.
pub const DEFER_FROM_TRIANGLES: usize = 1 << 18;

pub use sys::{huge_pages_enabled, set_huge_pages};

/// What the background collapse did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Collapse {
    /// Regions of the process that had asked for huge pages.
    pub regions: usize,
    /// The process's anonymous memory in huge pages once done (`AnonHugePages`), bytes.
    pub huge_bytes: u64,
    /// Wall seconds the collapse took.
    pub seconds: f64,
}

/// The guards alive, and whether the first of them turned huge pages off (they stay off
/// until the last one ends).
struct Deferring {
    builds: usize,
    turned_off: bool,
}

static DEFERRING: Mutex<Deferring> = Mutex::new(Deferring {
    builds: 0,
    turned_off: false,
});

/// The collapse still running, if any.
static PENDING: Mutex<Option<JoinHandle<Collapse>>> = Mutex::new(None);

/// Huge pages off for the process while this lives (nested and concurrent guards share
/// one switch); on drop of the last guard they are back on and the BVH's pages are being
/// collapsed in the background ([`wait_for_collapse`]).
pub struct Deferred(());

impl Deferred {
    /// Turns huge pages off unless the process had them off already or the kernel could
    /// not collapse them back.
    pub fn new() -> Deferred {
        let mut state = DEFERRING.lock().unwrap_or_else(|e| e.into_inner());
        if state.builds == 0 {
            state.turned_off =
                sys::huge_pages_enabled() && can_collapse() && sys::set_huge_pages(false);
        }
        state.builds += 1;
        Deferred(())
    }
}

impl Default for Deferred {
    fn default() -> Self {
        Self::new()
    }
}

impl Drop for Deferred {
    fn drop(&mut self) {
        let mut state = DEFERRING.lock().unwrap_or_else(|e| e.into_inner());
        state.builds -= 1;
        if state.builds == 0 && std::mem::take(&mut state.turned_off) && sys::set_huge_pages(true) {
            collapse_in_background();
        }
    }
}

/// Asks huge pages for the whole 2 MiB pages inside each of `ranges` (start, bytes):
/// memory a backend built in 4 KiB pages (no `MADV_HUGEPAGE` of its own, as the obvhs
/// BVH) and reads on every ray. They are collapsed in the background
/// ([`wait_for_collapse`]) where the process has huge pages on and the kernel can
/// collapse; elsewhere nothing changes.
pub fn advise(ranges: &[(usize, usize)]) {
    use sys::HUGE_PAGE as HUGE;
    if !(sys::huge_pages_enabled() && can_collapse()) {
        return;
    }
    let mut advised = false;
    for &(start, bytes) in ranges {
        let (lo, hi) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
        advised |= hi > lo && sys::advise_huge_pages(lo, hi - lo);
    }
    if advised {
        collapse_in_background();
    }
}

/// Collapses every region that asked for huge pages, on a thread of its own.
fn collapse_in_background() {
    let previous = PENDING
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .replace(std::thread::spawn(collapse_now));
    // A collapse still running covers older regions only: let it finish alone.
    drop(previous);
}

/// Waits for the background collapse, if one is running or finished unseen: what it did.
pub fn wait_for_collapse() -> Option<Collapse> {
    let handle = PENDING.lock().unwrap_or_else(|e| e.into_inner()).take()?;
    handle.join().ok()
}

/// Whether this kernel collapses memory into huge pages on request (tried once).
pub fn can_collapse() -> bool {
    static CAN: OnceLock<bool> = OnceLock::new();
    *CAN.get_or_init(sys::collapse_works)
}

/// Collapses every region of the process that asked for huge pages.
fn collapse_now() -> Collapse {
    let start = Instant::now();
    let regions = std::fs::read_to_string("/proc/self/smaps")
        .map(|text| huge_page_regions(&text))
        .unwrap_or_default();
    // In steps cut at multiples of 32 MiB (so no huge page straddles two), so that one
    // step the kernel cannot collapse (no free huge page at the moment, a page busy)
    // costs only its own part; each step is tried twice.
    const STEP: usize = 32 << 20;
    let next_cut = |s: usize| (s / STEP + 1) * STEP;
    for (lo, hi) in &regions {
        let steps = std::iter::successors(Some(*lo), |&s| Some(next_cut(s)).filter(|n| n < hi));
        for s in steps {
            let bytes = next_cut(s).min(*hi) - s;
            let _ = sys::collapse(s, bytes) || sys::collapse(s, bytes);
        }
    }
    Collapse {
        regions: regions.len(),
        huge_bytes: anon_huge_bytes(),
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// The process's anonymous memory in huge pages (`AnonHugePages` of
/// `/proc/self/smaps_rollup`), bytes; 0 where unknown.
pub fn anon_huge_bytes() -> u64 {
    let text = std::fs::read_to_string("/proc/self/smaps_rollup").unwrap_or_default();
    text.lines()
        .find_map(|l| l.strip_prefix("AnonHugePages:"))
        .and_then(|v| v.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(0, |kib| kib * 1024)
}

/// The address ranges (start, end) of `/proc/self/smaps` whose flags include `hg`
/// (`MADV_HUGEPAGE` asked for).
pub fn huge_page_regions(smaps: &str) -> Vec<(usize, usize)> {
    let mut regions = Vec::new();
    let mut current = None;
    for line in smaps.lines() {
        if let Some(flags) = line.strip_prefix("VmFlags:") {
            if let Some(range) = current.take() {
                if flags.split_whitespace().any(|f| f == "hg") {
                    regions.push(range);
                }
            }
        } else if let Some((range, _)) = line.split_once(' ') {
            // A region's header: `start-end perms offset dev inode [path]`.
            if let Some((lo, hi)) = range.split_once('-') {
                if let (Ok(lo), Ok(hi)) =
                    (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
                {
                    current = Some((lo, hi));
                }
            }
        }
    }
    regions
}

#[cfg(target_os = "linux")]
mod sys {
    const NONE: libc::c_ulong = 0;
    /// A transparent huge page (x86-64's PMD size).
    pub const HUGE_PAGE: usize = 2 << 20;

    /// Whether the process may use transparent huge pages (not `PR_SET_THP_DISABLE`d).
    pub fn huge_pages_enabled() -> bool {
        // SAFETY: PR_GET_THP_DISABLE reads a flag of the calling process.
        unsafe { libc::prctl(libc::PR_GET_THP_DISABLE, NONE, NONE, NONE, NONE) == 0 }
    }

    /// Turns the process's transparent huge pages on or off (the whole process, and the
    /// children it starts): whether that took. A [`super::Deferred`] alive meanwhile
    /// sets them back as it found them when it ends.
    pub fn set_huge_pages(on: bool) -> bool {
        let off = libc::c_ulong::from(!on);
        // SAFETY: PR_SET_THP_DISABLE sets a flag of the calling process.
        unsafe { libc::prctl(libc::PR_SET_THP_DISABLE, off, NONE, NONE, NONE) == 0 }
    }

    /// Marks `bytes` from `start` (whole huge pages) as wanting huge pages.
    pub fn advise_huge_pages(start: usize, bytes: usize) -> bool {
        // SAFETY: MADV_HUGEPAGE is advice on the pages behind memory, never its contents;
        // a range not mapped fails the call.
        unsafe { libc::madvise(start as *mut libc::c_void, bytes, libc::MADV_HUGEPAGE) == 0 }
    }

    /// Asks the kernel to back `bytes` from `start` with huge pages now.
    pub fn collapse(start: usize, bytes: usize) -> bool {
        // SAFETY: MADV_COLLAPSE never changes the contents of memory, only the pages
        // behind it; a range unmapped meanwhile fails the call, one mapped anew is
        // collapsed with its contents kept.
        unsafe { libc::madvise(start as *mut libc::c_void, bytes, libc::MADV_COLLAPSE) == 0 }
    }

    /// Collapses one touched page of a scratch mapping: whether the kernel can.
    pub fn collapse_works() -> bool {
        let len = 2 * HUGE_PAGE;
        // SAFETY: a private anonymous mapping of our own, written and unmapped here only.
        unsafe {
            let map = libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            );
            if map == libc::MAP_FAILED {
                return false;
            }
            let aligned = (map as usize).next_multiple_of(HUGE_PAGE);
            (aligned as *mut u8).write(1);
            let works = collapse(aligned, HUGE_PAGE);
            libc::munmap(map, len);
            works
        }
    }
}

#[cfg(not(target_os = "linux"))]
mod sys {
    pub const HUGE_PAGE: usize = 2 << 20;
    pub fn huge_pages_enabled() -> bool {
        false
    }
    pub fn set_huge_pages(_on: bool) -> bool {
        false
    }
    pub fn collapse(_start: usize, _bytes: usize) -> bool {
        false
    }
    pub fn advise_huge_pages(_start: usize, _bytes: usize) -> bool {
        false
    }
    pub fn collapse_works() -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_that_asked_for_huge_pages_are_found_in_smaps() {
        let smaps = "\
7f0000000000-7f0000400000 rw-p 00000000 00:00 0 
Size:               4096 kB
VmFlags: rd wr mr mw me ac sd hg 
7f0000400000-7f0000600000 rw-p 00000000 00:00 0 
Size:               2048 kB
VmFlags: rd wr mr mw me ac sd 
55d000000000-55d000001000 r--p 00000000 08:01 1234                       /usr/bin/x y
Size:                  4 kB
VmFlags: rd mr mw me dw sd hg
";
        assert_eq!(
            huge_page_regions(smaps),
            vec![
                (0x7f00_0000_0000, 0x7f00_0040_0000),
                (0x55d0_0000_0000, 0x55d0_0000_1000)
            ]
        );
    }
}
