//! Huge pages for a large BVH without paying for fresh ones during its build.
//!
//! Embree asks the kernel for transparent huge pages (`madvise(MADV_HUGEPAGE)`) for all it
//! allocates: its BVH and its temporary build arrays (98 B per triangle at the build's
//! peak, 66 of them the BVH). Rays through a BVH of 10⁷ triangles in 2 MiB pages run
//! ≈ 25 % faster than in 4 KiB pages (fewer TLB misses), but a fresh huge page is slow to
//! fault in where freed memory goes back to a hypervisor (free page reporting: measured
//! 0.7 GB/s on this project's VM, 1–3 s of a 10⁷-triangle build). So a large build runs
//! with huge pages off for the process (`PR_SET_THP_DISABLE`: recycled 4 KiB pages, for
//! the temporary arrays too), and afterwards a background thread collapses what is left
//! of the memory Embree asked huge pages for — the BVH — into huge pages
//! (`MADV_COLLAPSE`, Linux ≥ 6.1) while the first photons trace. Rays are right either
//! way: collapsing moves pages, never their contents. Where the process already had huge
//! pages off, or the kernel cannot collapse, nothing changes.

use std::sync::Mutex;
use std::thread::JoinHandle;
use std::time::Instant;

/// Builds of at least this many triangles defer their huge pages (a BVH of ≈ 64 MiB and
/// more); smaller ones fault them in at once, which costs little.
pub const DEFER_FROM_TRIANGLES: usize = 1 << 20;

pub use sys::{huge_pages_enabled, set_huge_pages};

/// What the background collapse did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Collapse {
    /// Regions that asked for huge pages, and the bytes in those the kernel collapsed.
    pub regions: usize,
    pub bytes_collapsed: u64,
    /// Wall seconds the collapse took.
    pub seconds: f64,
}

/// Builds in progress with huge pages off, and whether the first of them turned them off
/// (it stays off until the last one ends).
static DEFERRING: Mutex<(usize, bool)> = Mutex::new((0, false));

/// The collapse still running, if any.
static PENDING: Mutex<Option<JoinHandle<Collapse>>> = Mutex::new(None);

/// Huge pages off for the process while this lives (nested and concurrent guards share
/// one switch); on drop of the last guard they are back on and the BVH's pages are being
/// collapsed in the background ([`wait_for_collapse`]).
pub struct Deferred(());

impl Deferred {
    /// Turns huge pages off unless the process had them off already.
    pub fn new() -> Deferred {
        let mut state = DEFERRING.lock().unwrap_or_else(|e| e.into_inner());
        if state.0 == 0 {
            state.1 = sys::huge_pages_enabled() && sys::set_huge_pages(false);
        }
        state.0 += 1;
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
        state.0 -= 1;
        if state.0 == 0 && std::mem::take(&mut state.1) && sys::set_huge_pages(true) {
            let previous = PENDING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .replace(std::thread::spawn(collapse_now));
            // A collapse still running covers older regions only: let it finish alone.
            drop(previous);
        }
    }
}

/// Waits for the background collapse, if one is running or finished unseen: what it did.
pub fn wait_for_collapse() -> Option<Collapse> {
    let handle = PENDING.lock().unwrap_or_else(|e| e.into_inner()).take()?;
    handle.join().ok()
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
    let bytes_collapsed = regions
        .iter()
        .flat_map(|&(lo, hi)| {
            std::iter::successors(Some(lo), move |&s| Some(next_cut(s)).filter(|&n| n < hi))
                .map(move |s| (s, next_cut(s).min(hi) - s))
        })
        .filter(|&(start, bytes)| sys::collapse(start, bytes) || sys::collapse(start, bytes))
        .map(|(_, bytes)| bytes as u64)
        .sum();
    Collapse {
        regions: regions.len(),
        bytes_collapsed,
        seconds: start.elapsed().as_secs_f64(),
    }
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
    /// Whether the process may use transparent huge pages (not `PR_SET_THP_DISABLE`d).
    pub fn huge_pages_enabled() -> bool {
        // SAFETY: PR_GET_THP_DISABLE reads a flag of the calling process.
        unsafe {
            libc::prctl(
                libc::PR_GET_THP_DISABLE,
                0 as libc::c_ulong,
                0 as libc::c_ulong,
                0 as libc::c_ulong,
                0 as libc::c_ulong,
            ) == 0
        }
    }

    /// Turns the process's transparent huge pages on or off (for the whole process, and
    /// inherited by its children): whether that took.
    pub fn set_huge_pages(on: bool) -> bool {
        // SAFETY: PR_SET_THP_DISABLE sets a flag of the calling process.
        unsafe {
            libc::prctl(
                libc::PR_SET_THP_DISABLE,
                libc::c_ulong::from(!on),
                0 as libc::c_ulong,
                0 as libc::c_ulong,
                0 as libc::c_ulong,
            ) == 0
        }
    }

    /// Asks the kernel to back `bytes` from `start` with huge pages now.
    pub fn collapse(start: usize, bytes: usize) -> bool {
        // SAFETY: MADV_COLLAPSE neither changes the contents of the range nor frees it;
        // a range unmapped meanwhile only makes the call fail.
        unsafe { libc::madvise(start as *mut libc::c_void, bytes, libc::MADV_COLLAPSE) == 0 }
    }
}

#[cfg(not(target_os = "linux"))]
mod sys {
    pub fn huge_pages_enabled() -> bool {
        false
    }
    pub fn set_huge_pages(_on: bool) -> bool {
        false
    }
    pub fn collapse(_start: usize, _bytes: usize) -> bool {
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
